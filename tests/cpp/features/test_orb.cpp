#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "features/orb.hpp"
#include "features/orb_quadtree.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam::features;

namespace {

// KITTI-sized texture whose contrast fades from full (left) to 8 % (right): plain cv::ORB puts
// its keypoints where the contrast is, the bucketed extractor everywhere.
cv::Mat contrast_ramp_image() {
  cv::Mat t = test::random_texture(1242, 375, 7);
  for (int y = 0; y < t.rows; ++y) {
    float* row = t.ptr<float>(y);
    for (int x = 0; x < t.cols; ++x) {
      const float gain = 1.0f - 0.92f * static_cast<float>(x) / (t.cols - 1);
      row[x] = 128.0f + gain * (row[x] - 128.0f);
    }
  }
  return test::to_u8(t);
}

// Fraction of the 35-px cells of the keypoint area (19 px inside each border) holding a keypoint.
double cell_coverage(const std::vector<cv::KeyPoint>& kps, cv::Size size, int cell = 35) {
  const int x0 = kEdgeBorder, y0 = kEdgeBorder;
  const int cols = (size.width - 2 * x0) / cell, rows = (size.height - 2 * y0) / cell;
  std::vector<int> hits(cols * rows, 0);
  for (const auto& k : kps) {
    const int cx = static_cast<int>((k.pt.x - x0) / cell), cy = static_cast<int>((k.pt.y - y0) / cell);
    if (k.pt.x >= x0 && k.pt.y >= y0 && cx < cols && cy < rows) hits[cy * cols + cx] = 1;
  }
  return static_cast<double>(std::count(hits.begin(), hits.end(), 1)) / hits.size();
}

}  // namespace

TEST(OrbExtractor, BucketingCoversTheImageWherePlainOrbClusters) {
  const cv::Mat img = contrast_ramp_image();
  OrbOptions opt;
  const OrbExtractor orb(opt);
  const Keypoints k = orb.extract(img);

  const double ours = cell_coverage(k.keypoints, img.size());
  std::vector<cv::KeyPoint> plain;
  cv::ORB::create(opt.num_features)->detect(img, plain);
  const double theirs = cell_coverage(plain, img.size());
  RecordProperty("coverage_ours", std::to_string(ours));
  RecordProperty("coverage_cv_orb", std::to_string(theirs));
  EXPECT_GE(ours, 0.9);
  EXPECT_LT(theirs, ours - 0.25) << "plain ORB should cluster on the high-contrast side";

  // The right (low-contrast) half still gets a fair share.
  const auto right_half = std::count_if(k.keypoints.begin(), k.keypoints.end(),
                                        [&](const cv::KeyPoint& p) { return p.pt.x > 621; });
  EXPECT_GT(right_half, 0.3 * k.size());
}

TEST(OrbExtractor, CountCloseToTargetAndOctavesSpread) {
  const cv::Mat img = test::to_u8(test::random_texture(1242, 375, 3));
  OrbOptions eight_levels;  // ORB-SLAM2's pyramid: the per-level budget is what is checked
  eight_levels.num_levels = 8;
  const OrbExtractor orb(eight_levels);
  const Keypoints k = orb.extract(img);
  EXPECT_LE(k.size(), 2000u);
  EXPECT_GE(k.size(), 1900u);
  ASSERT_EQ(k.descriptors.rows, static_cast<int>(k.size()));
  EXPECT_EQ(k.descriptors.cols, 32);
  EXPECT_EQ(k.descriptors.type(), CV_8U);

  std::vector<int> per_level(8, 0);
  for (const auto& p : k.keypoints) {
    ASSERT_GE(p.octave, 0);
    ASSERT_LT(p.octave, 8);
    ++per_level[p.octave];
    EXPECT_GE(p.angle, 0.0f);
    EXPECT_LT(p.angle, 360.0f);
    EXPECT_GT(p.response, 0.0f);
    EXPECT_NEAR(p.size, 31.0f * orb.scale_factors()[p.octave], 1e-3);
  }
  const auto& wanted = orb.features_per_level();
  int sum = 0;
  for (int l = 0; l < 8; ++l) {
    sum += wanted[l];
    EXPECT_GE(per_level[l], 0.8 * wanted[l]) << "level " << l;
  }
  EXPECT_EQ(sum, 2000);
  EXPECT_GT(wanted[0], wanted[7] * 3);  // geometric in 1/1.2
}

