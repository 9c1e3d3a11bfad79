#pragma once
// The road plane of the map (TwistSLAM: the plane of the road cluster, "a SVD in a RANSAC
// loop", gives the normal of the planar mechanical link). World points labelled road are kept
// in a bounded, deterministic reservoir and the plane is re-fitted whenever the number of points
// seen has grown by a set fraction since the last fit, so it is re-estimated as the map grows.
// With window_m > 0 only the batches (keyframes) added within that distance of the newest one's
// camera are kept instead, and the plane is re-fitted on every batch: the road where the
// camera is now, which on a long drive over a changing grade is not the plane of the whole map.
// Until a fit is accepted (enough inliers, normal close to the prior "up") the prior is used.
#include <cstdint>
#include <deque>
#include <random>

#include "geometry/plane_fit.hpp"
#include "geometry/types.hpp"

namespace twistslam::objects {

struct RoadPlaneOptions {
  Vec3 prior_up = Vec3(0, -1, 0);  // world up; world = first camera frame, y points down
  double prior_height = 1.65;      // m, road below the world origin (KITTI camera height)
  int max_points = 5000;           // reservoir size: a 200-sample RANSAC on it takes ~1 ms
  int min_points = 50;             // fewer road points are not fitted at all
  int min_inliers = 30;            // an accepted fit needs this many RANSAC inliers
  double min_inlier_ratio = 0.3;   // ... and this fraction of the reservoir (road masks bleed)
  double refit_growth = 0.2;       // re-fit once the points seen grew by 20 % since the last fit
  double max_angle_from_prior_deg = 15;  // deg; steeper "roads" are clutter (KITTI slopes < 10 %)
  geometry::PlaneFitOptions fit{0.1, 200, 0};  // 0.1 m: triangulated road points are noisy
  std::uint64_t reservoir_seed = 0;      // deterministic reservoir sampling
  // 0: the reservoir over every point seen; > 0 (m): the points of the add_points calls whose
  // camera lies within this distance of the newest call's (the most recent max_points of
  // them), re-fitted on each call
  double window_m = 0;
};

class RoadPlaneEstimator {
 public:
  // Throws std::invalid_argument for bad options.
  explicit RoadPlaneEstimator(const RoadPlaneOptions& options = {});

  // Adds world points labelled road (non-finite rows are skipped), seen from a camera at
  // camera_w (the window's distance; unused without one); re-fits when due.
  void add_points(const Points3& points_w, const Vec3& camera_w = Vec3::Zero());
  // Fits now on the current reservoir (also called by add_points when due).
  void refit();

  // True when the last fit was accepted; otherwise plane() / normal_up() are the prior's.
  bool valid() const { return valid_; }
  // (n, d) with n = normal_up(), n . X + d = 0 for X on the road.
  Vec4 plane() const { return plane_; }
  Vec3 normal_up() const { return plane_.head<3>(); }

  int num_points() const { return static_cast<int>(count_); }  // in the reservoir / window
  std::int64_t points_seen() const { return seen_; }
  int num_fits() const { return num_fits_; }
  int last_inliers() const { return last_inliers_; }

 private:
  Vec4 prior_plane() const;
  void add_to_window(const Points3& points_w, const Vec3& camera_w);

  RoadPlaneOptions options_;
  Points3 reservoir_;  // max_points rows, the first count_ filled
  struct Batch {
    Points3 points_w;  // its finite rows
    Vec3 camera_w;
  };
  std::deque<Batch> window_;  // window_m > 0: the batches within window_m of the newest
                              // (at most those holding its newest max_points points)
  Eigen::Index count_ = 0;
  std::int64_t seen_ = 0, seen_at_last_fit_ = 0;
  std::mt19937_64 rng_;
  bool valid_ = false;
  Vec4 plane_;
  int num_fits_ = 0, last_inliers_ = 0;
};

}  // namespace twistslam::objects
