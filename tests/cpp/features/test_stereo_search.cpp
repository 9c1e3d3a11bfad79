// The descriptor-free stereo search (features/stereo_search.hpp) and the zero-mean SAD scan it
// is built on (features/sad.hpp): rows with a known integer shift, a periodic texture, and
// rendered planes at known depths seen by KITTI 0000's cameras 2 and 3.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "features/sad.hpp"
#include "features/stereo_search.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::features;

namespace {

// SAD window of the scan tests: the defaults of StereoSearchOptions (15 x 5 level px).
constexpr int kHalfWidth = 7, kHalfHeight = 2;

// A left image of random texture and a right image that sees it `disparity` px to the left
// (R(x) = L(x + disparity), rectified), each with its own Gaussian noise of `noise` grey levels.
struct ShiftedPair {
  cv::Mat left, right;
};

ShiftedPair shifted_pair(const cv::Mat& texture_f32, int disparity, double noise, std::uint64_t seed) {
  const int width = texture_f32.cols - disparity;
  cv::Mat left = texture_f32.colRange(0, width).clone();
  cv::Mat right = texture_f32.colRange(disparity, disparity + width).clone();
  cv::RNG rng(seed);
  for (cv::Mat* m : {&left, &right}) {
    cv::Mat n(m->size(), CV_32F);
    rng.fill(n, cv::RNG::NORMAL, 0.0, noise);
    *m += n;
  }
  return {test::to_u8(left), test::to_u8(right)};
}

TEST(ScanSad, RandomTextureGivesTheExactShiftAndADistinctMinimum) {
  const cv::Mat texture = test::random_texture(260, 40, 7);
  for (int disparity : {3, 17, 42}) {
    const ShiftedPair p = shifted_pair(texture, disparity, 1.0, 50 + disparity);
    for (int xl : {80, 120, 160}) {
      const SadScan scan = scan_sad(p.left, p.right, xl, 20, xl - 70, xl, kHalfWidth, kHalfHeight);
      ASSERT_EQ(scan.best_column, xl - disparity) << "disparity " << disparity << ", xl " << xl;
      // noise of 1 grey level against a texture of std ~40: the true minimum is far below
      // any other (a ratio near 1 would fail the search's uniqueness test of 0.7)
      EXPECT_LT(scan.best_cost, 0.2f);
      EXPECT_TRUE(std::isfinite(scan.second_cost));
      EXPECT_LT(scan.best_cost, 0.4f * scan.second_cost);
    }
  }
}

TEST(ScanSad, PeriodicTextureHasNoUniqueMinimum) {
  // Columns repeat every 8 px (a random 8 px wide tile repeated), rows vary: every
  // 8-px multiple of the shift fits as well as the true one.
  constexpr int kPeriodPx = 8;
  const cv::Mat tile = test::random_texture(kPeriodPx, 40, 9);
  cv::Mat texture;
  cv::repeat(tile, 1, 32, texture);
  const ShiftedPair p = shifted_pair(texture, 13, 1.0, 60);
  const SadScan scan = scan_sad(p.left, p.right, 120, 20, 60, 120, kHalfWidth, kHalfHeight);
  ASSERT_GE(scan.best_column, 0);
  EXPECT_EQ((120 - scan.best_column) % kPeriodPx, 13 % kPeriodPx);  // one of the aliases
  ASSERT_TRUE(std::isfinite(scan.second_cost));
  EXPECT_GT(scan.best_cost / scan.second_cost, 0.8f);
  // the control: the same scan on random texture is clearly unique
  const ShiftedPair q = shifted_pair(test::random_texture(256, 40, 10), 13, 1.0, 61);
  const SadScan unique = scan_sad(q.left, q.right, 120, 20, 60, 120, kHalfWidth, kHalfHeight);
  EXPECT_LT(unique.best_cost / unique.second_cost, 0.5f);
}

TEST(ScanSad, WindowsLeavingTheImageGiveNoColumn) {
  const ShiftedPair p = shifted_pair(test::random_texture(220, 40, 11), 10, 1.0, 62);
  const int W = p.left.cols, H = p.left.rows;
  // the left window leaves the image
  EXPECT_EQ(scan_sad(p.left, p.right, 100, 1, 50, 100, kHalfWidth, kHalfHeight).best_column, -1);
  EXPECT_EQ(scan_sad(p.left, p.right, 100, H - 2, 50, 100, kHalfWidth, kHalfHeight).best_column, -1);
  EXPECT_EQ(scan_sad(p.left, p.right, 3, 20, 0, 3, kHalfWidth, kHalfHeight).best_column, -1);
  EXPECT_EQ(scan_sad(p.left, p.right, W - 4, 20, 50, W - 4, kHalfWidth, kHalfHeight).best_column, -1);
  // every right window leaves the image
  EXPECT_EQ(scan_sad(p.left, p.right, 100, 20, -40, 2, kHalfWidth, kHalfHeight).best_column, -1);
  EXPECT_EQ(scan_sad(p.left, p.right, 100, 20, W, W + 30, kHalfWidth, kHalfHeight).best_column, -1);
  // a right image with fewer rows than the left window needs
  EXPECT_EQ(scan_sad(p.left, p.right.rowRange(0, 21), 100, 20, 50, 100, kHalfWidth, kHalfHeight)
                .best_column, -1);
  // a range reaching past the left edge is clipped, not refused: the true column is found
  const SadScan clipped = scan_sad(p.left, p.right, 30, 20, -60, 30, kHalfWidth, kHalfHeight);
  EXPECT_EQ(clipped.best_column, 20);
  // three columns around the minimum: nothing >= 2 columns away competes
  const SadScan narrow = scan_sad(p.left, p.right, 100, 20, 89, 91, kHalfWidth, kHalfHeight);
  EXPECT_EQ(narrow.best_column, 90);
  EXPECT_TRUE(std::isinf(narrow.second_cost));
}

// Planes at 8, 20 and 45 m and a uniform (untextured) one at 20 m, rendered for KITTI 0000;
// the right image's principal point sits kOffsetPx right of the calibration's, which the
// camera's disparity_offset declares.
constexpr double kOffsetPx = 0.6;  // px, what real KITTI colour pairs lack (docs/camera_scale.md)
constexpr int kUniformPlane = 3;

struct SearchScene {
  geometry::StereoCamera cam = test::kitti_camera();
  std::vector<test::Plane> planes;
  cv::Mat left, right, ids_left, ids_right;
  Keypoints keypoints;
  std::vector<cv::Mat> pyramid_left, pyramid_right;

