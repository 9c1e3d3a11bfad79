// Bindings of cpp/objects: the 3D multi-object tracker from detections and the assignment.
#include <pybind11/stl.h>

#include "bindings/numpy_checks.hpp"
#include "bindings/options_table.hpp"
#include "objects/assignment.hpp"
#include "objects/tracker.hpp"

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

// One track as numpy arrays (K = its backcast frames, then its frames).
py::dict track_to_dict(const o::ObjectTrack& t) {
  std::vector<const o::TrackFrame*> rows;
  rows.reserve(t.backcast.size() + t.frames.size());
  for (const auto& f : t.backcast) rows.push_back(&f);
  for (const auto& f : t.frames) rows.push_back(&f);
  const auto K = static_cast<py::ssize_t>(rows.size());
  DoubleArray poses = new_array({K, 4, 4}), detected_poses = new_array({K, 4, 4});
  DoubleArray twists = new_array({K, 6}), scores = new_array({K}), sizes = new_array({K, 3});
  DoubleArray ranges = new_array({K}), confidences = new_array({K});
  py::array_t<std::int64_t> frames(K), det_index(K);
  py::array_t<bool> detected(K), reported(K);
  for (py::ssize_t k = 0; k < K; ++k) {
    const auto& f = *rows[k];
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        poses.mutable_data()[k * 16 + r * 4 + c] = f.T_w_o(r, c);
        detected_poses.mutable_data()[k * 16 + r * 4 + c] = f.T_w_o_detected(r, c);
      }
    for (int i = 0; i < 6; ++i) twists.mutable_data()[k * 6 + i] = f.xi[i];
    for (int i = 0; i < 3; ++i) sizes.mutable_data()[k * 3 + i] = f.detected_size[i];
    scores.mutable_data()[k] = f.score;
    ranges.mutable_data()[k] = f.range;
    confidences.mutable_data()[k] = f.confidence;
    frames.mutable_data()[k] = f.frame;
    det_index.mutable_data()[k] = f.detection_index;
    detected.mutable_data()[k] = f.detected;
    reported.mutable_data()[k] = f.reported;
  }
  return py::dict("id"_a = t.id, "class_id"_a = t.class_id, "state"_a = o::to_string(t.state),
                  "link"_a = t.link == geometry::LinkType::kPlanar ? "planar" : "free",
                  "size"_a = to_numpy(t.size), "hits"_a = t.hits, "confirmed_frame"_a = t.confirmed_frame,
                  "mean_score"_a = t.mean_score(), "confidence"_a = t.confidence(),
                  "backcast"_a = static_cast<int>(t.backcast.size()), "frames"_a = frames,
                  "T_w_o"_a = poses, "T_w_o_detected"_a = detected_poses, "twist"_a = twists,
                  "detected"_a = detected, "reported"_a = reported, "score"_a = scores,
                  "range"_a = ranges, "frame_confidence"_a = confidences,
                  "detected_size"_a = sizes, "detection_index"_a = det_index);
}

}  // namespace

void bind_objects(py::module_& m) {
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
             const DoubleArray b = as_rows(boxes, "boxes", 7);
             const auto n = b.shape(0);
             const DoubleArray s = as_double_array(scores, "scores");
             const auto c = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(class_ids);
             const auto p = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(planar);
             if (!c || !p) throw py::type_error("class_ids / planar: expected integer / boolean arrays");
             if (s.ndim() != 1 || s.shape(0) != n || c.ndim() != 1 || c.shape(0) != n || p.ndim() != 1 || p.shape(0) != n)
               throw py::value_error("scores, class_ids, planar: expected (" + std::to_string(n) +
                                     ",) arrays like boxes, got " + shape_string(s) + ", " +
                                     shape_string(c) + ", " + shape_string(p));
             std::vector<o::Detection> dets(n);
             for (py::ssize_t i = 0; i < n; ++i) {
               dets[i].box = geometry::Box3D::from_row(b.data() + 7 * i);
               dets[i].score = s.data()[i];
               dets[i].class_id = static_cast<int>(c.data()[i]);
               dets[i].planar = p.data()[i];
             }
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
