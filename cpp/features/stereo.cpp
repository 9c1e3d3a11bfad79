#include "features/stereo.hpp"

#include "features/disparity_window.hpp"
#include "features/sad.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>

namespace twistslam::features {

namespace {

void check_options(const StereoOptions& o) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("StereoOptions: " + what);
  };
  if (o.max_hamming < 0 || o.max_hamming > 256) fail("max_hamming must be in [0, 256]");
  // Upper bounds keep the float-to-int conversions of the search bands defined.
  if (!(o.row_radius >= 0 && o.row_radius <= 64)) fail("row_radius must be in [0, 64] px");
  if (o.octave_tolerance < 0) fail("octave_tolerance must be >= 0");
  if (o.patch_radius < 1 || o.patch_radius > 15) fail("patch_radius must be in [1, 15]");
  if (o.patch_half_height < 0 || o.patch_half_height > 15)
    fail("patch_half_height must be in [0, 15]");
  if (o.refine_range < 1 || o.refine_range > 32) fail("refine_range must be in [1, 32]");
  if (!(o.min_depth > 0) || !(o.max_depth > o.min_depth) || !(o.max_depth <= 1e4))
    fail("need 0 < min_depth < max_depth <= 10000 m");
  if (!(o.outlier_factor > 0)) fail("outlier_factor must be > 0");
  if (!(o.right_features_factor > 0) || !(o.right_features_factor <= 16))
    fail("right_features_factor must be in (0, 16]");
}

void check_keypoints(const Keypoints& k, const char* which) {
  if (k.descriptors.rows != static_cast<int>(k.keypoints.size()) ||
      (!k.keypoints.empty() &&
       (k.descriptors.cols != kDescriptorBytes || k.descriptors.type() != CV_8UC1)))
    throw std::invalid_argument(std::string("match_stereo: ") + which +
                                " descriptors must be N x 32 CV_8U, one row per keypoint");
}

// The pyramid of k if it was built on this very image, otherwise a new one.
std::vector<cv::Mat> pyramid_for(const Keypoints& k, const cv::Mat& gray, int levels) {
  if (static_cast<int>(k.pyramid.size()) >= levels && k.pyramid[0].data == gray.data &&
      k.pyramid[0].size() == gray.size())
    return k.pyramid;
  return build_pyramid(gray, k.scale_factor, levels);
}

}  // namespace

std::size_t StereoMatches::num_matched() const {
  return static_cast<std::size_t>(
      std::count_if(depth.begin(), depth.end(), [](float z) { return z > 0; }));
}