  SearchScene() {
    planes = {test::make_plane(45.0, -40, -12, 40, 12, 1.3, cam.fx, 21),
              test::make_plane(20.0, -9.0, -2.0, -1.0, 2.0, 1.3, cam.fx, 22),
              test::make_plane(8.0, 0.5, -1.5, 4.0, 1.2, 1.3, cam.fx, 23),
              test::make_plane(20.0, 8.0, -1.5, 14.0, 1.5, 1.3, cam.fx, 24)};
    planes[kUniformPlane].texture.setTo(128.0);
    cam.disparity_offset = kOffsetPx;
    geometry::StereoCamera shifted = cam;
    shifted.cx += kOffsetPx;
    left = test::render(planes, cam, false, &ids_left, 1.0, 400);
    right = test::render(planes, shifted, true, &ids_right, 1.0, 401);
    keypoints = OrbExtractor(OrbOptions{}).extract(left);
    pyramid_left = keypoints.pyramid;
    pyramid_right = build_pyramid(right, keypoints.scale_factor, static_cast<int>(pyramid_left.size()));
  }

  // True depth along the left axis and image disparity (u_left - u_right of the rendered
  // pair) at a left pixel; plane -1 where the SAD window is not on one plane in both images.
  struct Truth {
    int plane = -1;
    double depth = 0, disparity = 0;
  };
  Truth truth(const cv::KeyPoint& k) const {
    Truth t;
    const test::Hit h = test::cast_ray(planes, cam, cam.t_left, k.pt.x, k.pt.y);
    if (h.plane < 0) return t;
    const double ur = cam.project_right(h.X_c).x() + kOffsetPx;
    // the 15 x 5 window at the keypoint's level with a margin of 2 level px
    const double r = 10.0 * std::pow(1.2, k.octave);
    if (!test::box_on_plane(ids_left, k.pt.x, k.pt.y, r, h.plane) ||
        !test::box_on_plane(ids_right, ur, k.pt.y, r, h.plane))
      return t;
    t.plane = h.plane;
    t.depth = (h.X_c + cam.t_left).z();
    t.disparity = k.pt.x - ur;
    return t;
  }
};

const SearchScene& search_scene() {
  static const SearchScene s;
  return s;
}

StereoMatches unmatched(size_t n) {
  return {std::vector<float>(n, -1.0f), std::vector<float>(n, -1.0f)};
}

TEST(SearchStereo, RecoversKnownDepthsAtOctavesZeroAndOne) {
  const SearchScene& s = search_scene();
  std::vector<int> which;
  for (int i = 0; i < static_cast<int>(s.keypoints.size()); ++i)
    if (s.keypoints.keypoints[i].octave <= 1 && s.truth(s.keypoints.keypoints[i]).plane >= 0 &&
        s.truth(s.keypoints.keypoints[i]).plane != kUniformPlane)
      which.push_back(i);
  StereoMatches m = unmatched(s.keypoints.size());
  const int found = search_stereo(s.keypoints, s.pyramid_left, s.pyramid_right, s.cam,
                                  StereoSearchOptions{}, which, &m);
  EXPECT_EQ(found, static_cast<int>(m.num_matched()));
  // per plane (8, 20, 45 m) and octave: accepted, and accurate within 1 % or 0.15 px
  int per_plane_octave[3][2] = {}, accepted_per_plane[3][2] = {};
  int accurate = 0, far_off = 0;
  for (int i : which) {
    const cv::KeyPoint& k = s.keypoints.keypoints[i];
    const SearchScene::Truth t = s.truth(k);
    const int p = t.plane == 0 ? 2 : t.plane == 1 ? 1 : 0;  // 0: 8 m, 1: 20 m, 2: 45 m
    ++per_plane_octave[p][k.octave];
    if (!(m.depth[i] > 0)) continue;
    ++accepted_per_plane[p][k.octave];
    // depth follows from the right column and the camera's offset
    EXPECT_NEAR(m.depth[i], s.cam.fx * s.cam.baseline / (k.pt.x - m.u_right[i] + kOffsetPx),
                1e-4 * m.depth[i]);
    const double disparity_error = std::abs(k.pt.x - m.u_right[i] - t.disparity);
    const double depth_error = std::abs(m.depth[i] - t.depth) / t.depth;
    if (depth_error < 0.01 || disparity_error < 0.15) ++accurate;
    if (disparity_error > 1.0) ++far_off;
  }
  std::cout << "[ search ] keypoints " << which.size() << ", found " << found << ", accurate "
            << accurate << ", > 1 px off " << far_off << "; per plane 8/20/45 m, octave 0|1:";
  for (int p = 0; p < 3; ++p)
    std::cout << " " << accepted_per_plane[p][0] << "/" << per_plane_octave[p][0] << "|"
              << accepted_per_plane[p][1] << "/" << per_plane_octave[p][1];
  std::cout << "\n";
  ASSERT_GT(found, 300);
  for (int p = 0; p < 3; ++p)
    for (int o = 0; o < 2; ++o) {
      ASSERT_GT(per_plane_octave[p][o], 10) << "plane " << p << " octave " << o;
      EXPECT_GT(accepted_per_plane[p][o], 0.6 * per_plane_octave[p][o]) << "plane " << p << " octave " << o;
    }
  EXPECT_GE(accurate, 0.97 * found);
  EXPECT_LE(far_off, 0.01 * found);
}

TEST(SearchStereo, IgnoringTheDisparityOffsetBiasesFarDepths) {
  // the control of the offset: the same pair searched with a camera that trusts the
  // calibration puts the 45 m plane ~0.6 / 8.7 ~ 7 % too deep
  const SearchScene& s = search_scene();
  geometry::StereoCamera trusting = s.cam;
  trusting.disparity_offset = 0;
  std::vector<int> which;
  for (int i = 0; i < static_cast<int>(s.keypoints.size()); ++i)
    if (s.keypoints.keypoints[i].octave == 0 && s.truth(s.keypoints.keypoints[i]).plane == 0)
      which.push_back(i);
  std::vector<double> with, without;
  for (const geometry::StereoCamera* cam : {&s.cam, static_cast<const geometry::StereoCamera*>(&trusting)}) {
    StereoMatches m = unmatched(s.keypoints.size());
    search_stereo(s.keypoints, s.pyramid_left, s.pyramid_right, *cam, StereoSearchOptions{}, which, &m);
    for (int i : which)
      if (m.depth[i] > 0) (cam == &s.cam ? with : without).push_back(m.depth[i] / 45.0);
  }
  ASSERT_GT(with.size(), 30u);
  ASSERT_GT(without.size(), 30u);
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  EXPECT_NEAR(median(with), 1.0, 0.005);
  EXPECT_GT(median(without), 1.05);
}

TEST(SearchStereo, UniformRegionGetsNoDepthAndOnlyWhichIsTouched) {
  const SearchScene& s = search_scene();
  // keypoints placed by hand on the untextured plane (ORB finds none there), and a few
  // textured ORB keypoints, of which only some are searched
  Keypoints kp;
  for (float u = 1000; u <= 1080; u += 20)
    for (float v = 140; v <= 200; v += 20) {
      ASSERT_EQ(s.ids_left.at<int>(static_cast<int>(v), static_cast<int>(u)), kUniformPlane);
      kp.keypoints.emplace_back(cv::Point2f(u, v), 31.0f, 0.0f, 0.0f, 0);
    }
  const int num_uniform = static_cast<int>(kp.size());
  for (const cv::KeyPoint& k : s.keypoints.keypoints)
    if (k.octave == 0 && s.truth(k).plane == 2 && kp.size() < static_cast<size_t>(num_uniform) + 40)
      kp.keypoints.push_back(k);
  ASSERT_EQ(kp.size(), static_cast<size_t>(num_uniform) + 40);
  std::vector<int> which;
  for (int i = 0; i < static_cast<int>(kp.size()); ++i)
    if (i < num_uniform || i % 2 == 0) which.push_back(i);
  constexpr float kSentinel = -7.0f;  // what the caller had: kept where nothing is found
  StereoMatches m{std::vector<float>(kp.size(), kSentinel), std::vector<float>(kp.size(), kSentinel)};
  const int found = search_stereo(kp, s.pyramid_left, s.pyramid_right, s.cam, StereoSearchOptions{}, which, &m);
  for (int i = 0; i < num_uniform; ++i) {
    EXPECT_EQ(m.depth[i], kSentinel) << "uniform keypoint " << i;
    EXPECT_EQ(m.u_right[i], kSentinel) << "uniform keypoint " << i;
  }
  int searched_found = 0;
  for (int i = num_uniform; i < static_cast<int>(kp.size()); ++i) {
    if (i % 2) {
      EXPECT_EQ(m.depth[i], kSentinel) << "keypoint " << i << " is not in which";
      EXPECT_EQ(m.u_right[i], kSentinel);
    } else if (m.depth[i] != kSentinel) {
      ++searched_found;
      EXPECT_NEAR(m.depth[i], 8.0, 0.08);
    }
  }
  EXPECT_EQ(found, searched_found);
  EXPECT_GT(searched_found, 15);  // of the 20 textured keypoints searched
}

TEST(SearchStereo, BadInputThrows) {
  const SearchScene& s = search_scene();
  const Keypoints& kp = s.keypoints;
  const StereoSearchOptions ok;
  const StereoMatches m0 = unmatched(kp.size());
  auto run = [&](const Keypoints& k, const std::vector<cv::Mat>& pl, const std::vector<cv::Mat>& pr,
                 const geometry::StereoCamera& cam, const StereoSearchOptions& o,
                 const std::vector<int>& which, StereoMatches m) {
    return search_stereo(k, pl, pr, cam, o, which, &m);
  };
  const int n = static_cast<int>(kp.size());
  EXPECT_NO_THROW(run(kp, s.pyramid_left, s.pyramid_right, s.cam, ok, {0, n - 1}, m0));
  EXPECT_THROW(run(kp, s.pyramid_left, s.pyramid_right, s.cam, ok, {n}, m0), std::invalid_argument);
  EXPECT_THROW(run(kp, s.pyramid_left, s.pyramid_right, s.cam, ok, {-1}, m0), std::invalid_argument);
  // a keypoint of octave 1 against pyramids of one level
  int octave1 = -1;
  for (int i = 0; i < n && octave1 < 0; ++i)
    if (kp.keypoints[i].octave == 1) octave1 = i;
  ASSERT_GE(octave1, 0);
  const std::vector<cv::Mat> one_left(s.pyramid_left.begin(), s.pyramid_left.begin() + 1);
  const std::vector<cv::Mat> one_right(s.pyramid_right.begin(), s.pyramid_right.begin() + 1);
  EXPECT_THROW(run(kp, one_left, s.pyramid_right, s.cam, ok, {octave1}, m0), std::invalid_argument);
  EXPECT_THROW(run(kp, s.pyramid_left, one_right, s.cam, ok, {octave1}, m0), std::invalid_argument);
  EXPECT_THROW(run(kp, s.pyramid_left, {}, s.cam, ok, {0}, m0), std::invalid_argument);
  const std::vector<cv::Mat> cropped = {s.pyramid_right[0](cv::Rect(0, 0, 600, 300))};
  EXPECT_THROW(run(kp, one_left, cropped, s.cam, ok, {0}, m0), std::invalid_argument);
  // matches of the wrong size
  StereoMatches short_depth = m0;
  short_depth.depth.pop_back();
  EXPECT_THROW(run(kp, s.pyramid_left, s.pyramid_right, s.cam, ok, {0}, short_depth), std::invalid_argument);
  EXPECT_THROW(run(kp, s.pyramid_left, s.pyramid_right, s.cam, ok, {0}, unmatched(n + 1)),
               std::invalid_argument);
  // a camera without baseline or focal length
  geometry::StereoCamera no_baseline = s.cam;
  no_baseline.baseline = 0;
  EXPECT_THROW(run(kp, s.pyramid_left, s.pyramid_right, no_baseline, ok, {0}, m0), std::invalid_argument);
  geometry::StereoCamera no_focal = s.cam;
  no_focal.fx = 0;
  EXPECT_THROW(run(kp, s.pyramid_left, s.pyramid_right, no_focal, ok, {0}, m0), std::invalid_argument);
  // each bad option, also with nothing to search
  std::vector<StereoSearchOptions> bad(9, ok);
  bad[0].min_depth = 0;
  bad[1].max_depth = bad[1].min_depth;
  bad[2].max_depth = 2e4f;
  bad[3].max_cost = 0;
  bad[4].uniqueness = 0;
  bad[5].uniqueness = 1.5f;
  bad[6].patch_radius = 0;
  bad[7].patch_radius = kMaxSadHalfWidth + 1;
  bad[8].patch_half_height = -1;
  for (size_t b = 0; b < bad.size(); ++b) {
    EXPECT_THROW(check_options(bad[b]), std::invalid_argument) << "option set " << b;
    EXPECT_THROW(run(kp, s.pyramid_left, s.pyramid_right, s.cam, bad[b], {}, m0), std::invalid_argument)
        << "option set " << b;
  }
  bad[0] = ok;
  bad[0].max_depth = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(check_options(bad[0]), std::invalid_argument);
}

// Left keypoints whose ray hits the 45 m background just left of the 8 m plane: the right
// camera, 0.54 m to the right, sees the 8 m plane there (it shifts ~48 px, the background
// ~9 px), so a scan matches them to whatever fits and the true match does not exist.
TEST(CheckLeftRight, DropsMatchesTheRightCameraCannotSeeAndKeepsGoodOnes) {
  const SearchScene& s = search_scene();
  std::vector<int> which;
  for (int i = 0; i < static_cast<int>(s.keypoints.size()); ++i)
    if (s.keypoints.keypoints[i].octave <= 1) which.push_back(i);
  StereoMatches m = unmatched(s.keypoints.size());
  // a loose scan, so that the occluded keypoints get (wrong) matches to check
  StereoSearchOptions loose;
  loose.max_cost = 1.5f;
  loose.uniqueness = 1.0f;
  search_stereo(s.keypoints, s.pyramid_left, s.pyramid_right, s.cam, loose, which, &m);
  const StereoMatches before = m;
  std::vector<int> good, wrong;
  for (int i : which) {
    if (!(m.depth[i] > 0)) continue;
    const cv::KeyPoint& k = s.keypoints.keypoints[i];
    const test::Hit h = test::cast_ray(s.planes, s.cam, s.cam.t_left, k.pt.x, k.pt.y);
    if (h.plane < 0 || h.plane == kUniformPlane) continue;
    const double depth = (h.X_c + s.cam.t_left).z();
    const double error = std::abs(m.depth[i] - depth) / depth;
    if (s.truth(k).plane >= 0 && error < 0.01) good.push_back(i);
    else if (error > 0.2) wrong.push_back(i);
  }
  const int removed = check_left_right(s.keypoints, s.pyramid_left, s.pyramid_right, s.cam,
                                       StereoSearchOptions{}, which, 1.0f, &m);
  int good_kept = 0, wrong_removed = 0, total_removed = 0;
  for (int i : good) good_kept += m.depth[i] > 0;
  for (int i : wrong) wrong_removed += !(m.depth[i] > 0);
  for (int i : which) {
    if (m.depth[i] > 0) {  // a kept match is untouched
      EXPECT_EQ(m.depth[i], before.depth[i]);
      EXPECT_EQ(m.u_right[i], before.u_right[i]);
    } else if (before.depth[i] > 0) {
      ++total_removed;
      EXPECT_EQ(m.u_right[i], -1.0f);
    }
  }
  std::cout << "[ left-right ] good " << good.size() << " kept " << good_kept << "; wrong "
            << wrong.size() << " removed " << wrong_removed << "\n";
  EXPECT_EQ(removed, total_removed);
  ASSERT_GT(good.size(), 300u);
  ASSERT_GT(wrong.size(), 10u);
  EXPECT_GE(good_kept, 0.97 * good.size());
  EXPECT_GE(wrong_removed, 0.6 * wrong.size());
  // bad input: as search_stereo, and a negative tolerance
  EXPECT_THROW(check_left_right(s.keypoints, s.pyramid_left, s.pyramid_right, s.cam,
                                StereoSearchOptions{}, which, -1.0f, &m),
               std::invalid_argument);
  StereoMatches short_matches = unmatched(s.keypoints.size() - 1);
  EXPECT_THROW(check_left_right(s.keypoints, s.pyramid_left, s.pyramid_right, s.cam,
                                StereoSearchOptions{}, which, 1.0f, &short_matches),
               std::invalid_argument);
  EXPECT_THROW(check_left_right(s.keypoints, s.pyramid_left, s.pyramid_right, s.cam,
                                StereoSearchOptions{}, {static_cast<int>(s.keypoints.size())}, 1.0f, &m),
               std::invalid_argument);
}

}  // namespace