TEST(OrbExtractor, KeypointsStayInsideTheLevelBorders) {
  const cv::Mat img = test::to_u8(test::random_texture(640, 240, 5));
  const Keypoints k = OrbExtractor(OrbOptions{}).extract(img);
  ASSERT_GT(k.size(), 500u);
  for (const auto& p : k.keypoints) {
    const float s = std::pow(1.2f, static_cast<float>(p.octave));
    EXPECT_GE(p.pt.x, kEdgeBorder * s - s);
    EXPECT_LE(p.pt.x, img.cols - kEdgeBorder * s + s);
    EXPECT_GE(p.pt.y, kEdgeBorder * s - s);
    EXPECT_LE(p.pt.y, img.rows - kEdgeBorder * s + s);
  }
}

TEST(OrbExtractor, NoKeypointWhereMaskIsZero) {
  const cv::Mat img = test::to_u8(test::random_texture(1242, 375, 9));
  cv::Mat mask(img.size(), CV_8U, cv::Scalar(255));
  cv::rectangle(mask, cv::Rect(300, 80, 400, 200), cv::Scalar(0), cv::FILLED);
  cv::circle(mask, cv::Point(1000, 150), 70, cv::Scalar(0), cv::FILLED);
  for (int x = 0; x < img.cols; x += 97) mask.col(x).setTo(0);  // thin 1-px stripes too
  const Keypoints k = OrbExtractor(OrbOptions{}).extract(img, mask);
  ASSERT_GT(k.size(), 1800u) << "the budget goes to the unmasked part";
  int near_mask = 0;
  for (const auto& p : k.keypoints) {
    const int u = cvRound(p.pt.x), v = cvRound(p.pt.y);
    ASSERT_NE(mask.at<std::uint8_t>(v, u), 0) << "keypoint at " << p.pt << " octave " << p.octave;
    if (u > 280 && u < 720 && v > 60 && v < 300) ++near_mask;
  }
  EXPECT_GT(near_mask, 20);  // keypoints right up to the masked rectangle
}

// FAST runs only around the mask's bounding box (orb.cpp, LevelArea::search): a mask whose box
// spans the whole image (one extra pixel on a flat patch far away) must give the very same
// keypoints and descriptors as the tight mask, corners at the mask's edge (whose non-maximum
// suppression reads pixels outside it) included.
TEST(OrbExtractor, AMasksBoundingBoxLimitsTheSearchNotTheResult) {
  cv::Mat img = test::to_u8(test::random_texture(1242, 375, 11));
  img(cv::Rect(1080, 280, 80, 60)).setTo(128);  // flat: no corner there
  cv::Mat tight(img.size(), CV_8U, cv::Scalar(0));
  cv::rectangle(tight, cv::Rect(430, 120, 180, 110), cv::Scalar(255), cv::FILLED);
  cv::circle(tight, cv::Point(700, 200), 40, cv::Scalar(255), cv::FILLED);
  cv::Mat wide = tight.clone();
  wide.at<std::uint8_t>(310, 1120) = 255;
  OrbOptions o;
  o.num_features = 600;
  o.fast_threshold = 7;
  o.cell_size = 10;
  o.num_levels = 3;
  const OrbExtractor extractor(o);
  const Keypoints a = extractor.extract(img, tight), b = extractor.extract(img, wide);
  ASSERT_GT(a.size(), 300u);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].pt, b.keypoints[i].pt) << i;
    EXPECT_EQ(a.keypoints[i].octave, b.keypoints[i].octave) << i;
    EXPECT_EQ(a.keypoints[i].response, b.keypoints[i].response) << i;
  }
  EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0.0);
  // an all-zero mask finds nothing (an empty box), without an error
  EXPECT_TRUE(extractor.extract(img, cv::Mat::zeros(img.size(), CV_8U)).keypoints.empty());
}

