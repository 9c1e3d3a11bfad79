#include "features/orb.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "features/orb_quadtree.hpp"
#include "options/option_range.hpp"

namespace twistslam::features {

namespace {

constexpr int kCircleRadius = kPatchSize / 2;  // 15: intensity-centroid disc

// Orientation of the intensity centroid of the disc of radius 15 around (x, y), degrees.
float centroid_angle(const cv::Mat& img, int x, int y, const std::vector<int>& half_width) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(img.step1());
  const std::uint8_t* c = img.ptr<std::uint8_t>(y) + x;
  int m10 = 0, m01 = 0;
  for (int u = -kCircleRadius; u <= kCircleRadius; ++u) m10 += u * c[u];
  for (int v = 1; v <= kCircleRadius; ++v) {
    const std::uint8_t* below = c + v * step;
    const std::uint8_t* above = c - v * step;
    const int w = half_width[v];
    int row_difference = 0;
    for (int u = -w; u <= w; ++u) {
      const int b = below[u], a = above[u];
      row_difference += b - a;
      m10 += u * (a + b);
    }
    m01 += v * row_difference;
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

// Where keypoints of one pyramid level may lie: inside the border region, and where the
// (level-0) mask, if any, is non-zero.
struct LevelArea {
  cv::Rect region;       // level pixels at least kEdgeBorder from the level's edges
  cv::Size level0;       // size of pyramid level 0
  float sx, sy;          // level-0 px per level px
  const cv::Mat& mask;   // level-0 CV_8UC1 or empty
  cv::Mat level_mask;    // the mask at the level's size (nearest), empty without a mask
  // Level pixels where an allowed corner may lie: the region, or with a mask its part around
  // the mask's bounding box (FAST is run there only; the quadtree still spans the region).
  cv::Rect search;

  LevelArea(const cv::Mat& img, const cv::Size& size0, const cv::Mat& mask0,
            const cv::Rect& mask_box0)
      : region(kEdgeBorder, kEdgeBorder, img.cols - 2 * kEdgeBorder, img.rows - 2 * kEdgeBorder),
        level0(size0),
        sx(static_cast<float>(size0.width) / img.cols),
        sy(static_cast<float>(size0.height) / img.rows),
        mask(mask0),
        search(region) {
    if (mask.empty() || region.width <= 0 || region.height <= 0) return;
    cv::resize(mask, level_mask, img.size(), 0, 0, cv::INTER_NEAREST);
    // the level-0 box in level pixels (x_l = (x_0 + 0.5) / s - 0.5), widened by 2 px for the
    // rounding of allows() and of the nearest-neighbour level mask
    const int x0 = static_cast<int>(std::floor((mask_box0.x + 0.5f) / sx - 0.5f)) - 2;
    const int y0 = static_cast<int>(std::floor((mask_box0.y + 0.5f) / sy - 0.5f)) - 2;
    const int x1 = static_cast<int>(std::ceil((mask_box0.br().x - 0.5f) / sx - 0.5f)) + 2;
    const int y1 = static_cast<int>(std::ceil((mask_box0.br().y - 0.5f) / sy - 0.5f)) + 2;
    search = region & cv::Rect(x0, y0, std::max(0, x1 - x0), std::max(0, y1 - y0));
  }
  cv::Point2f to_level0(const cv::Point2f& p) const {
    return {(p.x + 0.5f) * sx - 0.5f, (p.y + 0.5f) * sy - 0.5f};
  }
  bool allows(const cv::Point2f& p) const {
    if (!region.contains(cv::Point(cvRound(p.x), cvRound(p.y)))) return false;
    if (mask.empty()) return true;
    const cv::Point2f q = to_level0(p);
    const int u = std::clamp(cvRound(q.x), 0, level0.width - 1);
    const int v = std::clamp(cvRound(q.y), 0, level0.height - 1);
    return mask.at<std::uint8_t>(v, u) != 0;
  }
};

// FAST corners (with non-maximum suppression) of `img` inside `roi`, in level coordinates.
void fast_in(const cv::Mat& img, const cv::Rect& roi, int threshold, std::vector<cv::KeyPoint>* out) {
  out->clear();
  cv::FAST(img(roi), *out, threshold, true);
  const cv::Point2f offset(static_cast<float>(roi.x), static_cast<float>(roi.y));
  for (cv::KeyPoint& k : *out) k.pt += offset;
}

// Step 1: FAST at the normal threshold over the level's search area; the allowed corners.
void detect_corners(const cv::Mat& img, const LevelArea& area, int threshold,
                    std::vector<cv::KeyPoint>* candidates) {
  candidates->clear();
  const cv::Rect& r = area.search;
  if (r.width <= 0 || r.height <= 0) return;
  // FAST tests a ring of radius 3 (so it scores the pixels of roi 3 px inside its edges), and
  // its non-maximum suppression compares each corner with its 8 neighbours: with 4 px around
  // r, the corners inside r are those of a FAST over the whole region (3 px around it).
  const cv::Rect& g = area.region;
  const cv::Rect roi = cv::Rect(r.x - 4, r.y - 4, r.width + 8, r.height + 8) &
                       cv::Rect(g.x - 3, g.y - 3, g.width + 6, g.height + 6);
  fast_in(img, roi, threshold, candidates);
  candidates->erase(std::remove_if(candidates->begin(), candidates->end(),
                                   [&](const cv::KeyPoint& k) { return !area.allows(k.pt); }),
                    candidates->end());
}

// Step 2: grid cells of about cell_size px that step 1 left without a corner are searched
// again with the low threshold, so that low-contrast parts of the image contribute too.
void retry_empty_cells(const cv::Mat& img, const LevelArea& area, int cell_size,
                       int min_threshold, std::vector<cv::KeyPoint>* candidates) {
  const cv::Rect& region = area.region;
  const int cols = std::max(1, static_cast<int>(std::lround(static_cast<double>(region.width) / cell_size)));
  const int rows = std::max(1, static_cast<int>(std::lround(static_cast<double>(region.height) / cell_size)));
  const float cw = static_cast<float>(region.width) / cols;
  const float ch = static_cast<float>(region.height) / rows;
  std::vector<int> per_cell(static_cast<std::size_t>(cols) * rows, 0);
  for (const cv::KeyPoint& k : *candidates) {
    const int cx = std::min(cols - 1, static_cast<int>((k.pt.x - region.x) / cw));
    const int cy = std::min(rows - 1, static_cast<int>((k.pt.y - region.y) / ch));
    ++per_cell[static_cast<std::size_t>(cy) * cols + cx];
  }
  std::vector<cv::KeyPoint> cell_corners;
  for (int cy = 0; cy < rows; ++cy) {
    for (int cx = 0; cx < cols; ++cx) {
      if (per_cell[static_cast<std::size_t>(cy) * cols + cx] > 0) continue;
      const int x0 = region.x + static_cast<int>(std::lround(cx * cw));
      const int x1 = region.x + static_cast<int>(std::lround((cx + 1) * cw));
      const int y0 = region.y + static_cast<int>(std::lround(cy * ch));
      const int y1 = region.y + static_cast<int>(std::lround((cy + 1) * ch));
      const cv::Rect cell(x0, y0, x1 - x0, y1 - y0);
      if (cell.area() <= 0 || (cell & area.search).area() <= 0) continue;
      if (!area.level_mask.empty() && cv::countNonZero(area.level_mask(cell)) == 0) continue;
      // FAST needs 3 px around a pixel
      const cv::Rect roi = cv::Rect(x0 - 3, y0 - 3, cell.width + 6, cell.height + 6) &
                           cv::Rect(0, 0, img.cols, img.rows);
      fast_in(img, roi, min_threshold, &cell_corners);
      for (const cv::KeyPoint& k : cell_corners)
        if (cell.contains(cv::Point(cvRound(k.pt.x), cvRound(k.pt.y))) && area.allows(k.pt))
          candidates->push_back(k);
    }
  }
}

// Step 4 (after the quadtree of step 3): the kept candidates with their orientation, set up
// for cv::ORB::compute on this level (octave 0 there, the patch size of the level).
std::vector<cv::KeyPoint> oriented_keypoints(const cv::Mat& img,
                                             const std::vector<cv::KeyPoint>& candidates,
                                             const std::vector<int>& keep,
                                             const std::vector<int>& half_width) {
  std::vector<cv::KeyPoint> chosen;
  chosen.reserve(keep.size());
  for (int i : keep) {
    cv::KeyPoint k = candidates[i];
    k.octave = 0;  // level-local for cv::ORB::compute
    k.size = static_cast<float>(kPatchSize);
    k.class_id = -1;
    k.angle = centroid_angle(img, cvRound(k.pt.x), cvRound(k.pt.y), half_width);
    chosen.push_back(k);
  }
  return chosen;
}

// Extra level pixels around a level's keypoints kept when describing them: the rotated
// 31x31 BRIEF pattern reaches ~19 px from its centre (kEdgeBorder), so 32 px keep every
// tested pixel inside the crop, where cv::ORB::compute smooths it.
constexpr int kDescriptorCropMargin = 32;

// Rotated BRIEF descriptors of `keypoints` (level coordinates) by cv::ORB::compute on the
// part of the level around them. compute() pads and smooths (7x7 Gaussian) all of the image
// it is given, which for the few keypoints of an object mask cost more than the descriptors;
// a crop gives the same bits: OpenCV pads a crop with its parent image's own pixels (the
// image's edges, where they lie inside the padding, as for the whole image) and its 8-bit
// Gaussian is bit-exact, so every pixel the pattern reads is smoothed as in the whole level
// (tests/cpp/features/test_orb.cpp checks the descriptors against the whole-level ones).
cv::Mat describe(const cv::Ptr<cv::ORB>& brief, const cv::Mat& img,
                 const std::vector<cv::KeyPoint>& keypoints) {
  float x0 = keypoints.front().pt.x, x1 = x0, y0 = keypoints.front().pt.y, y1 = y0;
  for (const cv::KeyPoint& k : keypoints) {
    x0 = std::min(x0, k.pt.x), x1 = std::max(x1, k.pt.x);
    y0 = std::min(y0, k.pt.y), y1 = std::max(y1, k.pt.y);
  }
  // even offsets: a shifted coordinate rounds (half to even, cvRound) as the unshifted one
  const int left = std::max(0, static_cast<int>(std::floor(x0)) - kDescriptorCropMargin) & ~1;
  const int top = std::max(0, static_cast<int>(std::floor(y0)) - kDescriptorCropMargin) & ~1;
  const int right = std::min(img.cols, static_cast<int>(std::ceil(x1)) + kDescriptorCropMargin + 1);
  const int bottom = std::min(img.rows, static_cast<int>(std::ceil(y1)) + kDescriptorCropMargin + 1);
  const cv::Rect crop(left, top, right - left, bottom - top);
  std::vector<cv::KeyPoint> local = keypoints;
  for (cv::KeyPoint& k : local) k.pt -= cv::Point2f(static_cast<float>(left), static_cast<float>(top));
  cv::Mat desc;
  brief->compute(img(crop), local, desc);  // drops nothing: every keypoint is >= 19 px inside
  if (desc.rows != static_cast<int>(keypoints.size()))
    throw std::logic_error("OrbExtractor: descriptor count differs from keypoint count");
  return desc;
}

}  // namespace

void check_options(const OrbOptions& o) {
  try {
    options::check_ranges(o, "");
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("OrbOptions: ") + e.what());
  }
  if (o.min_fast_threshold > o.fast_threshold)
    throw std::invalid_argument("OrbOptions: min_fast_threshold (" +
                                std::to_string(o.min_fast_threshold) +
                                ") must not exceed fast_threshold (" +
                                std::to_string(o.fast_threshold) + ")");
}

std::vector<cv::Mat> build_pyramid(const cv::Mat& gray, float scale_factor, int num_levels) {
  std::vector<cv::Mat> levels;
  if (gray.empty()) return levels;
  levels.reserve(num_levels);
  levels.push_back(gray);
  for (int l = 1; l < num_levels; ++l) {
    const double s = std::pow(static_cast<double>(scale_factor), l);
    const cv::Size size(cvRound(gray.cols / s), cvRound(gray.rows / s));
    if (size.width <= 2 * kEdgeBorder || size.height <= 2 * kEdgeBorder) break;
    cv::Mat next;
    cv::resize(levels.back(), next, size, 0, 0, cv::INTER_LINEAR);
    levels.push_back(next);
  }
  return levels;
}

OrbExtractor::OrbExtractor(const OrbOptions& options) : options_(options) {
  check_options(options_);
  const int L = options_.num_levels;
  scale_.resize(L);
  inv_scale_.resize(L);
  sigma2_.resize(L);
  inv_sigma2_.resize(L);
  for (int l = 0; l < L; ++l) {
    const double s = std::pow(static_cast<double>(options_.scale_factor), l);
    scale_[l] = static_cast<float>(s);
    inv_scale_[l] = static_cast<float>(1.0 / s);
    sigma2_[l] = static_cast<float>(s * s);
    inv_sigma2_[l] = static_cast<float>(1.0 / (s * s));
  }
  // Share of level l proportional to 1/s^l (the level's linear size), summing to num_features.
  per_level_.assign(L, 0);
  const double f = 1.0 / options_.scale_factor;
  double share = options_.num_features * (1.0 - f) / (1.0 - std::pow(f, L));
  int assigned = 0;
  for (int l = 0; l + 1 < L; ++l) {
    per_level_[l] = static_cast<int>(std::lround(share));
    assigned += per_level_[l];
    share *= f;
  }
  per_level_[L - 1] = std::max(0, options_.num_features - assigned);

  circle_half_width_.resize(kCircleRadius + 1);
  const double r = kCircleRadius + 0.5;
  for (int v = 0; v <= kCircleRadius; ++v)
    circle_half_width_[v] =
        std::min(kCircleRadius, static_cast<int>(std::floor(std::sqrt(r * r - v * v))));
}

Keypoints OrbExtractor::extract(const cv::Mat& gray, const cv::Mat& mask) const {
  if (gray.empty()) throw std::invalid_argument("OrbExtractor::extract: empty image");
  if (gray.type() != CV_8UC1)
    throw std::invalid_argument("OrbExtractor::extract: expected a CV_8UC1 image (see to_gray)");
  return extract_levels(build_pyramid(gray, options_.scale_factor, options_.num_levels), mask);
}

Keypoints OrbExtractor::extract_on_pyramid(const std::vector<cv::Mat>& pyramid,
                                           const cv::Mat& mask) const {
  if (pyramid.empty() || pyramid[0].empty())
    throw std::invalid_argument("OrbExtractor::extract_on_pyramid: empty pyramid");
  if (pyramid[0].type() != CV_8UC1)
    throw std::invalid_argument("OrbExtractor::extract_on_pyramid: expected CV_8UC1 levels");
  // the levels build_pyramid makes of this image with this extractor's options
  const cv::Mat& gray = pyramid[0];
  int levels = 1;
  for (int l = 1; l < options_.num_levels; ++l, ++levels) {
    const double s = std::pow(static_cast<double>(options_.scale_factor), l);
    const cv::Size size(cvRound(gray.cols / s), cvRound(gray.rows / s));
    if (size.width <= 2 * kEdgeBorder || size.height <= 2 * kEdgeBorder) break;
    if (l >= static_cast<int>(pyramid.size()) || pyramid[l].size() != size ||
        pyramid[l].type() != CV_8UC1)
      throw std::invalid_argument(
          "OrbExtractor::extract_on_pyramid: level " + std::to_string(l) +
          " is missing or not the level of scale_factor " + std::to_string(options_.scale_factor));
  }
  return extract_levels(std::vector<cv::Mat>(pyramid.begin(), pyramid.begin() + levels), mask);
}

Keypoints OrbExtractor::extract_levels(std::vector<cv::Mat> pyramid, const cv::Mat& mask) const {
  const cv::Size size0 = pyramid[0].size();
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != size0))
    throw std::invalid_argument("OrbExtractor::extract: mask must be CV_8UC1 of the image size");

  // the mask's non-zero pixels lie in this box (level 0); an all-zero mask gives an empty box
  const cv::Rect mask_box = mask.empty() ? cv::Rect(cv::Point(0, 0), size0) : cv::boundingRect(mask);
  Keypoints out;
  out.scale_factor = options_.scale_factor;
  out.pyramid = std::move(pyramid);
  if (options_.num_features == 0) {
    out.descriptors.create(0, kDescriptorBytes, CV_8U);
    return out;
  }

  // Descriptors: OpenCV's rotated BRIEF on one level at a time, with our keypoints and angles.
  cv::Ptr<cv::ORB> brief = cv::ORB::create(options_.num_features, options_.scale_factor, 1,
                                           kEdgeBorder, 0, 2, cv::ORB::FAST_SCORE, kPatchSize,
                                           options_.fast_threshold);
  std::vector<cv::Mat> level_descriptors;
  out.keypoints.reserve(options_.num_features);
  std::vector<cv::KeyPoint> candidates;
  int carry = 0;  // keypoints a level could not supply are asked from the next one

  for (int l = 0; l < static_cast<int>(out.pyramid.size()); ++l) {
    const cv::Mat& img = out.pyramid[l];
    const int wanted = per_level_[l] + carry;
    carry = wanted;
    if (wanted <= 0) continue;
    const LevelArea area(img, size0, mask, mask_box);
    if (area.region.width <= 0 || area.region.height <= 0) continue;

    detect_corners(img, area, options_.fast_threshold, &candidates);
    retry_empty_cells(img, area, options_.cell_size, options_.min_fast_threshold, &candidates);
    std::vector<cv::KeyPoint> chosen = oriented_keypoints(
        img, candidates, detail::distribute_keypoints(candidates, cv::Rect2f(area.region), wanted),
        circle_half_width_);
    if (chosen.empty()) continue;
    const cv::Mat desc = describe(brief, img, chosen);
    carry = wanted - static_cast<int>(chosen.size());

    for (cv::KeyPoint k : chosen) {
      k.pt = area.to_level0(k.pt);
      k.octave = l;
      k.size = kPatchSize * scale_[l];
      out.keypoints.push_back(k);
    }
    level_descriptors.push_back(desc);
  }
  if (level_descriptors.empty())
    out.descriptors.create(0, kDescriptorBytes, CV_8U);
  else
    cv::vconcat(level_descriptors, out.descriptors);
  return out;
}

cv::Mat to_gray(const cv::Mat& image, bool rgb) {
  if (image.empty()) throw std::invalid_argument("to_gray: empty image");
  cv::Mat gray;
  switch (image.type()) {
    case CV_8UC1:
      return image;
    case CV_8UC3:
      cv::cvtColor(image, gray, rgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
      return gray;
    case CV_8UC4:
      cv::cvtColor(image, gray, rgb ? cv::COLOR_RGBA2GRAY : cv::COLOR_BGRA2GRAY);
      return gray;
    default:
      throw std::invalid_argument("to_gray: expected an 8-bit image with 1, 3 or 4 channels");
  }
}

int descriptor_distance(const cv::Mat& a, const cv::Mat& b) {
  auto ok = [](const cv::Mat& m) {
    return m.type() == CV_8UC1 && m.total() == static_cast<std::size_t>(kDescriptorBytes) &&
           m.isContinuous();
  };
  if (!ok(a) || !ok(b))
    throw std::invalid_argument("descriptor_distance: expected two continuous 32-byte CV_8U rows");
  return descriptor_distance(a.ptr<std::uint8_t>(), b.ptr<std::uint8_t>());
}

}  // namespace twistslam::features
