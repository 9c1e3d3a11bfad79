#pragma once
// The disparities a stereo search scans for a depth range, and how far the right row drifts
// with disparity, shared by match_stereo (stereo.cpp) and search_stereo (stereo_search.cpp).
#include "geometry/stereo_camera.hpp"

namespace twistslam::features {

struct DisparityWindow {
  // Disparities as measured in the images: the pair's offset (stereo_camera.hpp) is added
  // only when a disparity becomes a depth, so the search windows are in image pixels.
  float min_disparity = 0, max_disparity = 0;  // px, from max_depth and min_depth
  // v_right - v_left of a point at disparity d is (fy / fx) (t_right.y - t_left.y) / b * d
  // (exact for fronto-parallel offsets; the z offsets of KITTI's cameras are negligible):
  // on KITTI 0.005 d, i.e. 0.25 px at 8 m and 2 px at 1 m.
  float dv_per_disparity = 0;
};

inline DisparityWindow disparity_window(const geometry::StereoCamera& camera, double min_depth,
                                        double max_depth) {
  const double fb = camera.fx * camera.baseline;
  const float offset = static_cast<float>(camera.disparity_offset);
  DisparityWindow w;
  w.min_disparity = static_cast<float>(fb / max_depth) - offset;
  w.max_disparity = static_cast<float>(fb / min_depth) - offset;
  w.dv_per_disparity = static_cast<float>(camera.fy / camera.fx *
                                          (camera.t_right.y() - camera.t_left.y()) / camera.baseline);
  return w;
}

}  // namespace twistslam::features
