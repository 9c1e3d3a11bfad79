// The depth of a far camera-only vehicle track from the LiDAR (not in the paper, in the spirit
// of its LiDAR fusion). Beyond ~30 m a stereo depth is good to 1-3 m (0.3-0.5 px of a 7-13 px
// disparity), and a far car's matches lean one way for many frames (corners on a nearer
// occluder's edge, a slow drift along the line of sight that its projections barely show), while
// the 20-50 LiDAR returns on its mask measure its visible surface to centimetres. Online, each
// such row keeps those returns; at the end, once the final smoothing has placed the rows, each
// row's points are compared with the returns around them (the median of return depth over point
// depth, as the LiDAR check, object_lidar_check.cpp), the track's median of those row ratios
// scales every far row's position along its line of sight, and the scale grows in from
// far_lidar_align_min_depth_m over far_lidar_align_ramp_m so that no row jumps where it starts.
// A whole track's median, not each row's: single rows scatter by a few per cent (a point on a
// car's rear edge against returns on its roof). A camera-only free-link track (a pedestrian, a
// cyclist: a thin body whose returns and points lie on one surface) moves each far row by a
// running median of the row ratios around it instead (align_free_track_rows below): its far
// track drifts row by row, which one track-wide scale cannot undo.
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "tracking/object_lidar_align.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::median_value;
using detail::kDepthCheckMinReturns;
using detail::kDepthCheckRadiusPx;
using detail::transform;

namespace {
bool camera_only(const objects::ObjectTrack& track) {
  return !track.canonical && std::none_of(track.frames.begin(), track.frames.end(),
                                          [](const objects::TrackFrame& r) { return r.has_detection(); });
}

bool camera_only_vehicle(const objects::ObjectTrack& track) {
  return track.link == geometry::LinkType::kPlanar && camera_only(track);
}

bool camera_only_free(const objects::ObjectTrack& track) {
  return track.link != geometry::LinkType::kPlanar && camera_only(track);
}

// The median of the kept returns' depth around uv, by the LiDAR check's rule
// (detail::kDepthCheckRadiusPx, kDepthCheckMinReturns; NaN: too few).
double returns_depth_near(const Points3& returns, const Vec2& uv) {
  std::vector<double> depths;
  for (Eigen::Index i = 0; i < returns.rows(); ++i) {
    const double du = returns(i, 0) - uv.x(), dv = returns(i, 1) - uv.y();
    if (du * du + dv * dv <= kDepthCheckRadiusPx * kDepthCheckRadiusPx) depths.push_back(returns(i, 2));
  }
  if (static_cast<int>(depths.size()) < kDepthCheckMinReturns) return std::nan("");
  return median_value(depths);
}

// Whether the instance's mask reaches the image's left, right or bottom border: a car cut there
// shows the part of it the image holds, whose nearest faces need not be the car's (urban s35's
// car 8, passing the camera at 5-8 m: the part in view 0.3-0.5 m beyond its origin).
bool touches_image_border(const cv::Mat& instances, int instance) {
  const int last_row = instances.rows - 1, last_col = instances.cols - 1;
  for (int r = 0; r <= last_row; ++r)
    if (instances.at<int>(r, 0) == instance || instances.at<int>(r, last_col) == instance) return true;
  for (int c = 0; c <= last_col; ++c)
    if (instances.at<int>(last_row, c) == instance) return true;
  return false;
}

// The `quantile` (0..1, the lower of the two values around it) of non-empty values.
double quantile_value(std::vector<double> values, double quantile) {
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(quantile * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), at, values.end());
  return *at;
}
}  // namespace