// A person-like pole 11 px wide (0.12 m at 8 m), of weak texture, in front of a strongly
// textured wall at 12 m: the 15 px SAD window of a keypoint on the pole holds more wall than
// pole. The depth of the pole's own pixels (depth_on_instance_pixels) is the pole's; windows on
// one instance, and windows with too small a share of it, keep the depth they had.
struct PoleScene {
  geometry::StereoCamera cam = test::kitti_camera();
  cv::Mat left, right, instances;
  std::vector<cv::Mat> pyramid_left, pyramid_right;
  Keypoints pole, wall;  // keypoints on the pole's centre line, and in the wall's open middle

  PoleScene() {
    std::vector<test::Plane> planes = {test::make_plane(8.0, 0.0, -1.5, 0.12, 1.0, 1.3, cam.fx, 31),
                                       test::make_plane(12.0, -6.0, -3.0, 6.0, 2.0, 1.3, cam.fx, 32)};
    planes[0].texture = (planes[0].texture - 128.0) * 0.25 + 128.0;  // weak texture (std 10)
    cv::Mat ids_left, ids_right;
    left = test::render(planes, cam, false, &ids_left, 1.0, 410);
    right = test::render(planes, cam, true, &ids_right, 1.0, 411);
    instances = cv::Mat::zeros(ids_left.size(), CV_32SC1);
    instances.setTo(7, ids_left == 0);  // the pole is instance 7, the wall no instance
    pyramid_left = build_pyramid(left, 1.2f, 2);
    pyramid_right = build_pyramid(right, 1.2f, 2);
    for (int v = 80; v < 300; v += 6) {
      int first = -1, last = -1;
      for (int u = 0; u < left.cols; ++u)
        if (ids_left.at<int>(v, u) == 0) (first < 0 ? first : last) = u, last = u;
      if (first < 0) continue;
      pole.keypoints.emplace_back(cv::Point2f(0.5f * (first + last), static_cast<float>(v)), 31.0f,
                                  0.0f, 1.0f, 0);
      wall.keypoints.emplace_back(cv::Point2f(static_cast<float>(first - 60), static_cast<float>(v)),
                                  31.0f, 0.0f, 1.0f, 0);
    }
  }
};

