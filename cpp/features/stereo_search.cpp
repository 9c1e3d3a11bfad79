#include "features/stereo_search.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "features/disparity_window.hpp"
#include "features/sad.hpp"

namespace twistslam::features {

void check_options(const StereoSearchOptions& o) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("StereoSearchOptions: " + what);
  };
  if (!(o.min_depth > 0) || !(o.max_depth > o.min_depth) || !(o.max_depth <= 1e4))
    fail("need 0 < min_depth < max_depth <= 10000 m");
  if (!(o.max_cost > 0)) fail("max_cost must be > 0");
  if (!(o.uniqueness > 0 && o.uniqueness <= 1)) fail("uniqueness must be in (0, 1]");
  if (o.patch_radius < 1 || o.patch_radius > kMaxSadHalfWidth) fail("patch_radius must be in [1, 15]");
  if (o.patch_half_height < 0 || o.patch_half_height > kMaxSadHalfHeight)
    fail("patch_half_height must be in [0, 15]");
}

namespace {

void check_arguments(const char* who, const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
                     const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
                     const StereoSearchOptions& options, const std::vector<int>& which,
                     const StereoMatches& matches) {
  check_options(options);
  auto fail = [who](const std::string& what) {
    throw std::invalid_argument(std::string(who) + ": " + what);
  };
  const int N = static_cast<int>(left.size());
  if (static_cast<int>(matches.u_right.size()) != N || static_cast<int>(matches.depth.size()) != N)
    fail("matches must have one entry per left keypoint");
  if (pyramid_left.empty() || pyramid_right.empty() || pyramid_left[0].size() != pyramid_right[0].size())
    fail("left and right pyramids missing or of different sizes");
  if (!(camera.baseline > 0) || !(camera.fx > 0)) fail("the camera needs fx > 0 and a positive baseline");
  for (int i : which) {
    if (i < 0 || i >= N) fail("keypoint index out of range");
    const int o = left.keypoints[i].octave;
    if (o < 0 || o >= static_cast<int>(pyramid_left.size()) || o >= static_cast<int>(pyramid_right.size()))
      fail("keypoint octave exceeds the pyramids");
  }
}

}  // namespace

namespace {

// The scan's geometry, fixed per frame.
struct ScanSetup {
  cv::Size size0;
  DisparityWindow window;
  double fb = 0;      // depth = fb / (disparity + offset)
  float offset = 0;
};

ScanSetup scan_setup(const cv::Size& size0, const geometry::StereoCamera& camera,
                     const StereoSearchOptions& options) {
  return {size0, disparity_window(camera, options.min_depth, options.max_depth),
          camera.fx * camera.baseline, static_cast<float>(camera.disparity_offset)};
}

// The depth of one left keypoint by a SAD scan over the disparity range on its level, refined
// to sub-pixel (with `support`: on the supported window pixels only); false when rejected.
bool scan_depth(const cv::KeyPoint& kl, const cv::Mat& L, const cv::Mat& R, const ScanSetup& g,
                const StereoSearchOptions& options, const std::uint8_t* support, float* u_right,
                float* depth) {
  // sub-pixel refinement around the scan's integer minimum: +-2 level px
  constexpr int kRefineRange = 2;
  const float scale = static_cast<float>(g.size0.width) / L.cols;
  const cv::Point2f pl = image_to_level(kl.pt, g.size0, L.size());
  const int xl = cvRound(pl.x), y = cvRound(pl.y);
  // right columns (level px) of the disparity range
  const int x_first = static_cast<int>(std::floor(pl.x - g.window.max_disparity / scale));
  const int x_last = static_cast<int>(std::ceil(pl.x - g.window.min_disparity / scale));
  const SadScan scan = scan_sad(L, R, xl, y, x_first, x_last, options.patch_radius,
                                options.patch_half_height, support);
  if (scan.best_column < 0 || !(scan.best_cost <= options.max_cost) ||
      !(scan.best_cost < options.uniqueness * scan.second_cost))
    return false;
  const float level_sy = static_cast<float>(g.size0.height) / L.rows;
  // the right row drifts with disparity (KITTI)
  const float dy = g.window.dv_per_disparity * (pl.x - scan.best_column) * scale / level_sy;
  const SadRefined ref = refine_sad(L, R, xl, y, scan.best_column, dy, options.patch_radius,
                                    options.patch_half_height, kRefineRange, support);
  if (!ref.ok) return false;
  const float u_level = ref.u_level + (pl.x - static_cast<float>(xl));
  const float u = (u_level + 0.5f) * scale - 0.5f;
  const float disparity = kl.pt.x - u;
  if (!(disparity >= g.window.min_disparity && disparity <= g.window.max_disparity)) return false;
  *u_right = u;
  *depth = static_cast<float>(g.fb / (disparity + g.offset));
  return true;
}

}  // namespace