void ObjectTracker::keep_far_lidar_returns(const Frame& frame) {
  const ObjectLidarOptions& o = lidar_options_;
  const bool vehicles = o.far_lidar_align_min_depth_m > 0;  // the near lift works below that bound
  const bool free_tracks = o.far_lidar_align_free_window_rows > 0 && o.far_lidar_align_free_min_depth_m > 0;
  if (!(vehicles || free_tracks) || !scan_ || instances_.empty()) return;
  for (size_t c = 0; c < tracks_.size(); ++c) {
    objects::ObjectTrack& track = tracks_[c];
    const int instance = clusters_[c].instance;
    if (!track.alive() || track.frames.empty() || instance <= 0) continue;
    const bool vehicle = vehicles && camera_only_vehicle(track);
    if (!vehicle && !(free_tracks && camera_only_free(track))) continue;
    objects::TrackFrame& row = track.last();
    if (row.frame != frame.index || !row.reported) continue;
    const double depth_m = (frame.T_c_w * row.T_w_o)(2, 3);
    if (vehicle && o.near_lidar_surface_lift && depth_m < o.far_lidar_align_min_depth_m &&
        !touches_image_border(instances_, instance)) {
      const std::vector<double>* depths = mask_lidar_depths(instance);
      if (static_cast<int>(depths->size()) >= o.lidar_check_min_returns)
        row.lidar_face_depth_m = quantile_value(*depths, o.far_lidar_align_surface_quantile);
    }
    // rows a little nearer online may lie beyond the bound once smoothed
    const double keep_from_m = (vehicle ? o.far_lidar_align_min_depth_m : o.far_lidar_align_free_min_depth_m) *
                               (1.0 - o.far_lidar_align_max_ratio);
    if (depth_m < keep_from_m) continue;
    const lidar::ScanProjection* returns = instance_returns(instance);
    if (returns == nullptr || static_cast<int>(returns->returns.size()) < o.lidar_check_min_returns) continue;
    row.far_lidar_returns.resize(static_cast<Eigen::Index>(returns->returns.size()), 3);
    Eigen::Index n = 0;
    for (const lidar::ProjectedReturn& p : returns->returns) row.far_lidar_returns.row(n++) << p.u, p.v, p.depth;
  }
}

// A camera-only cluster's origin is the median of its points, which lie on its visible faces: a
// move nearer than the face the LiDAR sees is the points' fault, not the track's. Points
// smeared behind the origin by a far track's lagging depth motion give a ratio below 1 that
// pulled the origin in front of the car (urban s26's lead car at 55-66 m: the returns on its
// rear at 56 m, the origin moved from 56.9 to 54.7 m, a ghost).
double far_surface_floor(const objects::ObjectTrack& track, const std::map<int, Mat4>& T_c_w_of_frame,
                         double min_depth_m, double quantile) {
  std::vector<double> floors;
  for (const objects::TrackFrame& row : track.frames) {
    const auto pose = T_c_w_of_frame.find(row.frame);
    if (!row.reported || row.far_lidar_returns.rows() == 0 || pose == T_c_w_of_frame.end()) continue;
    const double depth = (pose->second * row.T_w_o)(2, 3);
    if (depth < min_depth_m) continue;
    std::vector<double> returns;
    for (Eigen::Index i = 0; i < row.far_lidar_returns.rows(); ++i)
      returns.push_back(row.far_lidar_returns(i, 2));
    floors.push_back(quantile_value(std::move(returns), quantile) / depth);
  }
  return floors.empty() ? 0.0 : median_value(floors);
}

double far_align_scale(double ratio, double floor, bool lift, double max_ratio) {
  if (!(floor > 0)) return ratio;
  if (lift) return std::max(ratio, std::min(floor, 1.0 + max_ratio));
  return ratio < 1.0 ? std::min(1.0, std::max(ratio, floor)) : ratio;
}

std::vector<double> running_median(const std::vector<double>& values, int window) {
  const size_t half = static_cast<size_t>(std::max(window, 1) / 2);
  std::vector<double> medians(values.size(), std::nan(""));
  for (size_t i = 0; i < values.size(); ++i) {
    std::vector<double> around;
    for (size_t j = i >= half ? i - half : 0; j < std::min(values.size(), i + half + 1); ++j)
      if (std::isfinite(values[j])) around.push_back(values[j]);
    if (!around.empty()) medians[i] = median_value(around);
  }
  return medians;
}

