// Object scans and their registration (paper sec. "Injecting LiDAR scans", eq. 6-7): the
// points of a frame's LiDAR scan inside a canonical object's box (enlarged by scan_margin_m,
// without the road under it) form its object scan; GICP (registration/gicp.hpp) aligns it
// with the object's scan of the previous frame, starting from the tracked motion and under the
// object's link. The registered motion M_w (T_w_o(i) = M_w T_w_o(i-1)) joins the object window
// as e_reg.
#include <algorithm>
#include <cmath>

#include "geometry/se3.hpp"
#include "objects/motion_uncertainty.hpp"
#include "registration/gicp.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {

struct ObjectTracker::ObjectScan {
  int frame = -1;
  registration::GicpScan scan;  // world frame
};

namespace {

// Neighbours of each scan point's plane covariance: GicpOptions' default (measured there).
constexpr int kScanNeighbors = registration::kDefaultNumNeighbors;

}  // namespace

namespace detail {

Points3 points_in_box(const Points3& scan_c, const Mat4& T_c_o, const Mat4& T_x_c, const Vec3& size,
                      double margin, double ground_clearance) {
  const Mat3 R = T_c_o.topLeftCorner<3, 3>();
  const Vec3 t = T_c_o.topRightCorner<3, 1>();
  // box axes: x length, y down (height), z width
  const Vec3 half(size.x() / 2 + margin, size.z() / 2, size.y() / 2 + margin);
  const double top = -half.y() - margin, bottom = half.y() - ground_clearance;
  const double reach2 = half.squaredNorm() + margin * margin;
  std::vector<Vec3> inside;
  for (Eigen::Index i = 0; i < scan_c.rows(); ++i) {
    const Vec3 p = scan_c.row(i).transpose();
    const Vec3 d = p - t;
    if (!(d.squaredNorm() <= reach2)) continue;  // far from the box (or not finite)
    const Vec3 q = R.transpose() * d;
    if (std::abs(q.x()) <= half.x() && std::abs(q.z()) <= half.z() && q.y() >= top && q.y() <= bottom)
      inside.push_back(transform(T_x_c, p));
  }
  Points3 out(static_cast<Eigen::Index>(inside.size()), 3);
  for (size_t i = 0; i < inside.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = inside[i].transpose();
  return out;
}

}  // namespace detail

void ObjectTracker::register_scan(int c, const Frame& frame) {
  objects::ObjectTrack& track = tracks_[c];
  const bool profile = lidar_options_.heading_from_profile && track.link == geometry::LinkType::kPlanar;
  if (!scan_ || !(lidar_options_.use_registration || profile) || !track.canonical ||
      !(track.size.minCoeff() > 0))
    return;
  objects::TrackFrame& row = track.last();
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  const Points3 points = detail::points_in_box(*scan_, frame.T_c_w * row.T_w_o, T_w_c, track.size,
                                       lidar_options_.scan_margin_m,
                                       lidar_options_.scan_ground_clearance_m);
  if (profile) add_front_profile_view(c, points);
  if (!lidar_options_.use_registration) return;
  const auto previous = last_scan_.find(track.id);
  if (points.rows() < std::max(lidar_options_.min_scan_points, kScanNeighbors)) {
    if (previous != last_scan_.end()) last_scan_.erase(previous);
    return;
  }
  auto current = std::make_shared<ObjectScan>();
  current->frame = frame.index;
  current->scan = registration::make_gicp_scan(points, kScanNeighbors);
  if (previous != last_scan_.end() && previous->second->frame == frame.index - 1 &&
      track.frames.size() >= 2) {
    // eq. 6: the new scan aligned onto the previous one, from the tracked motion (T_target_source
    // = M_w^-1); the link's projector acts in the target's frame, the world, as Pi does
    const Mat4 M_tracked = row.T_w_o * geometry::se3_inverse(track.frames[track.frames.size() - 2].T_w_o);
    registration::GicpOptions options;
    options.projector = track.Pi;
    const registration::GicpResult r = registration::gicp(current->scan, previous->second->scan,
                                                          geometry::se3_inverse(M_tracked), options);
    const bool usable = (r.status == registration::GicpStatus::kConverged ||
                         r.status == registration::GicpStatus::kMaxIterations) &&
                        r.rmse_m <= lidar_options_.reg_max_rmse_m &&
                        r.num_inliers >= lidar_options_.min_scan_points &&
                        r.num_inliers >= lidar_options_.reg_min_inlier_fraction *
                                             static_cast<double>(points.rows());
    if (usable) {
      row.registered = true;
      row.M_w_registered = geometry::se3_inverse(r.T_target_source);  // eq. 7: xi_r = log(M_w)
      row.reg_sigma = Vec2::Zero();
      row.reg_covariance = Mat6::Zero();
      // e_reg's whole covariance for a car (a rigid scan); a walker's limbs move between
      // scans, so its registrations keep the largest sigmas below
      if (lidar_options_.reg_sigma_from_information && lidar_options_.reg_full_covariance &&
          track.link == geometry::LinkType::kPlanar) {
        objects::MotionCovarianceOptions co;
        co.scale_translation = lidar_options_.reg_information_scale_translation;
        co.scale_rotation = lidar_options_.reg_information_scale_rotation;
        co.min_sigma_translation = lidar_options_.reg_min_sigma_translation;
        co.min_sigma_rotation = lidar_options_.reg_min_sigma_rotation;
        row.reg_covariance = objects::registered_motion_covariance(
            r.information, row.M_w_registered, track.Pi, row.T_w_o.topRightCorner<3, 1>(), co);
        // never a NaN into the window (it refuses one): the sigmas below then
        if (!row.reg_covariance.allFinite()) row.reg_covariance = Mat6::Zero();
      }
      if (lidar_options_.reg_sigma_from_information) {
        // W_reg from GICP's own uncertainty, scaled to the errors it measured (config)
        const objects::MotionSigmas sd = objects::registered_motion_sigmas(
            r.information, row.M_w_registered, track.Pi, row.T_w_o.topRightCorner<3, 1>());
        row.reg_sigma = Vec2(
            std::max(lidar_options_.reg_min_sigma_translation,
                     lidar_options_.reg_information_scale_translation * sd.translation_m),
            std::max(lidar_options_.reg_min_sigma_rotation,
                     lidar_options_.reg_information_scale_rotation * sd.rotation_rad));
      }
    }
  }
  last_scan_[track.id] = std::move(current);
}

void ObjectTracker::drop_stale_scans(int frame_index) {
  for (auto it = last_scan_.begin(); it != last_scan_.end();)
    it = it->second->frame < frame_index ? last_scan_.erase(it) : std::next(it);
}

}  // namespace twistslam::tracking