int search_stereo(const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
                  const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
                  const StereoSearchOptions& options, const std::vector<int>& which,
                  StereoMatches* matches) {
  check_arguments("search_stereo", left, pyramid_left, pyramid_right, camera, options, which, *matches);
  const ScanSetup setup = scan_setup(pyramid_left[0].size(), camera, options);
  std::atomic<int> found{0};
  auto search_range = [&](const cv::Range& range) {
    for (int j = range.start; j < range.end; ++j) {
      const int i = which[j];
      const cv::KeyPoint& kl = left.keypoints[i];
      if (scan_depth(kl, pyramid_left[kl.octave], pyramid_right[kl.octave], setup, options, nullptr,
                     &matches->u_right[i], &matches->depth[i]))
        ++found;
    }
  };
  cv::parallel_for_(cv::Range(0, static_cast<int>(which.size())), search_range, 2.0);
  return found.load();
}

bool search_pixel_stereo(const cv::Mat& left, const cv::Mat& right,
                         const geometry::StereoCamera& camera, const StereoSearchOptions& options,
                         float u, float v, const std::uint8_t* support, float* u_right,
                         float* depth) {
  check_options(options);
  if (left.type() != CV_8UC1 || right.type() != CV_8UC1 || left.size() != right.size() || left.empty())
    throw std::invalid_argument("search_pixel_stereo: left and right must be 8-bit gray of one size");
  if (!(camera.baseline > 0) || !(camera.fx > 0))
    throw std::invalid_argument("search_pixel_stereo: the camera needs fx > 0 and a positive baseline");
  if (!std::isfinite(u) || !std::isfinite(v)) return false;
  const ScanSetup setup = scan_setup(left.size(), camera, options);
  const cv::KeyPoint at(cv::Point2f(u, v), 1.0f, -1.0f, 0.0f, /*octave=*/0);
  return scan_depth(at, left, right, setup, options, support, u_right, depth);
}

namespace {

// The window pixels of keypoint kl (on level L) that lie on instance `id` at level 0: support
// (row-major, 1 = on it); returns their count. *beside_other (when given): whether a pixel of
// the window lies on another instance or on a marked occluder (a negative id).
int instance_support(const cv::KeyPoint& kl, const cv::Mat& L, const ScanSetup& setup,
                     const StereoSearchOptions& options, const cv::Mat& instances, int id,
                     std::uint8_t* support, bool* beside_other = nullptr) {
  const int cols = 2 * options.patch_radius + 1, rows = 2 * options.patch_half_height + 1;
  const cv::Point2f pl = image_to_level(kl.pt, setup.size0, L.size());
  const int xl = cvRound(pl.x), y = cvRound(pl.y);
  int count = 0;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      // the window pixel's centre in the level-0 image (its instance there)
      const cv::Point2f p0 = level_to_image(
          cv::Point2f(static_cast<float>(xl - options.patch_radius + c),
                      static_cast<float>(y - options.patch_half_height + r)),
          setup.size0, L.size());
      const int u = std::clamp(static_cast<int>(std::lround(p0.x)), 0, instances.cols - 1);
      const int v = std::clamp(static_cast<int>(std::lround(p0.y)), 0, instances.rows - 1);
      const int here = instances.at<int>(v, u);
      const bool own = here == id;
      support[static_cast<size_t>(r) * cols + c] = own;
      count += own;
      if (beside_other != nullptr && here != 0 && !own) *beside_other = true;
    }
  return count;
}