TEST(DepthOnInstancePixels, ThinObjectInFrontOfATexturedWallGetsItsOwnDepth) {
  const PoleScene s;
  const int n = static_cast<int>(s.pole.size());
  ASSERT_GE(n, 25);
  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  const StereoSearchOptions options;
  // the whole window's scan: the pole's depth for few keypoints, if any (the scene does what it
  // is for: the wall's texture dominates the window)
  StereoMatches whole = unmatched(n);
  search_stereo(s.pole, s.pyramid_left, s.pyramid_right, s.cam, options, all, &whole);
  int whole_good = 0;
  for (int i = 0; i < n; ++i) whole_good += std::abs(whole.depth[i] - 8.0f) < 0.08f;
  EXPECT_LT(whole_good, n / 4);
  // every keypoint given the wall's depth (what a descriptor match refined on the whole
  // window gave the simulator's pedestrian), then searched on the pole's pixels
  StereoMatches m = unmatched(n);
  const double fb = s.cam.fx * s.cam.baseline;
  for (int i = 0; i < n; ++i) {
    m.depth[i] = 12.0f;
    m.u_right[i] = s.pole.keypoints[i].pt.x - static_cast<float>(fb / 12.0);
  }
  const InstanceSupportReport report = depth_on_instance_pixels(
      s.pole, s.pyramid_left, s.pyramid_right, s.cam, options, all, s.instances, 0.3f, &m);
  int good = 0, with_depth = 0;
  for (int i = 0; i < n; ++i) {
    if (!(m.depth[i] > 0)) continue;
    ++with_depth;
    good += std::abs(m.depth[i] - 8.0f) < 0.08f;  // 1 %
    EXPECT_NEAR(m.u_right[i], s.pole.keypoints[i].pt.x - fb / m.depth[i], 1e-3) << i;
  }
  std::cout << "whole window: " << whole_good << " of " << n << " at the pole's depth; own pixels: "
            << good << " of " << with_depth << " within 1 % (" << report.num_rescanned
            << " rescanned, " << report.num_dropped << " dropped)\n";
  EXPECT_EQ(report.num_rescanned, n);
  EXPECT_EQ(report.num_dropped, n - with_depth);
  EXPECT_GE(with_depth, n * 3 / 4);
  EXPECT_EQ(good, with_depth);  // none kept the wall's depth
}

