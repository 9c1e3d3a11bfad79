#pragma once
// The far rows' alignment to the LiDAR (object_lidar_align.cpp; ObjectTracker's
// align_far_rows_to_lidar runs it): the part that is a plain function of one track.
#include <map>

#include "geometry/types.hpp"
#include "objects/object_track.hpp"

namespace twistslam::tracking {

// The smallest scale along the lines of sight that keeps a camera-only track's origin at or
// beyond the face the LiDAR sees: the median over its reported rows at min_depth_m or more
// that kept returns (TrackFrame::far_lidar_returns, camera frame u, v, depth) of
// (the returns' depth quantile, 0..1) / (origin depth); 0 when no row qualifies.
// T_c_w_of_frame: camera poses by frame index (rows without one are skipped).
double far_surface_floor(const objects::ObjectTrack& track, const std::map<int, Mat4>& T_c_w_of_frame,
                         double min_depth_m, double quantile);

}  // namespace twistslam::tracking