// The instance id under keypoint kl (0: none or outside the image).
int instance_at(const cv::KeyPoint& kl, const cv::Mat& instances) {
  const int u0 = static_cast<int>(std::lround(kl.pt.x)), v0 = static_cast<int>(std::lround(kl.pt.y));
  if (u0 < 0 || v0 < 0 || u0 >= instances.cols || v0 >= instances.rows) return 0;
  return std::max(instances.at<int>(v0, u0), 0);
}

void check_instances(const char* who, const cv::Mat& instances, const cv::Size& size0,
                     float min_support_fraction) {
  if (instances.type() != CV_32SC1 || instances.size() != size0)
    throw std::invalid_argument(std::string(who) + ": instances must be int32 ids of the "
                                "level-0 image's size");
  if (!(min_support_fraction >= 0.0f && min_support_fraction <= 1.0f))
    throw std::invalid_argument(std::string(who) + ": min_support_fraction must be in [0, 1]");
}

}  // namespace

// For each keypoint of `which` whose match passes `has_depth`, on an instance, whose window
// covers pixels other than its instance's (with `need_other_instance`: another instance or a
// marked occluder) and at least min_support_fraction of its own: visit(i, kl, L, support)
// with the window's pixels on its instance, in parallel. The two users' shared walk.
template <class HasDepth, class Visit>
void for_each_partial_window(const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
                             const ScanSetup& setup, const StereoSearchOptions& options,
                             const std::vector<int>& which, const cv::Mat& instances,
                             float min_support_fraction, bool need_other_instance,
                             HasDepth has_depth, Visit visit) {
  const int window = (2 * options.patch_radius + 1) * (2 * options.patch_half_height + 1);
  auto range_body = [&](const cv::Range& range) {
    std::vector<std::uint8_t> support(static_cast<size_t>(window));
    for (int j = range.start; j < range.end; ++j) {
      const int i = which[j];
      if (!has_depth(i)) continue;
      const cv::KeyPoint& kl = left.keypoints[i];
      const int id = instance_at(kl, instances);
      if (id <= 0) continue;
      const cv::Mat& L = pyramid_left[kl.octave];
      bool beside_other = false;
      const int count = instance_support(kl, L, setup, options, instances, id, support.data(),
                                         &beside_other);
      if (count == window) continue;  // the window lies on the object: its depth stands
      if (need_other_instance && !beside_other) continue;
      if (count < min_support_fraction * static_cast<float>(window)) continue;
      visit(i, kl, L, support.data());
    }
  };
  cv::parallel_for_(cv::Range(0, static_cast<int>(which.size())), range_body, 2.0);
}

InstanceSupportReport depth_on_instance_pixels(
    const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
    const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
    const StereoSearchOptions& options, const std::vector<int>& which, const cv::Mat& instances,
    float min_support_fraction, StereoMatches* matches) {
  check_arguments("depth_on_instance_pixels", left, pyramid_left, pyramid_right, camera, options,
                  which, *matches);
  check_instances("depth_on_instance_pixels", instances, pyramid_left[0].size(), min_support_fraction);
  const ScanSetup setup = scan_setup(pyramid_left[0].size(), camera, options);
  std::atomic<int> rescanned{0}, dropped{0};
  for_each_partial_window(
      left, pyramid_left, setup, options, which, instances, min_support_fraction,
      /*need_other_instance=*/false, [&](int i) { return matches->depth[i] > 0; },
      [&](int i, const cv::KeyPoint& kl, const cv::Mat& L, const std::uint8_t* support) {
        ++rescanned;
        if (!scan_depth(kl, L, pyramid_right[kl.octave], setup, options, support,
                        &matches->u_right[i], &matches->depth[i])) {
          matches->u_right[i] = -1.0f;
          matches->depth[i] = -1.0f;
          ++dropped;
        }
      });
  return {rescanned.load(), dropped.load()};
}