TEST(DepthOnInstancePixels, WindowsOnOneInstanceOrWithTooLittleOfItKeepTheirDepth) {
  const PoleScene s;
  const int n = static_cast<int>(s.wall.size());
  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  const StereoSearchOptions options;
  // the wall's keypoints on an instance of their own (the whole image but the pole)
  cv::Mat wall_instance = cv::Mat::zeros(s.instances.size(), CV_32SC1);
  wall_instance.setTo(3, s.instances == 0);
  StereoMatches m = unmatched(n);
  search_stereo(s.wall, s.pyramid_left, s.pyramid_right, s.cam, options, all, &m);
  const StereoMatches before = m;
  InstanceSupportReport r = depth_on_instance_pixels(s.wall, s.pyramid_left, s.pyramid_right, s.cam,
                                                     options, all, wall_instance, 0.3f, &m);
  EXPECT_EQ(r.num_rescanned, 0);
  EXPECT_EQ(m.depth, before.depth);
  EXPECT_EQ(m.u_right, before.u_right);
  // the pole's keypoints with a share threshold above what their windows hold: untouched
  StereoMatches p = unmatched(s.pole.size());
  std::vector<int> pole_all(s.pole.size());
  for (int i = 0; i < static_cast<int>(s.pole.size()); ++i) pole_all[i] = i;
  search_stereo(s.pole, s.pyramid_left, s.pyramid_right, s.cam, options, pole_all, &p);
  const StereoMatches pole_before = p;
  r = depth_on_instance_pixels(s.pole, s.pyramid_left, s.pyramid_right, s.cam, options, pole_all,
                               s.instances, 0.9f, &p);
  EXPECT_EQ(r.num_rescanned, 0);
  EXPECT_EQ(p.depth, pole_before.depth);
  // bad input
  EXPECT_THROW(depth_on_instance_pixels(s.pole, s.pyramid_left, s.pyramid_right, s.cam, options,
                                        pole_all, cv::Mat(s.instances.size(), CV_8UC1), 0.3f, &p),
               std::invalid_argument);
  EXPECT_THROW(depth_on_instance_pixels(s.pole, s.pyramid_left, s.pyramid_right, s.cam, options,
                                        pole_all, s.instances(cv::Rect(0, 0, 100, 100)), 0.3f, &p),
               std::invalid_argument);
  EXPECT_THROW(depth_on_instance_pixels(s.pole, s.pyramid_left, s.pyramid_right, s.cam, options,
                                        pole_all, s.instances, 1.5f, &p),
               std::invalid_argument);
}

