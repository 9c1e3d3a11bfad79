// Bindings of cpp/tracking: the stereo SLAM System, one track() call per frame.
#include <pybind11/stl.h>

#include <opencv2/core/mat.hpp>

#include "bindings/detection_arrays.hpp"
#include "bindings/numpy_checks.hpp"
#include "bindings/object_track_dict.hpp"
#include "bindings/slam_options.hpp"
#include "tracking/system.hpp"

namespace twistslam::bindings {
using namespace pybind11::literals;
namespace t = twistslam::tracking;

namespace {

// Zero-copy cv::Mat view of a C-contiguous numpy image; the array must outlive the view.
cv::Mat image_view(const py::array& a, const char* name, bool labels) {
  const bool ok_dtype = labels ? py::isinstance<py::array_t<std::int32_t>>(a) : py::isinstance<py::array_t<std::uint8_t>>(a);
  const bool ok_shape = a.ndim() == 2 || (!labels && a.ndim() == 3 && a.shape(2) == 3);
  if (!ok_dtype || !ok_shape) {
    throw py::value_error(std::string(name) + ": expected " +
                          (labels ? "int32 (H, W)" : "uint8 (H, W) or (H, W, 3)") + ", got " +
                          std::string(py::str(a.dtype())) + " " + shape_string(a));
  }
  if (!(a.flags() & py::array::c_style)) throw py::value_error(std::string(name) + ": array must be C-contiguous");
  if (a.shape(0) == 0 || a.shape(1) == 0) throw py::value_error(std::string(name) + ": empty image");
  const int type = labels ? CV_32SC1 : (a.ndim() == 3 ? CV_8UC3 : CV_8UC1);
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), type, const_cast<void*>(a.data()));
}

// Zero-copy CV_32FC2 view of a C-contiguous float32 (H, W, 2) flow field.
cv::Mat flow_view(const py::array& a) {
  if (!py::isinstance<py::array_t<float>>(a) || a.ndim() != 3 || a.shape(2) != 2)
    throw py::value_error("flow: expected float32 (H, W, 2), got " + std::string(py::str(a.dtype())) +
                          " " + shape_string(a));
  if (!(a.flags() & py::array::c_style)) throw py::value_error("flow: array must be C-contiguous");
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), CV_32FC2,
                 const_cast<void*>(a.data()));
}

// Every object cluster: its track (object_track_dict.hpp) plus its points in the object frame.
py::list objects_to_list(const t::ObjectTracker& tracker) {
  py::list out;
  for (size_t c = 0; c < tracker.tracks().size(); ++c) {
    py::dict d = track_to_dict(tracker.tracks()[c]);
    const auto& pts = tracker.clusters()[c].points;
    DoubleArray X = new_array({static_cast<py::ssize_t>(pts.size()), 3});
    py::array_t<std::int64_t> found(static_cast<py::ssize_t>(pts.size()));
    for (size_t i = 0; i < pts.size(); ++i) {
      for (int k = 0; k < 3; ++k) X.mutable_data()[3 * i + k] = pts[i].X_o[k];
      found.mutable_data()[i] = pts[i].found;
    }
    d["points_o"] = X;
    d["point_found"] = found;
    // the points it culled while tracked, each confirmed in two frames or more (kept for the
    // final smoothing; empty without it): faces an earlier view showed
    const auto& retired = tracker.clusters()[c].retired;
    DoubleArray R = new_array({static_cast<py::ssize_t>(retired.size()), 3});
    for (size_t i = 0; i < retired.size(); ++i)
      for (int k = 0; k < 3; ++k) R.mutable_data()[3 * i + k] = retired[i].X_o[k];
    d["retired_points_o"] = R;
    out.append(d);
  }
  return out;
}