// The descriptors are computed on a crop of each level around its keypoints (orb.cpp,
// describe): they must equal OpenCV's rotated BRIEF on the whole level, also for keypoints a
// few pixels from the crop's edges and for a mask touching the image's border.
TEST(OrbExtractor, DescriptorsOfAMaskedAreaEqualThoseOfTheWholeImage) {
  const cv::Mat img = test::to_u8(test::random_texture(1242, 375, 13));
  cv::Mat mask(img.size(), CV_8U, cv::Scalar(0));
  cv::rectangle(mask, cv::Rect(500, 140, 90, 70), cv::Scalar(255), cv::FILLED);  // inside
  cv::rectangle(mask, cv::Rect(0, 250, 120, 125), cv::Scalar(255), cv::FILLED);  // a corner
  OrbOptions o;
  o.num_features = 400;
  o.fast_threshold = 7;
  o.cell_size = 10;
  o.num_levels = 1;  // level 0 only: the keypoints' coordinates are the level's
  const Keypoints k = OrbExtractor(o).extract(img, mask);
  ASSERT_GT(k.size(), 150u);
  std::vector<cv::KeyPoint> whole = k.keypoints;
  cv::Mat reference;
  cv::ORB::create(o.num_features, o.scale_factor, 1, kEdgeBorder, 0, 2, cv::ORB::FAST_SCORE,
                  kPatchSize, o.fast_threshold)
      ->compute(img, whole, reference);
  ASSERT_EQ(whole.size(), k.size());
  for (std::size_t i = 0; i < k.size(); ++i)
    ASSERT_EQ(descriptor_distance(k.descriptors.row(static_cast<int>(i)), reference.row(static_cast<int>(i))), 0)
        << "keypoint " << i << " at " << k.keypoints[i].pt;
}

// An extractor on another one's pyramid of the same image (what the object keypoints do on
// the main pass's) finds what it finds on the image; a pyramid of another scale is refused.
TEST(OrbExtractor, ExtractOnAKeptPyramidEqualsExtract) {
  const cv::Mat img = test::to_u8(test::random_texture(1242, 375, 17));
  cv::Mat mask(img.size(), CV_8U, cv::Scalar(0));
  cv::circle(mask, cv::Point(800, 190), 90, cv::Scalar(255), cv::FILLED);
  const Keypoints main = OrbExtractor(OrbOptions{}).extract(img);
  ASSERT_EQ(main.pyramid.size(), 4u);
  OrbOptions o;
  o.num_features = 300;
  o.num_levels = 2;
  const OrbExtractor objects(o);
  const Keypoints a = objects.extract(img, mask), b = objects.extract_on_pyramid(main.pyramid, mask);
  ASSERT_GT(a.size(), 100u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.keypoints[i].pt, b.keypoints[i].pt) << i;
    ASSERT_EQ(a.keypoints[i].octave, b.keypoints[i].octave) << i;
  }
  EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0.0);
  EXPECT_EQ(b.pyramid.size(), 2u);
  EXPECT_EQ(b.pyramid[1].data, main.pyramid[1].data) << "the levels are shared, not rebuilt";

  OrbOptions other = o;
  other.scale_factor = 1.5f;
  try {
    OrbExtractor(other).extract_on_pyramid(main.pyramid, mask);
    FAIL() << "a pyramid of scale 1.2 taken for 1.5";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("level 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(objects.extract_on_pyramid({}, mask), std::invalid_argument);
}

TEST(OrbExtractor, OrientationAndDescriptorFollowARotation) {
  // A 90-degree rotation is an exact pixel permutation: each keypoint must reappear at the
  // rotated position with its angle turned by 90 degrees and a nearly equal descriptor.
  const cv::Mat img = test::to_u8(test::random_texture(480, 480, 21));
  cv::Mat rot;
  cv::rotate(img, rot, cv::ROTATE_90_CLOCKWISE);  // (x, y) -> (H - 1 - y, x)
  OrbOptions opt;
  opt.num_features = 1000;
  opt.num_levels = 3;
  const OrbExtractor orb(opt);
  const Keypoints a = orb.extract(img), b = orb.extract(rot);
  int paired = 0, good_angle = 0, good_desc = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a.keypoints[i].octave != 0) continue;
    const cv::Point2f want(img.rows - 1 - a.keypoints[i].pt.y, a.keypoints[i].pt.x);
    for (std::size_t j = 0; j < b.size(); ++j) {
      if (b.keypoints[j].octave != 0 || cv::norm(b.keypoints[j].pt - want) > 0.5) continue;
      ++paired;
      float diff = b.keypoints[j].angle - a.keypoints[i].angle - 90.0f;
      diff = std::fmod(std::fmod(diff, 360.0f) + 540.0f, 360.0f) - 180.0f;
      if (std::abs(diff) < 2.0f) ++good_angle;
      if (descriptor_distance(a.descriptors.row(i), b.descriptors.row(j)) < 25) ++good_desc;
      break;
    }
  }
  ASSERT_GT(paired, 100);
  EXPECT_GT(good_angle, 0.95 * paired);
  EXPECT_GT(good_desc, 0.8 * paired);
}

