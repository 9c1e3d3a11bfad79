#include "features/orb.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <queue>
#include <stdexcept>
#include <string>

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

// Quadtree over the candidates of one level: regions are split breadth-first (largest regions
// first, the most populated first among equals) until there are `wanted` non-empty regions or
// none can be split; each region then keeps its strongest corner. Returns indices into cand.
struct QuadNode {
  float x0, y0, x1, y1;
  int begin, end;  // range in the index array
  int depth;
  int count() const { return end - begin; }
};

struct SplitOrder {  // priority_queue top = shallowest, then most populated
  bool operator()(const QuadNode& a, const QuadNode& b) const {
    if (a.depth != b.depth) return a.depth > b.depth;
    return a.count() < b.count();
  }
};

std::vector<int> distribute(const std::vector<cv::KeyPoint>& cand, const cv::Rect2f& region,
                            int wanted) {
  std::vector<int> keep;
  if (wanted <= 0 || cand.empty()) return keep;
  std::vector<int> idx(cand.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);

  std::vector<QuadNode> leaves;  // regions that cannot or need not be split
  std::priority_queue<QuadNode, std::vector<QuadNode>, SplitOrder> open;
  auto add = [&](const QuadNode& n) {
    if (n.count() == 0) return;
    const bool splittable = n.count() > 1 && (n.x1 - n.x0 > 1.0f || n.y1 - n.y0 > 1.0f);
    if (splittable) open.push(n); else leaves.push_back(n);
  };

  // Roots: about square columns over the region, so that splits give square cells.
  const int roots = std::max(1, static_cast<int>(std::lround(region.width / region.height)));
  {
    int begin = 0;
    const float w = region.width / roots;
    for (int r = 0; r < roots; ++r) {
      const float x0 = region.x + r * w, x1 = (r + 1 == roots) ? region.x + region.width : x0 + w;
      auto mid = std::partition(idx.begin() + begin, idx.end(),
                                [&](int i) { return cand[i].pt.x < x1 || r + 1 == roots; });
      const int end = static_cast<int>(mid - idx.begin());
      add({x0, region.y, x1, region.y + region.height, begin, end, 0});
      begin = end;
    }
  }

  auto regions = [&] { return static_cast<int>(open.size() + leaves.size()); };
  while (!open.empty() && regions() < wanted) {
    const QuadNode n = open.top();
    open.pop();
    const float mx = 0.5f * (n.x0 + n.x1), my = 0.5f * (n.y0 + n.y1);
    auto first = idx.begin() + n.begin, last = idx.begin() + n.end;
    auto split_x = std::partition(first, last, [&](int i) { return cand[i].pt.x < mx; });
    auto split_l = std::partition(first, split_x, [&](int i) { return cand[i].pt.y < my; });
    auto split_r = std::partition(split_x, last, [&](int i) { return cand[i].pt.y < my; });
    const int a = n.begin, b = static_cast<int>(split_l - idx.begin()),
              c = static_cast<int>(split_x - idx.begin()),
              d = static_cast<int>(split_r - idx.begin()), e = n.end;
    const int depth = n.depth + 1;
    add({n.x0, n.y0, mx, my, a, b, depth});
    add({n.x0, my, mx, n.y1, b, c, depth});
    add({mx, n.y0, n.x1, my, c, d, depth});
    add({mx, my, n.x1, n.y1, d, e, depth});
  }
  while (!open.empty()) {
    leaves.push_back(open.top());
    open.pop();
  }

  keep.reserve(leaves.size());
  for (const QuadNode& n : leaves) {
    int best = idx[n.begin];
    for (int k = n.begin + 1; k < n.end; ++k)
      if (cand[idx[k]].response > cand[best].response) best = idx[k];
    keep.push_back(best);
  }
  if (static_cast<int>(keep.size()) > wanted) {  // the last split may overshoot by up to 3
    std::nth_element(keep.begin(), keep.begin() + wanted, keep.end(),
                     [&](int i, int j) { return cand[i].response > cand[j].response; });
    keep.resize(wanted);
  }
  std::sort(keep.begin(), keep.end());  // deterministic, roughly raster order
  return keep;
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
  const bool masked = !mask.empty();
  if (masked && (mask.type() != CV_8UC1 || mask.size() != gray.size()))
    throw std::invalid_argument("OrbExtractor::extract: mask must be CV_8UC1 of the image size");

  Keypoints out;
  out.scale_factor = options_.scale_factor;
  out.pyramid = build_pyramid(gray, options_.scale_factor, options_.num_levels);
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
  const cv::Size size0 = gray.size();
  std::vector<cv::KeyPoint> cand, cell_kps, chosen;
  int carry = 0;  // keypoints a level could not supply are asked from the next one

  for (int l = 0; l < static_cast<int>(out.pyramid.size()); ++l) {
    const cv::Mat& img = out.pyramid[l];
    const int wanted = per_level_[l] + carry;
    carry = wanted;
    const cv::Rect region(kEdgeBorder, kEdgeBorder, img.cols - 2 * kEdgeBorder,
                          img.rows - 2 * kEdgeBorder);
    if (wanted <= 0 || region.width <= 0 || region.height <= 0) continue;

    const float sx = static_cast<float>(size0.width) / img.cols;
    const float sy = static_cast<float>(size0.height) / img.rows;
    auto allowed = [&](const cv::Point2f& p) {
      if (!region.contains(cv::Point(cvRound(p.x), cvRound(p.y)))) return false;
      if (!masked) return true;
      const int u = std::clamp(cvRound((p.x + 0.5f) * sx - 0.5f), 0, size0.width - 1);
      const int v = std::clamp(cvRound((p.y + 0.5f) * sy - 0.5f), 0, size0.height - 1);
      return mask.at<std::uint8_t>(v, u) != 0;
    };

    // FAST at the normal threshold over the whole level, then the grid.
    // FAST tests a ring of radius 3: a 3-px margin around the region is all it needs.
    const cv::Rect scan(region.x - 3, region.y - 3, region.width + 6, region.height + 6);
    cand.clear();
    cv::FAST(img(scan), cand, options_.fast_threshold, true);
    for (cv::KeyPoint& k : cand) k.pt += cv::Point2f(static_cast<float>(scan.x), static_cast<float>(scan.y));
    cand.erase(std::remove_if(cand.begin(), cand.end(),
                              [&](const cv::KeyPoint& k) { return !allowed(k.pt); }),
               cand.end());
    const int cols = std::max(1, static_cast<int>(std::lround(
                                     static_cast<double>(region.width) / options_.cell_size)));
    const int rows = std::max(1, static_cast<int>(std::lround(
                                     static_cast<double>(region.height) / options_.cell_size)));
    const float cw = static_cast<float>(region.width) / cols;
    const float ch = static_cast<float>(region.height) / rows;
    std::vector<int> per_cell(static_cast<std::size_t>(cols) * rows, 0);
    for (const cv::KeyPoint& k : cand) {
      const int cx = std::min(cols - 1, static_cast<int>((k.pt.x - region.x) / cw));
      const int cy = std::min(rows - 1, static_cast<int>((k.pt.y - region.y) / ch));
      ++per_cell[static_cast<std::size_t>(cy) * cols + cx];
    }
    // Cells without a corner: retry with the low threshold (FAST needs 3 px around a pixel).
    cv::Mat level_mask;
    if (masked) cv::resize(mask, level_mask, img.size(), 0, 0, cv::INTER_NEAREST);
    for (int cy = 0; cy < rows; ++cy) {
      for (int cx = 0; cx < cols; ++cx) {
        if (per_cell[static_cast<std::size_t>(cy) * cols + cx] > 0) continue;
        const int x0 = region.x + static_cast<int>(std::lround(cx * cw));
        const int x1 = region.x + static_cast<int>(std::lround((cx + 1) * cw));
        const int y0 = region.y + static_cast<int>(std::lround(cy * ch));
        const int y1 = region.y + static_cast<int>(std::lround((cy + 1) * ch));
        const cv::Rect cell(x0, y0, x1 - x0, y1 - y0);
        if (cell.area() <= 0) continue;
        if (masked && cv::countNonZero(level_mask(cell)) == 0) continue;
        const cv::Rect roi = cv::Rect(x0 - 3, y0 - 3, cell.width + 6, cell.height + 6) &
                             cv::Rect(0, 0, img.cols, img.rows);
        cell_kps.clear();
        cv::FAST(img(roi), cell_kps, options_.min_fast_threshold, true);
        for (cv::KeyPoint k : cell_kps) {
          k.pt.x += roi.x;
          k.pt.y += roi.y;
          if (cell.contains(cv::Point(cvRound(k.pt.x), cvRound(k.pt.y))) && allowed(k.pt))
            cand.push_back(k);
        }
      }
    }

    const std::vector<int> keep = distribute(cand, cv::Rect2f(region), wanted);
    chosen.clear();
    chosen.reserve(keep.size());
    for (int i : keep) {
      cv::KeyPoint k = cand[i];
      k.octave = 0;  // level-local for cv::ORB::compute
      k.size = static_cast<float>(kPatchSize);
      k.class_id = -1;
      k.angle = centroid_angle(img, cvRound(k.pt.x), cvRound(k.pt.y), circle_half_width_);
      chosen.push_back(k);
    }
    if (chosen.empty()) continue;
    cv::Mat desc;
    brief->compute(img, chosen, desc);  // drops nothing: every keypoint is >= 19 px inside
    if (desc.rows != static_cast<int>(chosen.size()))
      throw std::logic_error("OrbExtractor: descriptor count differs from keypoint count");
    carry = wanted - static_cast<int>(chosen.size());

    for (cv::KeyPoint k : chosen) {
      k.pt = cv::Point2f((k.pt.x + 0.5f) * sx - 0.5f, (k.pt.y + 0.5f) * sy - 0.5f);
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
