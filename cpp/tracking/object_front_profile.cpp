// A canonical vehicle's front from its own returns (not in the paper). A LiDAR box knows a
// car's heading mod pi; a car that moves shows its front by the way it goes
// (check_heading_from_motion), and the classical detector tells the front of a car seen whole
// from its height profile when one view is clear (detection/front_profile.hpp, 0.4 m). A
// stopped car whose views all fell short of that kept the heading of its first box. Classical
// urban s13's car 21, stopped across the road at 11-29 m: per view 0.03-0.47 m (mean 0.24 m
// over 7 views, 4.5 standard errors), tracked turned around (yaw error 180 deg). Here each
// object scan that spans the track's length adds its gap difference in the object frame; once
// their mean is clear, each view votes on the heading like a box that told the front
// (check_heading_from_votes): that car had one such box, wrong, against 16 views.
#include <cmath>
#include <limits>
#include <vector>

#include "detection/front_profile.hpp"
#include "geometry/se3.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::transform;

namespace {
// the greenhouse: returns above this fraction of the car's top (the detector's default,
// DetectorOptions::front_profile_upper_fraction)
constexpr double kUpperFraction = 0.8;
// m, returns this far outside the track's box footprint still join the profile (its box is
// good to ~0.1 m); the object scan's own margin (scan_margin_m) reaches into neighbours
constexpr double kProfileMarginM = 0.15;
}  // namespace

void ObjectTracker::add_front_profile_view(int c, const Points3& points_w) {
  objects::ObjectTrack& track = tracks_[c];
  if (!lidar_options_.heading_from_profile || !track.canonical ||
      track.link != geometry::LinkType::kPlanar || !(track.size.minCoeff() > 0))
    return;
  const Mat4 T_o_w = geometry::se3_inverse(track.last().T_w_o);
  // box axes: x length, y down (height), z width
  const double half_length = track.size.x() / 2 + kProfileMarginM;
  const double half_width = track.size.y() / 2 + kProfileMarginM;
  std::vector<detection::ProfilePoint> profile;
  profile.reserve(static_cast<size_t>(points_w.rows()));
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (Eigen::Index i = 0; i < points_w.rows(); ++i) {
    const Vec3 X_o = transform(T_o_w, points_w.row(i).transpose());
    if (std::abs(X_o.x()) > half_length || std::abs(X_o.z()) > half_width) continue;
    profile.push_back({static_cast<float>(X_o.x()), static_cast<float>(track.size.z() / 2 - X_o.y())});
    lo = std::min(lo, X_o.x());
    hi = std::max(hi, X_o.x());
  }
  // a view of one end shows the greenhouse but not the far bumper: no gap to compare there
  if (profile.empty() || hi - lo < lidar_options_.front_profile_min_span * track.size.x()) return;
  const double difference = detection::profile_gap_difference(profile, kUpperFraction);
  if (std::isfinite(difference)) track.front_profile_m.push_back(difference);
}

int ObjectTracker::front_from_profile_views(const objects::ObjectTrack& track) const {
  const ObjectLidarOptions& o = lidar_options_;
  if (!o.heading_from_profile) return 0;
  return detection::front_from_views(track.front_profile_m, o.front_profile_min_views,
                                     o.front_profile_min_sigmas, o.front_profile_min_difference_m);
}

}  // namespace twistslam::tracking
