#pragma once
// The far rows' alignment to the LiDAR (object_lidar_align.cpp; ObjectTracker's
// align_far_rows_to_lidar runs it): the part that is a plain function of one track.
#include <map>
#include <vector>

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

// The scale along the lines of sight of a camera-only vehicle track's far rows, from the
// median of its rows' return-over-point ratios and its floor (far_surface_floor less the
// margin; 0: none): the ratio, but the origin never ends in front of the face the returns
// measure. A move nearer stops at that face; with `lift`, an origin already in front of it
// moves onto it, by at most max_ratio (a larger gap is an occluder's or the background's
// returns, as for a row's ratio). The origin is the median of the points only until the final
// smoothing moves them: urban s19's track 21 (a parked car at 47-39 m, 2 m in front of its face
// after the smoothing while its points lay 1.6 % beyond the returns, a ghost).
double far_align_scale(double ratio, double floor, bool lift, double max_ratio);

// Per value, the median of the finite values among the `window` around it (window / 2 on each
// side, fewer at the ends; window <= 1: the value itself); NaN where none is finite. A far
// free-link track's rows move by these medians of their ratios (align_free_track_rows).
std::vector<double> running_median(const std::vector<double>& values, int window);

}  // namespace twistslam::tracking