// A full support is the plain zero-mean SAD (the same column, the cost to float rounding).
TEST(ScanSad, FullSupportIsThePlainWindow) {
  const cv::Mat texture = test::random_texture(260, 40, 9);
  const ShiftedPair p = shifted_pair(texture, 17, 2.0, 90);
  const std::vector<std::uint8_t> full((2 * kHalfWidth + 1) * (2 * kHalfHeight + 1), 1);
  for (int xl : {80, 130, 170}) {
    const SadScan plain = scan_sad(p.left, p.right, xl, 20, xl - 60, xl, kHalfWidth, kHalfHeight);
    const SadScan masked = scan_sad(p.left, p.right, xl, 20, xl - 60, xl, kHalfWidth, kHalfHeight,
                                    full.data());
    EXPECT_EQ(masked.best_column, plain.best_column);
    EXPECT_NEAR(masked.best_cost, plain.best_cost, 1e-4f);
    EXPECT_NEAR(masked.second_cost, plain.second_cost, 1e-4f);
    const SadRefined a = refine_sad(p.left, p.right, xl, 20, plain.best_column, 0.3f, kHalfWidth,
                                    kHalfHeight, 2);
    const SadRefined b = refine_sad(p.left, p.right, xl, 20, plain.best_column, 0.3f, kHalfWidth,
                                    kHalfHeight, 2, full.data());
    ASSERT_TRUE(a.ok && b.ok);
    EXPECT_NEAR(a.u_level, b.u_level, 1e-4f);
    EXPECT_NEAR(a.cost, b.cost, 1e-4f);
  }
  // an empty support gives nothing
  const std::vector<std::uint8_t> none(full.size(), 0);
  EXPECT_LT(scan_sad(p.left, p.right, 100, 20, 40, 100, kHalfWidth, kHalfHeight, none.data()).best_column, 0);
}

// A pixel located by the optical flow is no keypoint: search_pixel_stereo scans it on the
// level-0 images at its sub-pixel position. On the rendered planes (8, 20, 45 m) a grid of
// such pixels gets its depth within 1 % or 0.15 px like the keypoints, none on the uniform
// plane, and none for a NaN pixel.
TEST(SearchPixelStereo, PixelsThatAreNoKeypointsGetTheirPlanesDepth) {
  const SearchScene& s = search_scene();
  const StereoSearchOptions options;
  int on_planes = 0, found = 0, accurate = 0, uniform = 0, uniform_found = 0;
  for (float v = 20.25f; v < s.left.rows - 20; v += 13.0f)
    for (float u = 20.6f; u < s.left.cols - 20; u += 17.0f) {
      const SearchScene::Truth t = s.truth(cv::KeyPoint(cv::Point2f(u, v), 31.0f, -1.0f, 0.0f, 0));
      if (t.plane < 0) continue;
      float u_right = -1, depth = -1;
      const bool ok = search_pixel_stereo(s.left, s.right, s.cam, options, u, v, nullptr, &u_right, &depth);
      if (t.plane == kUniformPlane) {
        ++uniform, uniform_found += ok;
        continue;
      }
      ++on_planes;
      if (!ok) {
        EXPECT_EQ(depth, -1.0f);  // untouched
        continue;
      }
      ++found;
      EXPECT_NEAR(depth, s.cam.fx * s.cam.baseline / (u - u_right + kOffsetPx), 1e-4 * depth);
      if (std::abs(depth - t.depth) / t.depth < 0.01 || std::abs(u - u_right - t.disparity) < 0.15)
        ++accurate;
    }
  std::cout << "[ pixels ] on textured planes " << on_planes << ", found " << found << ", accurate "
            << accurate << "; uniform plane " << uniform_found << " of " << uniform << "\n";
  ASSERT_GT(on_planes, 500);
  ASSERT_GT(uniform, 20);
  EXPECT_GT(found, 0.8 * on_planes);
  EXPECT_GE(accurate, 0.97 * found);
  EXPECT_EQ(uniform_found, 0);
  float u_right = -1, depth = -1;
  EXPECT_FALSE(search_pixel_stereo(s.left, s.right, s.cam, options, std::nanf(""), 100.0f, nullptr,
                                   &u_right, &depth));
  EXPECT_FALSE(search_pixel_stereo(s.left, s.right, s.cam, options, 2.0f, 100.0f, nullptr, &u_right,
                                   &depth));  // the window leaves the image
  EXPECT_EQ(depth, -1.0f);
}

