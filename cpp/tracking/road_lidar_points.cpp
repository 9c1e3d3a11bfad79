#include "tracking/road_lidar_points.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace twistslam::tracking {
namespace {

struct Candidate {
  int u, v;   // pixel of the return in the left image
  int index;  // row of the scan
};

// True when every pixel of the (2 r + 1)^2 window around (u, v) has class `road`; the window
// lies inside the image (candidates are taken r pixels away from its edges).
bool road_all_around(const cv::Mat& labels, int u, int v, int r, int road) {
  for (int y = v - r; y <= v + r; ++y) {
    const int* row = labels.ptr<int>(y);
    for (int x = u - r; x <= u + r; ++x)
      if (row[x] != road) return false;
  }
  return true;
}

}  // namespace

RoadLidarPoints select_road_lidar_points(const Points3& points_c,
                                         const geometry::StereoCamera& camera,
                                         const cv::Mat& labels,
                                         const RoadLidarSelection& selection) {
  const RoadLidarSelection& s = selection;
  if (s.border_px < 0 || s.max_points < 0 || !(s.max_depth_m > 0))
    throw std::invalid_argument("RoadLidarSelection: border_px, max_points >= 0 and max_depth_m > 0");
  RoadLidarPoints out;
  out.points_c.resize(0, 3);
  if (labels.empty() || points_c.rows() == 0 || s.max_points == 0) return out;
  if (labels.type() != CV_32SC1)
    throw std::invalid_argument("select_road_lidar_points: labels must be int32 class ids");

  // Pass 1: one projection per return (the whole scan), keeping returns on a road pixel.
  const int r = s.border_px;
  const double u_lo = r - 0.5, v_lo = r - 0.5;  // pixel x covers [x - 0.5, x + 0.5)
  const double u_hi = labels.cols - r - 0.5, v_hi = labels.rows - r - 0.5;
  std::vector<Candidate> candidates;
  candidates.reserve(static_cast<std::size_t>(points_c.rows() / 8));
  for (Eigen::Index i = 0; i < points_c.rows(); ++i) {
    const Vec3 X = points_c.row(i).transpose();
    if (!X.allFinite()) {
      ++out.num_non_finite;
      continue;
    }
    const double z = X.z() + camera.t_left.z();  // depth along the left optical axis
    if (!(z > 0) || z > s.max_depth_m) continue;
    const Vec2 uv = camera.project(X);
    const double u = uv.x(), v = uv.y();
    if (!(u >= u_lo && u < u_hi && v >= v_lo && v < v_hi)) continue;
    const int pu = static_cast<int>(std::floor(u + 0.5)), pv = static_cast<int>(std::floor(v + 0.5));
    if (labels.at<int>(pv, pu) != s.road_class_id) continue;
    candidates.push_back({pu, pv, static_cast<int>(i)});
  }
  out.num_candidates = static_cast<int>(candidates.size());

  // Pass 2: the candidates split into max_points blocks of consecutive scan rows; the first
  // of each block whose neighbourhood is all road is kept. The scan order sweeps rings and
  // azimuth, so the blocks spread the kept returns over the visible road.
  const std::size_t n = candidates.size(), blocks = std::min<std::size_t>(n, s.max_points);
  std::vector<int> kept;
  kept.reserve(blocks);
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t begin = b * n / blocks, end = (b + 1) * n / blocks;
    for (std::size_t k = begin; k < end; ++k) {
      const Candidate& c = candidates[k];
      if (road_all_around(labels, c.u, c.v, r, s.road_class_id)) {
        kept.push_back(c.index);
        break;
      }
      ++out.num_near_border;
    }
  }
  out.points_c.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (std::size_t k = 0; k < kept.size(); ++k)
    out.points_c.row(static_cast<Eigen::Index>(k)) = points_c.row(kept[k]);
  return out;
}

}  // namespace twistslam::tracking