py::dict to_dict(const t::TrackResult& r) {
  py::dict timings;
  for (const auto& [stage, ms] : r.timings_ms) timings[py::str(stage)] = ms;
  return py::dict("status"_a = t::to_string(r.status), "T_w_c"_a = to_numpy(r.T_w_c),
                  "is_keyframe"_a = r.is_keyframe, "num_inliers"_a = r.num_inliers,
                  "num_map_points"_a = r.num_map_points, "num_keyframes"_a = r.num_keyframes,
                  "num_lidar_depth"_a = r.num_lidar_depth, "timings_ms"_a = timings,
                  "num_objects_tracked"_a = r.objects.num_tracked,
                  "num_objects_new"_a = r.objects.num_new,
                  "num_object_points"_a = r.objects.num_points);
}

// A local BA still solving in its thread (local_ba.asynchronous) is applied before the
// state is read, without the GIL: the read-ahead thread of twistslam.run goes on meanwhile.
void finish_ba(t::System& s) {
  py::gil_scoped_release release;
  s.finish_local_ba();
}

}  // namespace

void bind_slam(py::module_& m) {
  m.def("default_options", &default_slam_options,
        "The C++ defaults of every option, nested {section: {key: value}} as System() takes them.");
  py::class_<t::System>(m, "System", "Stereo SLAM: camera tracking on static points, keyframes, local BA.")
      .def(py::init([](const geometry::StereoCamera& camera, const py::dict& options) {
             return std::make_unique<t::System>(camera, parse_slam_options(options));
           }),
           "camera"_a, "options"_a = py::dict(),
           R"doc(Create a SLAM system.

Parameters
----------
camera : twistslam.geometry.StereoCamera
    Rectified stereo pair with the image size set.
options : dict
    Nested ``{section: {key: value}}`` (sections orb, stereo, tracking, keyframes, local_ba,
    map); see ``twistslam.Config.to_options()``. Unknown keys raise ValueError.
)doc")
      .def("track",
           [](t::System& s, int index, double timestamp, const py::array& left, const py::array& right,
              const py::object& labels, const py::object& points_c, const py::object& instances,
              const py::object& flow, const py::object& boxes, const py::object& scores,
              const py::object& class_ids, const py::object& open_ends,
              const py::object& point_extents, const py::object& headings_known) {
             const cv::Mat l = image_view(left, "image_left", false);
             std::vector<objects::Detection> detections;
             if (!boxes.is_none())
               detections = detections_from_arrays(boxes, scores, class_ids, py::none(), open_ends,
                                                   point_extents, headings_known);
             Points3 scan;
             if (!points_c.is_none()) scan = points_view(as_rows(points_c, "points_c", 3));
             const cv::Mat r = image_view(right, "image_right", false);
             py::array label_array;
             cv::Mat lab;
             if (!labels.is_none()) {
               label_array = py::array::ensure(labels);
               lab = image_view(label_array, "labels", true);
             }
             py::array instance_array, flow_array;
             cv::Mat inst, flo;
             if (!instances.is_none()) {
               instance_array = py::array::ensure(instances);
               inst = image_view(instance_array, "instances", true);
             }
             if (!flow.is_none()) {
               flow_array = py::array::ensure(flow);
               flo = flow_view(flow_array);
             }
             t::TrackResult result;
             {
               py::gil_scoped_release release;
               try {
                 result = s.track(index, timestamp, l, r, lab, scan, inst, flo, detections);
               } catch (const std::invalid_argument& e) {
                 py::gil_scoped_acquire acquire;
                 throw py::value_error("frame " + std::to_string(index) + ": " + e.what());
               }
             }
             return to_dict(result);
           },
           "index"_a, "timestamp"_a, "image_left"_a, "image_right"_a, "labels"_a = py::none(),
           "points_c"_a = py::none(), "instances"_a = py::none(), "flow"_a = py::none(),
           "boxes"_a = py::none(), "scores"_a = py::none(), "class_ids"_a = py::none(),
           "open_ends"_a = py::none(), "point_extents"_a = py::none(),
           "headings_known"_a = py::none(), R"doc(Track one stereo frame.

Parameters
----------
index : int
    Frame index in the sequence.
timestamp : float
    Seconds.
image_left, image_right : ndarray
    uint8 (H, W) gray or (H, W, 3) colour, C-contiguous, of the camera's size.
labels : ndarray of int32 (H, W), optional
    Semantic class id per pixel; keypoints on ``tracking.dynamic_class_ids`` never track the camera.
points_c : ndarray (N, 3) float, optional
    The frame's LiDAR scan in the rectified reference camera frame c. With
    ``lidar.use_depth`` keypoints near its returns take their depth from it (returns on
    dynamic classes are dropped; non-finite points are skipped). None or (0, 3): stereo only.
instances : ndarray of int32 (H, W), optional
    Panoptic instance id per pixel (0: none); instances of ``visual_objects.object_class_ids``
    (by ``labels``) become object clusters tracked by eq. 4.
flow : ndarray of float32 (H, W, 2), optional
    Optical flow (u, v) px from the previous frame's left image to this one, NaN where
    unknown: the search of object tracking starts at the flow-predicted position.
boxes : ndarray (N, 7) float, optional
    The frame's 3D detections [cx, cy, cz, l, w, h, ry] in frame c (geometric centre, KITTI
    yaw), with ``scores`` (N,) and ``class_ids`` (N,) int in the panoptic vocabulary: the
    LiDAR fusion of object tracking (``lidar_objects``): canonical pose, size and e_det.
open_ends : ndarray (N,) int, optional
    Per box, 0 for a measured length, +1 / -1 for a partly seen car whose prior length runs
    from its seen face to the box's +x / -x end (``Detections3D.open_end``); None: all 0.
point_extents : ndarray (N,) bool, optional
    Per box, true when it is the tight extent of its LiDAR points (the classical detector:
    ``Detections3D.point_extent``): its measured length is a lower bound and its end nearer
    the sensor the seen one; None: all false.
headings_known : ndarray (N,) bool, optional
    Per box, true when its yaw points to the object's front (``Detections3D.heading_known``):
    only such boxes vote for a parked car's heading with their own; None: true where
    ``point_extents`` is false.

Returns
-------
dict
    status ("initialized", "ok", "lost", "relocalized"), T_w_c (4, 4), is_keyframe,
    num_inliers, num_map_points, num_keyframes, num_lidar_depth (keypoints with a LiDAR
    depth), timings_ms {stage: ms}, num_objects_tracked, num_objects_new,
    num_object_points (matched inlier points of all clusters).
)doc")
      .def("objects", [](t::System& s) { finish_ba(s); return objects_to_list(s.objects()); },
           R"doc(Every object cluster ever started, as dicts: the track's fields (id, class_id,
state, link, frames, T_w_o (K, 4, 4) in the world frame, twist (K, 6), detected = a valid twist
was estimated that frame, ...) and ``points_o`` (M, 3) its points in the object frame,
``point_found`` (M,) the frames each was matched in.)doc")
      .def("smooth_objects",
           [](t::System& s) {
             const t::ObjectSmoothingReport r = s.smooth_objects();
             return py::dict("num_tracks"_a = r.num_tracks, "num_rejected"_a = r.num_rejected,
                             "num_residuals"_a = r.num_residuals);
           },
           R"doc(The final smoothing of the object tracks, once the sequence ends
(``visual_objects.final_smoothing``; nothing when it is off): per track, all its rows, every
observation its points made (culled points too), e_const, e_link, e_head and the LiDAR terms
(e_det, the box pose prior, e_reg) in one problem, the cameras fixed at the refined
trajectory. ``objects()`` then gives the smoothed ``T_w_o`` and the online poses as
``T_w_o_online``. A track is smoothed once; one whose smoothed steps exceed
``max_step_m`` keeps its online poses.

Returns
-------
dict
    num_tracks : int, tracks smoothed; num_rejected : int, tracks kept online (a smoothed
    step beyond max_step_m); num_residuals : int, residuals over the smoothed tracks.)doc")
      .def("road_plane",
           [](const t::System& s) {
             const auto& r = s.road_plane();
             const Vec4 plane = r.plane();
             DoubleArray out = new_array({4});
             for (int k = 0; k < 4; ++k) out.mutable_data()[k] = plane[k];
             return py::dict("valid"_a = r.valid(), "plane"_a = out, "num_points"_a = r.num_points(),
                             "num_fits"_a = r.num_fits(), "last_inliers"_a = r.last_inliers());
           },
           R"doc(The road plane that gives the planar link's normal, fitted (RANSAC + SVD) to the
stereo keypoints labelled ``visual_objects.road_class_id`` of the keyframes within
``visual_objects.road_plane_window_m`` of the newest one (0: of every keyframe, a reservoir),
and with ``visual_objects.road_lidar_points`` the scan's returns on road pixels away from the
mask boundary.

Returns
-------
dict
    valid : bool, a fit was accepted (otherwise ``plane`` is the prior: the first camera's up,
    1.65 m below it); plane : (4,) float64 (n, d), n . X_w + d = 0 on the road, n pointing up;
    num_points : int, road points in the reservoir (the window); num_fits, last_inliers : int.)doc")
      .def("trajectory",
           [](t::System& s) {
             finish_ba(s);
             const auto traj = s.trajectory();
             DoubleArray poses = new_array({static_cast<py::ssize_t>(traj.size()), 4, 4});
             py::array_t<std::int64_t> frames(static_cast<py::ssize_t>(traj.size()));
             py::list status;
             for (size_t i = 0; i < traj.size(); ++i) {
               frames.mutable_data()[i] = traj[i].first.frame_index;
               status.append(t::to_string(traj[i].first.status));
               for (int r = 0; r < 4; ++r)
                 for (int c = 0; c < 4; ++c) poses.mutable_data()[i * 16 + r * 4 + c] = traj[i].second(r, c);
             }
             return py::dict("frame_index"_a = frames, "T_w_c"_a = poses, "status"_a = status);
           },
           "Poses T_w_c (N, 4, 4) of every tracked frame, refined through their reference keyframes.")
      .def("keyframes",
           [](t::System& s) {
             finish_ba(s);
             const auto ids = s.map().keyframe_ids();
             DoubleArray poses = new_array({static_cast<py::ssize_t>(ids.size()), 4, 4});
             py::array_t<std::int64_t> frames(static_cast<py::ssize_t>(ids.size()));
             for (size_t i = 0; i < ids.size(); ++i) {
               const auto& kf = s.map().keyframe(ids[i]);
               frames.mutable_data()[i] = kf.frame_index;
               const Mat4 T = kf.T_w_c();
               for (int r = 0; r < 4; ++r)
                 for (int c = 0; c < 4; ++c) poses.mutable_data()[i * 16 + r * 4 + c] = T(r, c);
             }
             return py::dict("frame_index"_a = frames, "T_w_c"_a = poses);
           },
           "Keyframes: frame_index (K,) and T_w_c (K, 4, 4).")
      .def("map_points",
           [](t::System& s) {
             finish_ba(s);
             const auto& pts = s.map().points();
             const auto n = static_cast<py::ssize_t>(pts.size());
             DoubleArray X = new_array({n, 3});
             py::array_t<std::int64_t> cluster(n), nobs(n), label(n);
             py::ssize_t i = 0;
             for (const auto& [id, p] : pts) {
               for (int k = 0; k < 3; ++k) X.mutable_data()[3 * i + k] = p.X_w[k];
               cluster.mutable_data()[i] = p.cluster_id;
               label.mutable_data()[i] = p.label;
               nobs.mutable_data()[i] = static_cast<std::int64_t>(p.observations.size());
               ++i;
             }
             return py::dict("X_w"_a = X, "cluster_id"_a = cluster, "label"_a = label, "num_observations"_a = nobs);
           },
           "Map points: X_w (M, 3), cluster_id (M,), label (M,), num_observations (M,).")
      .def("reset", &t::System::reset, "Forget the map and start again at the next frame.");
}

}  // namespace twistslam::bindings