// With a support on the thin object's pixels, a pixel on it takes its depth, not the wall's.
TEST(SearchPixelStereo, SupportOnTheObjectsPixelsGivesItsDepth) {
  const PoleScene s;
  const StereoSearchOptions options;
  const int cols = 2 * options.patch_radius + 1, rows = 2 * options.patch_half_height + 1;
  const double fb = s.cam.fx * s.cam.baseline;
  int n = 0, whole_good = 0, own_found = 0, own_good = 0;
  for (const cv::KeyPoint& k : s.pole.keypoints) {
    ++n;
    float u_right = -1, depth = -1;
    if (search_pixel_stereo(s.left, s.right, s.cam, options, k.pt.x, k.pt.y, nullptr, &u_right, &depth))
      whole_good += std::abs(depth - 8.0f) < 0.08f;
    std::vector<std::uint8_t> support(static_cast<size_t>(rows) * cols);
    const int x = cvRound(k.pt.x), y = cvRound(k.pt.y);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        support[static_cast<size_t>(r) * cols + c] =
            s.instances.at<int>(y - options.patch_half_height + r, x - options.patch_radius + c) == 7;
    u_right = depth = -1;
    if (!search_pixel_stereo(s.left, s.right, s.cam, options, k.pt.x, k.pt.y, support.data(), &u_right,
                             &depth))
      continue;
    ++own_found;
    own_good += std::abs(depth - 8.0f) < 0.08f;
    EXPECT_NEAR(u_right, k.pt.x - fb / depth, 1e-3);
  }
  std::cout << "[ pixels ] pole: whole window " << whole_good << " of " << n << " at its depth; own pixels "
            << own_good << " of " << own_found << "\n";
  EXPECT_LT(whole_good, n / 4);
  EXPECT_GE(own_found, n * 3 / 4);
  EXPECT_EQ(own_good, own_found);
}

TEST(SearchPixelStereo, BadImagesThrow) {
  const SearchScene& s = search_scene();
  float u_right = -1, depth = -1;
  cv::Mat colour;
  cv::cvtColor(s.left, colour, cv::COLOR_GRAY2BGR);
  EXPECT_THROW(search_pixel_stereo(colour, s.right, s.cam, StereoSearchOptions{}, 100, 100, nullptr,
                                   &u_right, &depth),
               std::invalid_argument);
  EXPECT_THROW(search_pixel_stereo(s.left, s.right.colRange(0, 600), s.cam, StereoSearchOptions{}, 100,
                                   100, nullptr, &u_right, &depth),
               std::invalid_argument);
  StereoSearchOptions bad;
  bad.uniqueness = 0;
  EXPECT_THROW(search_pixel_stereo(s.left, s.right, s.cam, bad, 100, 100, nullptr, &u_right, &depth),
               std::invalid_argument);
}

namespace {

// A weakly textured far car (a plane at 45 m, 2 m wide) with a strongly textured nearer car at
// 25 m just left of it in the image and a textured wall at 60 m behind: windows on the far
// car's left edge hold the nearer car's texture, which outweighs its own; windows on its right
// edge hold the wall's. (The nearer car is on the left so that the right camera still sees the
// far car's edge: on its right it would hide it there.) The far car is instance 5, the nearer
// one instance 9, the wall no instance.
struct FarCarScene {
  geometry::StereoCamera cam = test::kitti_camera();
  cv::Mat left, right, instances;
  std::vector<cv::Mat> pyramid_left, pyramid_right;
  Keypoints near_car_edge, wall_edge, middle;
  static constexpr double kCarDepth = 45.0, kNearCarDepth = 25.0;

  FarCarScene() {
    // the nearer car's right edge on the car's left edge seen from the left camera
    const double near_x1 = -1.0 * kNearCarDepth / kCarDepth;
    std::vector<test::Plane> planes = {test::make_plane(kCarDepth, -1.0, -1.5, 1.0, 1.5, 1.3, cam.fx, 51),
                                       test::make_plane(kNearCarDepth, near_x1 - 1.0, -3.0, near_x1, 3.0, 1.3, cam.fx, 52),
                                       test::make_plane(60.0, -30, -10, 30, 10, 1.3, cam.fx, 53)};
    planes[0].texture = (planes[0].texture - 128.0) * 0.15 + 128.0;  // weak texture (std 6)
    cv::Mat ids_left, ids_right;
    left = test::render(planes, cam, false, &ids_left, 1.0, 420);
    right = test::render(planes, cam, true, &ids_right, 1.0, 421);
    instances = cv::Mat::zeros(ids_left.size(), CV_32SC1);
    instances.setTo(5, ids_left == 0);
    instances.setTo(9, ids_left == 1);
    pyramid_left = build_pyramid(left, 1.2f, 2);
    pyramid_right = build_pyramid(right, 1.2f, 2);
    auto at = [](double u, int row) {
      return cv::KeyPoint(cv::Point2f(static_cast<float>(u), static_cast<float>(row)), 31.0f, 0.0f, 1.0f, 0);
    };
    for (int v = 3; v + 3 < left.rows; v += 2) {
      int first = -1, last = -1;
      for (int u = 0; u < left.cols; ++u)
        if (ids_left.at<int>(v, u) == 0) (first < 0 ? first : last) = u, last = u;
      // rows whose windows lie within the car's height
      if (first < 0 || ids_left.at<int>(v - 3, first + 1) != 0 || ids_left.at<int>(v + 3, first + 1) != 0 ||
          ids_left.at<int>(v - 3, last - 1) != 0 || ids_left.at<int>(v + 3, last - 1) != 0)
        continue;
      near_car_edge.keypoints.push_back(at(first + 3, v));
      wall_edge.keypoints.push_back(at(last - 2, v));
      middle.keypoints.push_back(at(0.5 * (first + last), v));
    }
  }

  // every keypoint given the depth `depth`
  StereoMatches at_depth(const Keypoints& k, double depth) const {
    StereoMatches m = unmatched(k.size());
    for (size_t i = 0; i < k.size(); ++i) {
      m.depth[i] = static_cast<float>(depth);
      m.u_right[i] = k.keypoints[i].pt.x - static_cast<float>(cam.fx * cam.baseline / depth);
    }
    return m;
  }
};

std::vector<int> every_index(size_t n) {
  std::vector<int> all(n);
  for (size_t i = 0; i < n; ++i) all[i] = static_cast<int>(i);
  return all;
}

}  // namespace

