// Bindings of cpp/objects: the 3D multi-object tracker from detections and the assignment.
#include <pybind11/stl.h>

#include <cmath>

#include "bindings/detection_arrays.hpp"
#include "bindings/numpy_checks.hpp"
#include "bindings/object_track_dict.hpp"
#include "bindings/options_table.hpp"
#include "objects/assignment.hpp"
#include "objects/tracker.hpp"
#include "objects/twist_estimation.hpp"

namespace twistslam::bindings {
using namespace pybind11::literals;
namespace o = twistslam::objects;

namespace {

FieldTable tracker_fields(o::TrackerOptions& t) {
  auto& w = t.window_options;
  return {
      {"association", custom([&t](const py::handle& v) { t.metric = o::association_metric_from_string(v.cast<std::string>()); },
                             [&t] { return py::cast(std::string(o::to_string(t.metric))); })},
      {"max_cost", set(&t.max_cost)}, {"second_pass", set(&t.second_pass)},
      {"second_pass_max_cost", set(&t.second_pass_max_cost)}, {"high_score", set(&t.high_score)},
      {"low_score", set(&t.low_score)}, {"birth_score", set(&t.birth_score)},
      {"birth_hits", set(&t.birth_hits)}, {"max_misses", set(&t.max_misses)},
      {"tentative_max_misses", set(&t.tentative_max_misses)},
      {"ground_normal", custom([&t](const py::handle& v) { t.ground_normal = as_vec3(v, "objects.ground_normal"); },
                               [&t] { return py::cast(std::vector<double>{t.ground_normal.x(), t.ground_normal.y(), t.ground_normal.z()}); })},
      {"optimize", set(&t.optimize)}, {"window", set(&t.window)},
      {"report_tentative_frames", set(&t.report_tentative_frames)},
      {"max_reported_gap", set(&t.max_reported_gap)},
      {"range_score_start", set(&t.range_score_start)}, {"range_score_slope", set(&t.range_score_slope)},
      {"backcast_frames", set(&t.backcast_frames)}, {"backcast_min_range", set(&t.backcast_min_range)},
      {"interpolate_gaps", set(&t.interpolate_gaps)}, {"miss_turn_decay", set(&t.miss_turn_decay)},
      {"const_sigma_translation", set(&w.const_sigma_translation)},
      {"const_sigma_rotation", set(&w.const_sigma_rotation)},
      {"det_sigma_translation", set(&w.det_sigma_translation)},
      {"det_sigma_rotation", set(&w.det_sigma_rotation)},
      {"prior_sigma_translation", set(&w.prior_sigma_translation)},
      {"prior_sigma_rotation", set(&w.prior_sigma_rotation)},
      {"link_sigma_translation", set(&w.link_sigma_translation)},
      {"link_sigma_rotation", set(&w.link_sigma_rotation)},
      {"huber_const", set(&w.huber_const)}, {"huber_det", set(&w.huber_det)},
      {"huber_prior", set(&w.huber_prior)}, {"use_const", set(&w.use_const)},
      {"use_det_twist", set(&w.use_det_twist)}, {"use_prior", set(&w.use_prior)},
      {"use_link", set(&w.use_link)}, {"max_iterations", set(&w.max_iterations)},
  };
}

o::TrackerOptions parse_tracker_options(const py::dict& options) {
  o::TrackerOptions t;
  try {
    apply_section(options, "objects", tracker_fields(t));
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string("options: ") + e.what());
  }
  return t;
}

}  // namespace

void bind_object_twist(py::module_& m);  // estimate_object_twist, at the end