InstanceSupportReport drop_matches_pulled_nearer(
    const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
    const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
    const StereoSearchOptions& options, const std::vector<int>& which, const cv::Mat& instances,
    float min_support_fraction, float min_depth, float max_pull_px, StereoMatches* matches) {
  check_arguments("drop_matches_pulled_nearer", left, pyramid_left, pyramid_right, camera, options,
                  which, *matches);
  check_instances("drop_matches_pulled_nearer", instances, pyramid_left[0].size(), min_support_fraction);
  if (!(max_pull_px >= 0)) throw std::invalid_argument("drop_matches_pulled_nearer: max_pull_px must be >= 0");
  const ScanSetup setup = scan_setup(pyramid_left[0].size(), camera, options);
  std::atomic<int> rescanned{0}, dropped{0};
  for_each_partial_window(
      left, pyramid_left, setup, options, which, instances, min_support_fraction,
      /*need_other_instance=*/true, [&](int i) { return matches->depth[i] >= min_depth; },
      [&](int i, const cv::KeyPoint& kl, const cv::Mat& L, const std::uint8_t* support) {
        ++rescanned;
        float u_own = -1.0f, depth_own = -1.0f;
        if (!scan_depth(kl, L, pyramid_right[kl.octave], setup, options, support, &u_own,
                        &depth_own))
          return;  // the object's pixels alone do not match: no evidence against the match
        // disparities (level-0 px): the match's and the object pixels' own
        if ((kl.pt.x - matches->u_right[i]) - (kl.pt.x - u_own) > max_pull_px) {
          matches->u_right[i] = -1.0f;
          matches->depth[i] = -1.0f;
          ++dropped;
        }
      });
  return {rescanned.load(), dropped.load()};
}

int check_left_right(const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
                     const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
                     const StereoSearchOptions& options, const std::vector<int>& which,
                     float tolerance_px, StereoMatches* matches) {
  check_arguments("check_left_right", left, pyramid_left, pyramid_right, camera, options, which,
                  *matches);
  if (!(tolerance_px >= 0)) throw std::invalid_argument("check_left_right: tolerance_px must be >= 0");
  const cv::Size size0 = pyramid_left[0].size();
  const DisparityWindow window = disparity_window(camera, options.min_depth, options.max_depth);
  std::atomic<int> removed{0};
  auto check_range = [&](const cv::Range& range) {
    for (int j = range.start; j < range.end; ++j) {
      const int i = which[j];
      if (!(matches->depth[i] > 0)) continue;
      const cv::KeyPoint& kl = left.keypoints[i];
      const cv::Mat& L = pyramid_left[kl.octave];
      const cv::Mat& R = pyramid_right[kl.octave];
      const float scale = static_cast<float>(size0.width) / L.cols;
      const cv::Point2f pl = image_to_level(kl.pt, size0, L.size());
      const float xr = image_to_level({matches->u_right[i], kl.pt.y}, size0, R.size()).x;
      const int xr_int = cvRound(xr), y = cvRound(pl.y);
      // the right window against the left windows of every disparity of the range (the
      // matched one and, for an occluder, larger ones: it is nearer)
      // (a match outside [min_depth, max_depth], from another matcher, still finds itself)
      const int x_first = std::min(static_cast<int>(std::floor(xr + window.min_disparity / scale)),
                                   static_cast<int>(std::floor(pl.x - tolerance_px)) - 2);
      const int x_last = std::max(static_cast<int>(std::ceil(xr + window.max_disparity / scale)),
                                  static_cast<int>(std::ceil(pl.x + tolerance_px)) + 2);
      const SadScan back = scan_sad(R, L, xr_int, y, x_first, x_last, options.patch_radius,
                                    options.patch_half_height);
      if (back.best_column < 0) continue;  // window off the image: cannot judge, keep
      // + 0.5: the scan works on whole columns, the match is sub-pixel
      if (std::abs(static_cast<float>(back.best_column) - (pl.x + (xr_int - xr))) <= tolerance_px + 0.5f)
        continue;
      matches->u_right[i] = -1.0f;
      matches->depth[i] = -1.0f;
      ++removed;
    }
  };
  cv::parallel_for_(cv::Range(0, static_cast<int>(which.size())), check_range, 2.0);
  return removed.load();
}

}  // namespace twistslam::features