TEST(DropMatchesPulledNearer, FarCarEdgeMatchesTakenByANearerCarAreDropped) {
  const FarCarScene s;
  const int n = static_cast<int>(s.near_car_edge.size());
  ASSERT_GE(n, 12);
  const std::vector<int> all = every_index(n);
  const StereoSearchOptions options;
  // the whole window's scan gives the car's depth to few of the keypoints beside the nearer car
  // (the scene does what it is for: most are rejected, some take the nearer car's depth)
  StereoMatches whole = unmatched(n);
  search_stereo(s.near_car_edge, s.pyramid_left, s.pyramid_right, s.cam, options, all, &whole);
  int at_car = 0, at_near = 0;
  for (int i = 0; i < n; ++i) {
    at_car += std::abs(whole.depth[i] - FarCarScene::kCarDepth) < 0.02 * FarCarScene::kCarDepth;
    at_near += std::abs(whole.depth[i] - FarCarScene::kNearCarDepth) < 0.05 * FarCarScene::kNearCarDepth;
  }
  EXPECT_LT(at_car, n / 4);
  EXPECT_GT(at_near, 0);
  // every such keypoint given the nearer car's depth: dropped, its own pixels match farther
  StereoMatches m = s.at_depth(s.near_car_edge, FarCarScene::kNearCarDepth);
  InstanceSupportReport r = drop_matches_pulled_nearer(s.near_car_edge, s.pyramid_left, s.pyramid_right,
                                                       s.cam, options, all, s.instances, 0.3f,
                                                       20.0f, 0.5f, &m);
  std::cout << "edge beside the nearer car: " << at_car << " / " << at_near << " of " << n << " at the far / nearer car's depth; " << r.num_rescanned
            << " scanned on the car's pixels, " << r.num_dropped << " dropped\n";
  EXPECT_EQ(r.num_rescanned, n);
  EXPECT_GE(r.num_dropped, n * 3 / 4);
  for (int i = 0; i < n; ++i) EXPECT_TRUE(m.depth[i] < 0 || m.depth[i] == FarCarScene::kNearCarDepth);
  // nearer than min_depth: not checked
  StereoMatches near = s.at_depth(s.near_car_edge, FarCarScene::kNearCarDepth);
  r = drop_matches_pulled_nearer(s.near_car_edge, s.pyramid_left, s.pyramid_right, s.cam, options, all,
                                 s.instances, 0.3f, 30.0f, 0.5f, &near);
  EXPECT_EQ(r.num_rescanned, 0);
  EXPECT_EQ(near.depth, s.at_depth(s.near_car_edge, FarCarScene::kNearCarDepth).depth);
}

TEST(DropMatchesPulledNearer, MatchesAtTheirDepthOrFartherAndWindowsBesideNoOtherInstanceAreKept) {
  const FarCarScene s;
  const StereoSearchOptions options;
  const std::vector<int> all = every_index(s.near_car_edge.size());
  // the car's true depth beside the nearer car: kept (its own pixels agree within 0.5 px)
  StereoMatches m = s.at_depth(s.near_car_edge, FarCarScene::kCarDepth);
  InstanceSupportReport r = drop_matches_pulled_nearer(s.near_car_edge, s.pyramid_left, s.pyramid_right,
                                                       s.cam, options, all, s.instances, 0.3f,
                                                       20.0f, 0.5f, &m);
  EXPECT_EQ(r.num_rescanned, static_cast<int>(s.near_car_edge.size()));
  EXPECT_LE(r.num_dropped, static_cast<int>(s.near_car_edge.size()) / 10);
  // a farther match (the wall's depth) there: not the check's business, kept
  StereoMatches far = s.at_depth(s.near_car_edge, 60.0);
  r = drop_matches_pulled_nearer(s.near_car_edge, s.pyramid_left, s.pyramid_right, s.cam, options, all,
                                 s.instances, 0.3f, 20.0f, 0.5f, &far);
  EXPECT_EQ(r.num_dropped, 0);
  // windows beside the wall (no instance) or wholly on the car are not scanned, whatever their
  // depth
  for (const Keypoints* k : {&s.wall_edge, &s.middle}) {
    StereoMatches near = s.at_depth(*k, FarCarScene::kNearCarDepth);
    r = drop_matches_pulled_nearer(*k, s.pyramid_left, s.pyramid_right, s.cam, options,
                                   every_index(k->size()), s.instances, 0.3f, 20.0f, 0.5f, &near);
    EXPECT_EQ(r.num_rescanned, 0);
    EXPECT_EQ(near.depth, s.at_depth(*k, FarCarScene::kNearCarDepth).depth);
  }
  // a marked occluder (a negative id: a tree trunk's pixels) beside the window counts as another
  // object: the wall's edge is then scanned, and its true depth kept
  cv::Mat marked = s.instances.clone();
  marked.setTo(-2, s.instances == 0);
  StereoMatches wall = s.at_depth(s.wall_edge, FarCarScene::kCarDepth);
  r = drop_matches_pulled_nearer(s.wall_edge, s.pyramid_left, s.pyramid_right, s.cam, options,
                                 every_index(s.wall_edge.size()), marked, 0.3f, 20.0f, 0.5f, &wall);
  EXPECT_EQ(r.num_rescanned, static_cast<int>(s.wall_edge.size()));
  EXPECT_LE(r.num_dropped, static_cast<int>(s.wall_edge.size()) / 10);
  // bad input
  EXPECT_THROW(drop_matches_pulled_nearer(s.near_car_edge, s.pyramid_left, s.pyramid_right, s.cam, options,
                                          all, s.instances, 0.3f, 20.0f, -1.0f, &m),
               std::invalid_argument);
  EXPECT_THROW(drop_matches_pulled_nearer(s.near_car_edge, s.pyramid_left, s.pyramid_right, s.cam, options,
                                          all, cv::Mat(s.instances.size(), CV_8UC1), 0.3f, 20.0f, 0.5f, &m),
               std::invalid_argument);
}