TEST(OrbExtractor, DeterministicAndThreadSafeAcrossCalls) {
  const cv::Mat img = test::to_u8(test::random_texture(640, 300, 4));
  const OrbExtractor orb(OrbOptions{});
  const Keypoints a = orb.extract(img), b = orb.extract(img.clone());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a.keypoints[i].pt, b.keypoints[i].pt);
  EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_L1), 0.0);
}

TEST(OrbExtractor, BlankTinyAndInvalidImages) {
  const OrbExtractor orb(OrbOptions{});
  const Keypoints blank = orb.extract(cv::Mat(375, 1242, CV_8U, cv::Scalar(90)));
  EXPECT_EQ(blank.size(), 0u);
  EXPECT_EQ(blank.descriptors.rows, 0);
  EXPECT_EQ(orb.extract(cv::Mat(20, 30, CV_8U, cv::Scalar(5))).size(), 0u);
  EXPECT_THROW(orb.extract(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(orb.extract(cv::Mat(50, 50, CV_32F)), std::invalid_argument);
  EXPECT_THROW(orb.extract(cv::Mat(50, 50, CV_8U), cv::Mat(40, 50, CV_8U)), std::invalid_argument);

  OrbOptions bad;
  bad.scale_factor = 1.0f;
  EXPECT_THROW(OrbExtractor{bad}, std::invalid_argument);
  bad = {};
  bad.min_fast_threshold = 30;
  EXPECT_THROW(OrbExtractor{bad}, std::invalid_argument);
}

TEST(OrbExtractor, ScaleTables) {
  OrbOptions eight_levels;
  eight_levels.num_levels = 8;
  const OrbExtractor orb(eight_levels);
  ASSERT_EQ(orb.scale_factors().size(), 8u);
  EXPECT_FLOAT_EQ(orb.scale_factors()[0], 1.0f);
  EXPECT_NEAR(orb.scale_factors()[3], 1.728f, 1e-5);
  EXPECT_NEAR(orb.level_sigma2()[3], 1.728f * 1.728f, 1e-4);
  EXPECT_NEAR(orb.inv_level_sigma2()[3] * orb.level_sigma2()[3], 1.0f, 1e-6);
}

TEST(Features, ToGray) {
  cv::Mat bgr(4, 5, CV_8UC3, cv::Scalar(10, 20, 200));  // B, G, R
  const cv::Mat g = to_gray(bgr);
  ASSERT_EQ(g.type(), CV_8UC1);
  EXPECT_NEAR(g.at<std::uint8_t>(0, 0), 0.114 * 10 + 0.587 * 20 + 0.299 * 200, 1.0);
  EXPECT_NEAR(to_gray(bgr, true).at<std::uint8_t>(0, 0), 0.299 * 10 + 0.587 * 20 + 0.114 * 200, 1.0);
  const cv::Mat gray(4, 5, CV_8UC1, cv::Scalar(7));
  EXPECT_EQ(to_gray(gray).data, gray.data);  // shared, no copy
  EXPECT_THROW(to_gray(cv::Mat(4, 5, CV_32FC3)), std::invalid_argument);
  EXPECT_THROW(to_gray(cv::Mat()), std::invalid_argument);
}

TEST(Features, DescriptorDistanceIsABitCount) {
  cv::RNG rng(5);
  cv::Mat d(200, 32, CV_8U);
  rng.fill(d, cv::RNG::UNIFORM, 0, 256);
  for (int i = 0; i + 1 < d.rows; ++i) {
    int bits = 0;
    for (int k = 0; k < 32; ++k) {
      const int x = d.at<std::uint8_t>(i, k) ^ d.at<std::uint8_t>(i + 1, k);
      for (int b = 0; b < 8; ++b) bits += (x >> b) & 1;
    }
    ASSERT_EQ(descriptor_distance(d.row(i), d.row(i + 1)), bits);
    ASSERT_EQ(descriptor_distance(d.row(i), d.row(i)), 0);
  }
  cv::Mat zeros = cv::Mat::zeros(1, 32, CV_8U), ones(1, 32, CV_8U, cv::Scalar(255));
  EXPECT_EQ(descriptor_distance(zeros, ones), 256);
  EXPECT_THROW(descriptor_distance(zeros, cv::Mat::zeros(1, 16, CV_8U)), std::invalid_argument);
}

TEST(Features, Popcount64CountsEveryBitOfTheWord) {
  EXPECT_EQ(popcount64(0), 0);
  EXPECT_EQ(popcount64(~std::uint64_t{0}), 64);
  for (int b = 0; b < 64; ++b) {
    ASSERT_EQ(popcount64(std::uint64_t{1} << b), 1);
    ASSERT_EQ(popcount64(~(std::uint64_t{1} << b)), 63);
  }
  std::uint64_t x = 0x9E3779B97F4A7C15ULL;  // a scrambled sequence against the builtin
  for (int i = 0; i < 1000; ++i) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    ASSERT_EQ(popcount64(x), __builtin_popcountll(x));
  }
}

TEST(OrbExtractor, InvalidOptionsNameTheOptionAndItsRange) {
  auto message = [](const OrbOptions& o) -> std::string {
    try {
      OrbExtractor{o};
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  OrbOptions o;
  o.num_levels = 0;
  EXPECT_EQ(message(o), "OrbOptions: num_levels = 0 is out of range [1, 32]");
  o = {};
  o.num_features = 200000;
  EXPECT_EQ(message(o), "OrbOptions: num_features = 200000 is out of range [0, 100000]");
  o = {};
  o.cell_size = 4;
  EXPECT_EQ(message(o), "OrbOptions: cell_size = 4 is out of range [8, 4096]");
  o = {};
  o.min_fast_threshold = 30;
  EXPECT_EQ(message(o), "OrbOptions: min_fast_threshold (30) must not exceed fast_threshold (20)");
  EXPECT_EQ(message(OrbOptions{}), "");
}

TEST(OrbQuadtree, KeepsTheStrongestCornerOfEachRegion) {
  // 4 tight clusters of corners in the four quadrants of a square; asked for 4 keypoints the
  // quadtree keeps one per cluster, the strongest of each.
  std::vector<cv::KeyPoint> cand;
  const cv::Point2f centres[] = {{10, 10}, {90, 10}, {10, 90}, {90, 90}};
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 5; ++k)
      cand.emplace_back(centres[c] + cv::Point2f(static_cast<float>(k), 0.5f * k), 7.0f, -1.0f,
                        static_cast<float>(10 * c + k));  // response: strongest is k = 4
  const auto keep = detail::distribute_keypoints(cand, cv::Rect2f(0, 0, 100, 100), 4);
  EXPECT_EQ(keep, (std::vector<int>{4, 9, 14, 19}));
  EXPECT_EQ(detail::distribute_keypoints(cand, cv::Rect2f(0, 0, 100, 100), 0).size(), 0u);
  EXPECT_EQ(detail::distribute_keypoints(cand, cv::Rect2f(0, 0, 100, 100), 100).size(), cand.size());
  const auto two = detail::distribute_keypoints(cand, cv::Rect2f(0, 0, 100, 100), 2);
  EXPECT_EQ(two.size(), 2u);  // the overshoot of the last split is cut to the strongest
  EXPECT_EQ(two, (std::vector<int>{14, 19}));
}