void bind_objects(py::module_& m) {
  bind_object_twist(m);
  m.def("default_tracker_options", [] { o::TrackerOptions t; return dump_section(tracker_fields(t)); },
        "The C++ defaults of every tracker option, {key: value} as Tracker() takes them.");
  m.def("solve_assignment",
        [](py::handle cost, double max_cost) {
          const DoubleArray c = as_double_array(cost, "cost");
          if (c.ndim() != 2) throw py::value_error("cost: expected a 2-D array, got " + shape_string(c));
          const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> view(
              c.data(), c.shape(0), c.shape(1));
          const auto pairs = o::solve_assignment(view, max_cost);
          py::array_t<std::int64_t> out({static_cast<py::ssize_t>(pairs.size()), py::ssize_t{2}});
          for (size_t k = 0; k < pairs.size(); ++k) {
            out.mutable_data()[2 * k] = pairs[k].first;
            out.mutable_data()[2 * k + 1] = pairs[k].second;
          }
          return out;
        },
        "cost"_a, "max_cost"_a, R"doc(Minimum-cost one-to-one assignment (Hungarian method).

Parameters
----------
cost : (N, M) array_like
    Pair costs; a pair is allowed when its cost is finite and <= max_cost.
max_cost : float

Returns
-------
(K, 2) int64 ndarray
    (row, column) pairs: the most allowed pairs, then the least total cost among them.
)doc");

  py::class_<o::Tracker>(m, "Tracker", "3D multi-object tracker from detections (cpp/objects).")
      .def(py::init([](const py::dict& options) { return std::make_unique<o::Tracker>(parse_tracker_options(options)); }),
           "options"_a = py::dict(), R"doc(Create a tracker.

Parameters
----------
options : dict
    ``{key: value}`` of the ``objects`` config section (``twistslam.Config().objects``);
    unknown keys raise ValueError.
)doc")
      .def("step",
           [](o::Tracker& tr, int frame, py::handle T_w_c, py::handle boxes, py::handle scores,
              py::handle class_ids, py::handle planar) {
             const Mat4 T = as_mat4(T_w_c, "T_w_c");
             if (planar.is_none()) throw py::type_error("planar: expected a boolean array");
             const std::vector<o::Detection> dets = detections_from_arrays(boxes, scores, class_ids, planar);
             py::gil_scoped_release release;
             try {
               tr.step(frame, T, dets);
             } catch (const std::invalid_argument& e) {
               py::gil_scoped_acquire acquire;
               throw py::value_error(e.what());
             }
           },
           "frame"_a, "T_w_c"_a, "boxes"_a, "scores"_a, "class_ids"_a, "planar"_a, R"doc(Track one frame.

Parameters
----------
frame : int
    Frame index, larger than the previous call's (skipped frames are predicted).
T_w_c : (4, 4) array_like
    Camera pose in the tracking frame (identity: track in each frame's camera frame).
boxes : (N, 7) array_like
    Detections [cx, cy, cz, l, w, h, ry] in this frame's camera frame (geometric centre).
scores : (N,) array_like
class_ids : (N,) int array_like
    Tracks and detections associate within a class only.
planar : (N,) bool array_like
    The class moves on the ground plane (planar link) or freely.

Raises
------
ValueError
    Frame out of order, non-finite pose, a detection with a non-finite value or a
    non-positive size, arrays of mismatched shapes.
)doc")
      .def("tracks", [](o::Tracker& tr) {
             py::list out;
             for (const auto& t : tr.tracks()) out.append(track_to_dict(t));
             return out;
           },
           R"doc(Every track born so far (dead ones included), each a dict of numpy arrays:
``id``, ``class_id``, ``state``, ``link``, ``size`` (3,) l w h (median of the detections),
``hits``, ``confirmed_frame``, ``mean_score``, ``confidence`` (mean range-corrected score: the
track score of the results), ``backcast`` (number of leading rows predicted before the first
frame), and per frame of the track (K rows, consecutive frames, the backcast first):
``frames``, ``T_w_o`` (K, 4, 4), ``T_w_o_detected``, ``twist`` (K, 6) to the next frame,
``detected``, ``reported`` (the output policy), ``score`` (the detector's), ``range`` (m from
the camera), ``frame_confidence`` (range-corrected score), ``detected_size``,
``detection_index``.)doc")
      .def_property_readonly("num_live", &o::Tracker::num_live, "Tracks not dead.")
      .def_property_readonly("last_frame", &o::Tracker::last_frame, "Last frame stepped (-1: none).");
}

}  // namespace twistslam::bindings

// ---- Object twist estimation (paper eq. 4, cpp/objects/twist_estimation.hpp) ----
namespace twistslam::bindings {
namespace {

FieldTable twist_estimation_fields(objects::TwistEstimationOptions& t) {
  return {{"max_iterations", set(&t.max_iterations, 1, 1000)},
          {"refine_iterations", set(&t.refine_iterations, 0, 1000)},
          {"huber_k", set(&t.huber_k, 1e-6, 1e6)}, {"min_sigma_px", set(&t.min_sigma_px, 1e-6, 1e6)},
          {"max_sigma_px", set(&t.max_sigma_px, 1e-6, 1e6)},
          {"inlier_chi2_stereo", set(&t.inlier_chi2_stereo, 1e-6, 1e6)},
          {"inlier_chi2_mono", set(&t.inlier_chi2_mono, 1e-6, 1e6)},
          {"min_inliers", set(&t.min_inliers, 1, 1e9)}, {"min_depth", set(&t.min_depth, 1e-9, 1e6)},
          {"initial_lambda", set(&t.initial_lambda, 1e-12, 1e12)},
          {"step_tolerance", set(&t.step_tolerance, 0, 1)}};
}

// (N,) float64 vector or, for None, N copies of `fill`.
std::vector<double> optional_column(const py::object& obj, const char* name, py::ssize_t n, double fill) {
  if (obj.is_none()) return std::vector<double>(n, fill);
  const DoubleArray a = as_double_array(obj, name);
  if (a.ndim() != 1 || a.shape(0) != n)
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) + ",), got " + shape_string(a));
  return std::vector<double>(a.data(), a.data() + n);
}

}  // namespace