StereoMatches match_stereo(const Keypoints& left, const Keypoints& right,
                           const cv::Mat& gray_left, const cv::Mat& gray_right,
                           const geometry::StereoCamera& camera, const StereoOptions& options) {
  check_options(options);
  if (gray_left.empty() || gray_right.empty())
    throw std::invalid_argument("match_stereo: empty image");
  if (gray_left.type() != CV_8UC1 || gray_right.type() != CV_8UC1)
    throw std::invalid_argument("match_stereo: expected CV_8UC1 images (see to_gray)");
  if (gray_left.size() != gray_right.size())
    throw std::invalid_argument("match_stereo: left and right images differ in size");
  if (!(camera.baseline > 0) || !(camera.fx > 0))
    throw std::invalid_argument("match_stereo: the camera needs fx > 0 and a positive baseline");
  if (left.scale_factor != right.scale_factor)
    throw std::invalid_argument("match_stereo: left and right keypoints come from pyramids "
                                "with different scale factors");
  check_keypoints(left, "left");
  check_keypoints(right, "right");

  const int N = static_cast<int>(left.size());
  StereoMatches result;
  result.u_right.assign(N, -1.0f);
  result.depth.assign(N, -1.0f);
  if (N == 0 || right.empty()) return result;

  int levels = 1;
  for (const auto& k : left.keypoints) levels = std::max(levels, k.octave + 1);
  for (const auto& k : right.keypoints) levels = std::max(levels, k.octave + 1);
  const std::vector<cv::Mat> pyr_left = pyramid_for(left, gray_left, levels);
  const std::vector<cv::Mat> pyr_right = pyramid_for(right, gray_right, levels);
  if (static_cast<int>(pyr_left.size()) < levels || static_cast<int>(pyr_right.size()) < levels)
    throw std::invalid_argument("match_stereo: keypoint octaves exceed the image's pyramid");
  const cv::Size size0 = gray_left.size();

  const DisparityWindow window = disparity_window(camera, options.min_depth, options.max_depth);
  const double fb = camera.fx * camera.baseline;  // depth = fb / (disparity + offset)
  const float offset = static_cast<float>(camera.disparity_offset);
  const float min_disparity = window.min_disparity, max_disparity = window.max_disparity;
  const float dv_per_disparity = window.dv_per_disparity;
  const float dv_max = dv_per_disparity *
                       std::min(max_disparity, static_cast<float>(size0.width));

  // Right keypoints by row: each one is listed on every row within its band (widened on one
  // side by the largest vertical offset), sorted by column (compressed rows, no per-row
  // allocation). Candidates are then checked against the row predicted for their disparity.
  const int H = size0.height;
  const int M = static_cast<int>(right.size());
  std::vector<int> order(M);
  for (int j = 0; j < M; ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return right.keypoints[a].pt.x < right.keypoints[b].pt.x;
  });
  auto band = [&](const cv::KeyPoint& k, int& r0, int& r1) {
    const float scale = static_cast<float>(size0.height) / pyr_right[k.octave].rows;
    const float r = options.row_radius * scale;
    r0 = std::max(0, static_cast<int>(std::floor(k.pt.y - r - std::max(0.0f, dv_max))));
    r1 = std::min(H - 1, static_cast<int>(std::ceil(k.pt.y + r + std::max(0.0f, -dv_max))));
  };
  std::vector<int> row_start(H + 1, 0);
  for (int j : order) {
    int r0, r1;
    band(right.keypoints[j], r0, r1);
    for (int r = r0; r <= r1; ++r) ++row_start[r + 1];
  }
  for (int r = 0; r < H; ++r) row_start[r + 1] += row_start[r];
  std::vector<int> row_entries(row_start[H]);
  {
    std::vector<int> fill(row_start.begin(), row_start.end() - 1);
    for (int j : order) {
      int r0, r1;
      band(right.keypoints[j], r0, r1);
      for (int r = r0; r <= r1; ++r) row_entries[fill[r]++] = j;
    }
  }

  std::vector<float> cost(N, -1.0f);
  const int half_width = options.patch_radius, half_height = options.patch_half_height;

  auto match_range = [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const cv::KeyPoint& kl = left.keypoints[i];
      const int row = cvRound(kl.pt.y);
      if (row < 0 || row >= H) continue;
      const int o = kl.octave;
      const float scale = static_cast<float>(size0.width) / pyr_left[o].cols;
      // Column window of the descriptor search; one level pixel of slack each side (the
      // refined disparity is checked against the exact range below).
      const float u_min = kl.pt.x - max_disparity - scale;
      const float u_max = kl.pt.x - min_disparity + scale;
      const int* first = row_entries.data() + row_start[row];
      const int* last = row_entries.data() + row_start[row + 1];
      first = std::lower_bound(first, last, u_min, [&](int j, float u) {
        return right.keypoints[j].pt.x < u;
      });
      const std::uint8_t* dl = left.descriptors.ptr<std::uint8_t>(i);
      int best_dist = options.max_hamming + 1, best = -1;
      for (const int* it = first; it != last; ++it) {
        const cv::KeyPoint& kr = right.keypoints[*it];
        if (kr.pt.x > u_max) break;
        if (std::abs(kr.octave - o) > options.octave_tolerance) continue;
        const float v_expected = kl.pt.y + dv_per_disparity * (kl.pt.x - kr.pt.x);
        const float band = options.row_radius * static_cast<float>(size0.height) /
                           static_cast<float>(pyr_right[kr.octave].rows);
        if (std::abs(kr.pt.y - v_expected) > band) continue;
        const int dist = descriptor_distance(dl, right.descriptors.ptr<std::uint8_t>(*it));
        if (dist < best_dist) {
          best_dist = dist;
          best = *it;
        }
      }
      if (best < 0) continue;

      // Sub-pixel column on the left keypoint's level.
      const cv::Mat& L = pyr_left[o];
      const cv::Mat& R = pyr_right[o];
      const cv::Point2f pl = image_to_level(kl.pt, size0, L.size());
      const cv::Point2f pr = image_to_level(right.keypoints[best].pt, size0, R.size());
      // Vertical offset of the match predicted from the descriptor disparity (the two cameras
      // of a KITTI pair sit at slightly different heights), in level pixels.
      const float disparity0 = kl.pt.x - right.keypoints[best].pt.x;
      const float level_sy = static_cast<float>(size0.height) / L.rows;
      const float dy = dv_per_disparity * disparity0 / level_sy;
      const SadRefined ref = refine_sad(L, R, cvRound(pl.x), cvRound(pl.y), cvRound(pr.x), dy,
                                     half_width, half_height, options.refine_range);
      if (!ref.ok) continue;
      // The left window is centred on the rounded level pixel: shift by the rounding.
      const float u_level = ref.u_level + (pl.x - cvRound(pl.x));
      const float u_right = (u_level + 0.5f) * scale - 0.5f;
      const float disparity = kl.pt.x - u_right;
      if (!(disparity >= min_disparity && disparity <= max_disparity)) continue;
      result.u_right[i] = u_right;
      result.depth[i] = static_cast<float>(fb / (disparity + offset));
      cost[i] = ref.cost;
    }
  };
  cv::parallel_for_(cv::Range(0, N), match_range, 2.0);

  // Drop matches whose SAD is far above the median of this frame.
  std::vector<float> costs;
  costs.reserve(N);
  for (float c : cost)
    if (c >= 0) costs.push_back(c);
  if (!costs.empty()) {
    auto mid = costs.begin() + costs.size() / 2;
    std::nth_element(costs.begin(), mid, costs.end());
    const float limit = options.outlier_factor * *mid;
    for (int i = 0; i < N; ++i) {
      if (cost[i] > limit) {
        result.u_right[i] = -1.0f;
        result.depth[i] = -1.0f;
      }
    }
  }
  return result;
}