namespace {
// One row's median, over the cluster's points with returns around them, of the returns' depth
// over the point's; NaN with fewer than min_points such points or beyond max_ratio of 1 (an
// occluder's or the background's returns).
double row_lidar_ratio(const objects::TrackFrame& row, const Mat4& T_c_o,
                       const std::vector<objects::ObjectPoint>& points, const geometry::StereoCamera& camera,
                       int min_points, double max_ratio) {
  std::vector<double> ratios;
  for (const objects::ObjectPoint& p : points) {
    const Vec3 X_c = transform(T_c_o, p.X_o);
    if (X_c.z() <= 0.1) continue;
    const Vec2 uv = camera.project(X_c);
    if (!camera.in_image(uv)) continue;
    const double depth = returns_depth_near(row.far_lidar_returns, uv);
    if (std::isfinite(depth)) ratios.push_back(depth / X_c.z());
  }
  if (static_cast<int>(ratios.size()) < min_points) return std::nan("");
  const double ratio = median_value(ratios);
  return std::abs(ratio - 1.0) <= max_ratio ? ratio : std::nan("");
}

// One row's median depth of the returns on its mask over its origin's depth; NaN without
// returns. A thin body's (a pedestrian's) returns lie on the surface its origin stands in, and
// its points need not: a far pedestrian cluster gathers points metres before and behind it
// (urban s35's track 54, 58 points over 6.6 m: the ones with returns around them at the
// returns' depth, its origin 1.2-2 m in front of them).
double row_origin_ratio(const objects::TrackFrame& row, double origin_depth_m) {
  if (row.far_lidar_returns.rows() == 0 || !(origin_depth_m > 0)) return std::nan("");
  std::vector<double> depths(static_cast<size_t>(row.far_lidar_returns.rows()));
  for (Eigen::Index i = 0; i < row.far_lidar_returns.rows(); ++i) depths[static_cast<size_t>(i)] = row.far_lidar_returns(i, 2);
  return median_value(depths) / origin_depth_m;
}

// A camera-only free-link track's far rows, each moved by the running median of the row ratios
// around it (far_lidar_align_free_window_rows). Urban s24's DIS ghost 18, a pedestrian standing
// at 41-25 m tracked as if it walked away at 3 km/h: its rows' ratios fall steadily from 1.01 to
// 0.91 (the track 0.1 m off at first, 2.5 m beyond it by its last row), while a track-wide ratio
// would move its first rows off and leave its last ones beyond. Offline on urban s24 / s26 / s29,
// a window of 7 rows put all 23 of its rows on the pedestrian and moved no other pedestrian
// track's reported row off its box; one row at a time (no window) moved 4 rows of 4 good tracks
// off (occluders' returns on a thin mask). With far_lidar_align_free_from_origin the ratio is
// the origin's (row_origin_ratio), and with far_lidar_align_free_hide_beyond a row whose running
// median lies beyond far_lidar_align_max_ratio of 1 is not reported: urban s34's track 35, a
// pedestrian standing at 46-41 m, reported at 35-28 m (its running medians 1.27-1.38).
void align_free_track_rows(objects::ObjectTrack* track, const std::vector<objects::ObjectPoint>& points,
                           const std::map<int, Mat4>& T_c_w_of_frame, const geometry::StereoCamera& camera,
                           const ObjectLidarOptions& o) {
  std::vector<size_t> rows;
  std::vector<double> ratios;
  for (size_t k = 0; k < track->frames.size(); ++k) {
    const objects::TrackFrame& row = track->frames[k];
    const auto pose = T_c_w_of_frame.find(row.frame);
    if (!row.reported || row.far_lidar_returns.rows() == 0 || pose == T_c_w_of_frame.end()) continue;
    const Mat4 T_c_o = pose->second * row.T_w_o;
    if (T_c_o(2, 3) < o.far_lidar_align_free_min_depth_m) continue;
    rows.push_back(k);
    ratios.push_back(o.far_lidar_align_free_from_origin
                         ? row_origin_ratio(row, T_c_o(2, 3))
                         : row_lidar_ratio(row, T_c_o, points, camera, o.lidar_check_min_points,
                                           o.far_lidar_align_max_ratio));
  }
  const std::vector<double> scales = running_median(ratios, o.far_lidar_align_free_window_rows);
  for (size_t i = 0; i < rows.size(); ++i) {  // after every ratio: each is read before any row moves
    if (!std::isfinite(scales[i])) continue;
    objects::TrackFrame& row = track->frames[rows[i]];
    if (std::abs(scales[i] - 1.0) > o.far_lidar_align_max_ratio) {
      // only an origin ratio gets here (a points' ratio beyond the bound is not counted)
      if (o.far_lidar_align_free_hide_beyond) row.reported = false, row.lidar_contradicted = true;
      continue;
    }
    const Mat4& T_c_w = T_c_w_of_frame.at(row.frame);
    Mat4 T_c_o = T_c_w * row.T_w_o;
    T_c_o.topRightCorner<3, 1>() *= scales[i];  // along the line of sight
    row.T_w_o = T_c_w.inverse() * T_c_o;
  }
}

// A camera-only vehicle row nearer than far_lidar_align_min_depth_m whose origin lies in front of
// the face its mask's returns measured (TrackFrame::lidar_face_depth_m, less the margin) moves
// onto it along its line of sight, by at most far_lidar_align_max_ratio. Crowded s21's DIS ghost
// 27, on a car seen between two nearer ones (occlusion 2), started 2.2 m in front of that car's
// rear at 15.7 m and came onto it over 20 frames: too little for the LiDAR check's track medians
// (0.9 m), and 1-2.2 m in front of the car in 14 reported rows. An origin is the median of
// points on the visible faces and lies behind the nearest tenth of them, whatever the view,
// unless the image cuts the car (touches_image_border: no face is kept then). Each row's floor
// is the running median of the floors of the near_lidar_surface_window_rows rows around it, as
// the free-link rows' ratios: a row whose mask's returns meet an occluder's edge does not move
// alone.
void lift_near_rows_onto_their_face(objects::ObjectTrack* track, const std::map<int, Mat4>& T_c_w_of_frame,
                                    const ObjectLidarOptions& o) {
  std::vector<size_t> rows;
  std::vector<double> floors;
  for (size_t k = 0; k < track->frames.size(); ++k) {
    const objects::TrackFrame& row = track->frames[k];
    const auto pose = T_c_w_of_frame.find(row.frame);
    if (!row.reported || pose == T_c_w_of_frame.end()) continue;
    const double depth_m = (pose->second * row.T_w_o)(2, 3);
    if (!(depth_m > 0) || depth_m >= o.far_lidar_align_min_depth_m) continue;
    rows.push_back(k);
    floors.push_back(row.lidar_face_depth_m / depth_m - o.far_lidar_align_surface_margin);  // NaN: no face
  }
  const std::vector<double> medians = running_median(floors, o.near_lidar_surface_window_rows);
  for (size_t i = 0; i < rows.size(); ++i) {
    // only a row with a face of its own: a row cut by the image (real 0001's car 1 at 3 m,
    // its neighbours' floors lifted it 0.25 m past its box) or without returns stays
    if (!std::isfinite(floors[i]) || !std::isfinite(medians[i])) continue;
    const double scale = far_align_scale(1.0, medians[i], true, o.far_lidar_align_max_ratio);
    if (scale <= 1.0) continue;
    objects::TrackFrame& row = track->frames[rows[i]];
    const Mat4& T_c_w = T_c_w_of_frame.at(row.frame);
    Mat4 T_c_o = T_c_w * row.T_w_o;
    T_c_o.topRightCorner<3, 1>() *= scale;  // along the line of sight
    row.T_w_o = T_c_w.inverse() * T_c_o;
  }
}

// A camera-only vehicle's far rows whose origin lies more than far_lidar_align_max_behind_m beyond
// the median depth of the returns on their mask, by their own measure and by the running median
// over far_lidar_align_behind_window_rows rows, move nearer by the smaller excess (at most
// far_lidar_align_max_ratio of their depth).
// After the track-wide scale, which one ratio of the whole track sets: a far track whose depth
// lags row by row (urban s40's DIS ghost 29, a parked car at 60-45 m tracked as if it drove with
// the camera: its rows 0.1 m off the returns' median at 55 m, 4.3 m beyond it at 50 m) keeps
// its first rows on the car and its last ones beyond it under any one scale. An origin is the
// median of points on the car's visible faces, which its returns measure: seen end-on it lies on
// them, seen from an angle a little beyond their median.
void pull_far_rows_to_their_returns(objects::ObjectTrack* track, const std::map<int, Mat4>& T_c_w_of_frame,
                                    const ObjectLidarOptions& o) {
  std::vector<size_t> rows;
  std::vector<double> behind_m;
  for (size_t k = 0; k < track->frames.size(); ++k) {
    const objects::TrackFrame& row = track->frames[k];
    const auto pose = T_c_w_of_frame.find(row.frame);
    if (!row.reported || row.far_lidar_returns.rows() == 0 || pose == T_c_w_of_frame.end()) continue;
    const double depth_m = (pose->second * row.T_w_o)(2, 3);
    if (depth_m < o.far_lidar_align_min_depth_m) continue;
    rows.push_back(k);
    behind_m.push_back(depth_m - depth_m * row_origin_ratio(row, depth_m));
  }
  const std::vector<double> medians = running_median(behind_m, o.far_lidar_align_behind_window_rows);
  for (size_t i = 0; i < rows.size(); ++i) {
    // both its own and its neighbours': a row after a gap is not moved by rows that lagged
    // before it (urban s40's files track 28, at 42 m six frames after two rows 5 m behind), nor
    // one row by its own stray returns
    const double excess_m = std::min(behind_m[i], medians[i]) - o.far_lidar_align_max_behind_m;
    if (!(excess_m > 0)) continue;
    objects::TrackFrame& row = track->frames[rows[i]];
    const Mat4& T_c_w = T_c_w_of_frame.at(row.frame);
    Mat4 T_c_o = T_c_w * row.T_w_o;
    const double scale = std::max(1.0 - o.far_lidar_align_max_ratio, 1.0 - excess_m / T_c_o(2, 3));
    T_c_o.topRightCorner<3, 1>() *= scale;  // along the line of sight
    row.T_w_o = T_c_w.inverse() * T_c_o;
  }
}

// A camera-only vehicle track's far rows scaled along their lines of sight by the track's median
// row ratio (the file's head comment), from far_lidar_align_min_depth_m over far_lidar_align_ramp_m.
void scale_far_vehicle_track(objects::ObjectTrack* track, const std::vector<objects::ObjectPoint>& points,
                             const std::map<int, Mat4>& T_c_w_of_frame, const geometry::StereoCamera& camera,
                             const ObjectLidarOptions& o) {
  std::vector<double> row_ratios;
  for (const objects::TrackFrame& row : track->frames) {
    const auto pose = T_c_w_of_frame.find(row.frame);
    if (!row.reported || row.far_lidar_returns.rows() == 0 || pose == T_c_w_of_frame.end()) continue;
    const Mat4 T_c_o = pose->second * row.T_w_o;
    if (T_c_o(2, 3) < o.far_lidar_align_min_depth_m) continue;
    const double ratio = row_lidar_ratio(row, T_c_o, points, camera, o.lidar_check_min_points,
                                         o.far_lidar_align_max_ratio);
    if (std::isfinite(ratio)) row_ratios.push_back(ratio);
  }
  if (static_cast<int>(row_ratios.size()) < o.far_lidar_align_min_rows) return;
  double ratio = median_value(row_ratios);
  if (o.far_lidar_align_surface_floor) {
    // not in front of the face its returns measure, less the margin (a ratio: the margin is
    // that fraction of the origin's depth)
    const double floor = far_surface_floor(*track, T_c_w_of_frame, o.far_lidar_align_min_depth_m,
                                           o.far_lidar_align_surface_quantile);
    if (floor > 0)
      ratio = far_align_scale(ratio, floor - o.far_lidar_align_surface_margin, o.far_lidar_align_surface_lift,
                              o.far_lidar_align_max_ratio);
  }
  for (objects::TrackFrame& row : track->frames) {
    const auto pose = T_c_w_of_frame.find(row.frame);
    if (!row.reported || pose == T_c_w_of_frame.end()) continue;
    Mat4 T_c_o = pose->second * row.T_w_o;
    const double beyond_m = T_c_o(2, 3) - o.far_lidar_align_min_depth_m;
    if (beyond_m <= 0) continue;
    const double weight = o.far_lidar_align_ramp_m > 0 ? std::min(1.0, beyond_m / o.far_lidar_align_ramp_m) : 1.0;
    T_c_o.topRightCorner<3, 1>() *= 1.0 + (ratio - 1.0) * weight;  // along the line of sight
    row.T_w_o = pose->second.inverse() * T_c_o;
  }
}
}  // namespace

void ObjectTracker::align_far_rows_to_lidar(const std::map<int, Mat4>& T_c_w_of_frame) {
  const ObjectLidarOptions& o = lidar_options_;
  const bool free_tracks = o.far_lidar_align_free_window_rows > 0 && o.far_lidar_align_free_min_depth_m > 0;
  for (size_t c = 0; c < tracks_.size(); ++c) {
    objects::ObjectTrack& track = tracks_[c];
    if (free_tracks && camera_only_free(track))
      align_free_track_rows(&track, clusters_[c].points, T_c_w_of_frame, camera_, o);
    // before the far rows move: the near ones are those nearer than the bound as they stand
    if (o.near_lidar_surface_lift && camera_only_vehicle(track))
      lift_near_rows_onto_their_face(&track, T_c_w_of_frame, o);
    if (o.far_lidar_align_min_depth_m <= 0 || !camera_only_vehicle(track)) continue;
    scale_far_vehicle_track(&track, clusters_[c].points, T_c_w_of_frame, camera_, o);
    if (o.far_lidar_align_max_behind_m > 0) pull_far_rows_to_their_returns(&track, T_c_w_of_frame, o);
  }
}

}  // namespace twistslam::tracking