void bind_object_twist(py::module_& m) {
  m.def("default_twist_estimation_options",
        [] { objects::TwistEstimationOptions t; return dump_section(twist_estimation_fields(t)); },
        "The C++ defaults of estimate_object_twist's keyword options.");
  m.def("estimate_object_twist",
        [](const geometry::StereoCamera& camera, py::handle T_c_w, py::handle T_w_o_prev, py::handle Pi,
           py::handle points_o, py::handle uv, const py::object& u_right, const py::object& inv_sigma2,
           const py::object& xi_init, const py::kwargs& kwargs) {
          objects::TwistEstimationOptions opt;
          apply_keywords(kwargs, "estimate_object_twist", twist_estimation_fields(opt));
          const Mat4 Tcw = as_rigid_transform(T_c_w, "T_c_w"), Two = as_rigid_transform(T_w_o_prev, "T_w_o_prev");
          const Mat6 P = as_mat6(Pi, "Pi");
          const Vec6 xi0 = xi_init.is_none() ? Vec6::Zero() : as_vec6(xi_init, "xi_init");
          const DoubleArray X = as_rows(points_o, "points_o", 3), z = as_rows(uv, "uv", 2);
          const py::ssize_t n = X.shape(0);
          if (z.shape(0) != n)
            throw py::value_error("uv: expected " + std::to_string(n) + " rows like points_o, got " + shape_string(z));
          const auto ur = optional_column(u_right, "u_right", n, -1.0);
          const auto w = optional_column(inv_sigma2, "inv_sigma2", n, 1.0);
          std::vector<objects::TwistObservation> obs(n);
          for (py::ssize_t j = 0; j < n; ++j) {
            obs[j].X_o = Vec3(X.data()[3 * j], X.data()[3 * j + 1], X.data()[3 * j + 2]);
            obs[j].uv = Vec2(z.data()[2 * j], z.data()[2 * j + 1]);
            obs[j].u_right = std::isnan(ur[j]) ? -1.0 : ur[j];  // NaN = unmatched in match_stereo
            obs[j].inv_sigma2 = w[j];
          }
          objects::TwistEstimate e;
          {
            py::gil_scoped_release release;
            e = objects::estimate_object_twist(camera, Tcw, Two, P, obs, xi0, opt);
          }
          py::array_t<bool> inlier(n);
          for (py::ssize_t j = 0; j < n; ++j) inlier.mutable_data()[j] = e.inlier[j];
          return py::dict("valid"_a = e.valid, "failure"_a = e.failure, "xi"_a = to_numpy(e.xi),
                          "T_w_o"_a = to_numpy(e.T_w_o), "covariance"_a = to_numpy(e.covariance),
                          "sigma_px"_a = e.sigma_px, "inlier"_a = inlier, "num_inliers"_a = e.num_inliers,
                          "iterations"_a = e.iterations, "final_rms_px"_a = e.final_rms_px);
        },
        "camera"_a, "T_c_w"_a, "T_w_o_prev"_a, "Pi"_a, "points_o"_a, "uv"_a, "u_right"_a = py::none(),
        "inv_sigma2"_a = py::none(), "xi_init"_a = py::none(),
        R"doc(Twist of one object between two frames from its keypoints (TwistSLAM eq. 4).

Minimises sum_j rho(|z_j - proj(T_c_w exp(Pi xi) T_w_o_prev X_o_j)|) by Levenberg-Marquardt
inside range(Pi), Huber rho with a MAD-based scale, then re-solves on the chi2 inliers.

Parameters
----------
camera : twistslam.geometry.StereoCamera
    The rectified pair; its ``disparity_offset`` is part of the stereo measurement.
T_c_w : (4, 4) array_like
    Current camera pose (world to camera).
T_w_o_prev : (4, 4) array_like
    Object pose at the previous frame.
Pi : (6, 6) array_like
    Link projector (``projector_planar(n)`` / identity); twists are [v; w].
points_o : (N, 3) array_like
    Object points in the object frame, m.
uv : (N, 2) array_like
    Their keypoints in the current left image, px.
u_right : (N,) array_like, optional
    Right-image columns, px; negative or NaN for a mono observation. None: all mono.
inv_sigma2 : (N,) array_like, optional
    1 / sigma^2 of each keypoint's pyramid level. None: all 1.
xi_init : (6,) array_like, optional
    Initial twist (projected onto range(Pi)). None: zero.
**options
    Keys of ``default_twist_estimation_options()``.

Returns
-------
dict
    ``valid``, ``failure`` (why not valid), ``xi`` (6,), ``T_w_o`` (4, 4) = exp(xi) T_w_o_prev,
    ``covariance`` (6, 6) of xi, ``sigma_px``, ``inlier`` (N,) bool, ``num_inliers``,
    ``iterations``, ``final_rms_px``.

Raises
------
ValueError
    Wrong shapes, non-finite poses or Pi, a pose that is not rigid, an option out of range.
TypeError
    An unknown option or one of the wrong type.
)doc");
}

}  // namespace twistslam::bindings