StereoFeatures extract_and_match(const OrbExtractor& extractor, const cv::Mat& gray_left,
                                 const cv::Mat& gray_right, const geometry::StereoCamera& camera,
                                 const StereoOptions& options, const cv::Mat& mask_left) {
  if (gray_left.size() != gray_right.size())
    throw std::invalid_argument("extract_and_match: left and right images differ in size");
  check_options(options);
  OrbOptions right_options = extractor.options();
  right_options.num_features = static_cast<int>(
      std::lround(right_options.num_features * options.right_features_factor));
  const OrbExtractor right_extractor(right_options);
  using clock = std::chrono::steady_clock;
  StereoFeatures out;
  const auto t0 = clock::now();
  std::exception_ptr right_error;
  std::thread right_worker([&] {
    try {
      out.right = right_extractor.extract(gray_right);
    } catch (...) {
      right_error = std::current_exception();
    }
  });
  std::exception_ptr left_error;
  try {
    out.left = extractor.extract(gray_left, mask_left);
  } catch (...) {
    left_error = std::current_exception();
  }
  right_worker.join();
  if (left_error) std::rethrow_exception(left_error);
  if (right_error) std::rethrow_exception(right_error);
  const auto t1 = clock::now();
  out.matches = match_stereo(out.left, out.right, gray_left, gray_right, camera, options);
  const auto t2 = clock::now();
  out.extract_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  out.match_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
  return out;
}

}  // namespace twistslam::features
