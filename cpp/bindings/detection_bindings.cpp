// Bindings of cpp/detection: the classical LiDAR 3D detector. Options cross as a dict and / or
// keyword arguments checked against the one field table of DetectorOptions (unknown keys and
// out-of-range values raise ValueError naming "detection.<key>").
#include <pybind11/stl.h>

#include <cstdint>
#include <stdexcept>
#include <string>

#include "bindings/numpy_checks.hpp"
#include "bindings/options_table.hpp"
#include "detection/detector.hpp"

namespace twistslam::bindings {
namespace d = twistslam::detection;
using namespace pybind11::literals;

namespace {

// options dict merged with keyword arguments (keywords win), validated.
d::DetectorOptions detector_options(const py::object& options, const py::kwargs& kwargs) {
  d::DetectorOptions o;
  const FieldTable fields = field_table(o);
  if (!options.is_none()) {
    if (!py::isinstance<py::dict>(options))
      throw py::type_error("detection options: expected a dict or None");
    apply_section(options.cast<py::dict>(), "detection", fields);
  }
  apply_keywords(kwargs, "detect", fields);
  try {
    d::validate(o);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  return o;
}

// (N, >=3) array of any numeric dtype -> (N, 3) float64 rows (extra columns, e.g. the
// intensity of Frame.points_c, are ignored).
Points3 xyz_rows(const py::handle& obj) {
  const DoubleArray a = as_double_array(obj, "points_c");
  if (a.ndim() != 2 || a.shape(1) < 3)
    throw py::value_error("points_c: expected shape (N, 3) or (N, >=3), got " + shape_string(a));
  const py::ssize_t n = a.shape(0), cols = a.shape(1);
  using Strided = Eigen::Map<const Points3, 0, Eigen::OuterStride<>>;
  return Strided(a.data(), n, 3, Eigen::OuterStride<>(cols));
}

py::dict run_detect(const py::handle& points_c, const py::object& options, const py::kwargs& kwargs) {
  const d::DetectorOptions o = detector_options(options, kwargs);
  const Points3 xyz = xyz_rows(points_c);
  d::DetectorResult r;
  {
    py::gil_scoped_release release;  // pure C++ from here: other Python threads may run
    r = d::detect(xyz, o);
  }
  const auto n = static_cast<py::ssize_t>(r.detections.size());
  DoubleArray boxes = new_array({n, 7});
  DoubleArray scores = new_array({n});
  py::array_t<int> num_points(n);
  py::array_t<bool> length_seen(n);
  py::array_t<std::int8_t> open_end(n);
  py::array_t<bool> heading_known(n);
  DoubleArray edge_distance = new_array({n});
  DoubleArray surface_variation = new_array({n});
  py::list classes;
  for (py::ssize_t i = 0; i < n; ++i) {
    const d::Detection& det = r.detections[static_cast<std::size_t>(i)];
    const double row[7] = {det.centre.x(), det.centre.y(), det.centre.z(), det.length,
                           det.width, det.height, det.yaw};
    std::copy(row, row + 7, boxes.mutable_data() + 7 * i);
    scores.mutable_data()[i] = det.score;
    num_points.mutable_data()[i] = det.num_points;
    length_seen.mutable_data()[i] = det.length_seen;
    open_end.mutable_data()[i] = static_cast<std::int8_t>(det.open_end);
    heading_known.mutable_data()[i] = det.heading_known;
    edge_distance.mutable_data()[i] = det.edge_distance_m;
    surface_variation.mutable_data()[i] = det.surface_variation;
    classes.append(d::to_string(det.cls));
  }
  const py::dict timings("select_ms"_a = r.timings.select_ms, "ground_ms"_a = r.timings.ground_ms,
                         "cluster_ms"_a = r.timings.cluster_ms, "fit_ms"_a = r.timings.fit_ms);
  return py::dict("boxes"_a = boxes, "scores"_a = scores, "classes"_a = classes,
                  "num_points"_a = num_points, "length_seen"_a = length_seen,
                  "open_end"_a = open_end, "heading_known"_a = heading_known,
                  "edge_distance_m"_a = edge_distance,
                  "surface_variation"_a = surface_variation,
                  "num_non_finite"_a = r.num_non_finite,
                  "num_selected"_a = r.num_selected, "num_obstacle"_a = r.num_obstacle,
                  "num_clusters"_a = r.num_clusters, "timings"_a = timings,
                  "top_beam"_a = py::dict("valid"_a = r.top_beam.valid, "a"_a = r.top_beam.a,
                                          "b"_a = r.top_beam.b, "c"_a = r.top_beam.c,
                                          "d"_a = r.top_beam.d, "num_bins"_a = r.top_beam.num_bins,
                                          "rms_m"_a = r.top_beam.rms_m));
}

}  // namespace

void bind_detection(py::module_& m) {
  m.def("detect", &run_detect, "points_c"_a, "options"_a = py::none(),
        R"doc(Classical LiDAR 3D detection of one scan (ground removal, clustering, L-shape fit).

Parameters
----------
points_c : (N, 3) or (N, >=3) array
    Points in the rectified camera frame c (x right, y down, z forward), e.g.
    ``Frame.points_c``; columns past the third (intensity) are ignored. N may be 0; rows with
    NaN / Inf are skipped and counted.
options : dict, optional
    Detector options (see ``default_options``; units in docs/detection.md); keyword
    arguments override it.

Returns
-------
dict
    ``boxes`` (M, 7) float64 ``[x, y, z, l, w, h, yaw]`` geometric centre in frame c, KITTI
    ``rotation_y``: in [-pi, pi) pointing to the car's front where ``heading_known``, else
    in [-pi/2, pi/2) (the fit knows it mod pi); ``scores`` (M,) float64 in (0, 1]; ``classes`` list of M
    KITTI type names (Car, Pedestrian, Cyclist); ``num_points`` (M,) int32 returns per box;
    ``length_seen`` (M,) bool, a car whose length was measured (an L-shape) rather than
    set by the ``car_length_m`` prior behind its visible face; ``open_end`` (M,) int8, for
    such a box the end (+1 the +x end along its heading, -1 the -x end) that the prior
    extended past the seen face, else 0; ``heading_known`` (M,) bool, a car whose front
    was told from the height profile of its returns (``front_from_profile``); ``edge_distance_m`` (M,) float64, the mean distance
    (m) of the box's footprint returns to the nearest edge of their fitted rectangle (a car's
    faces: a few cm; cars above ``car_max_edge_distance_m`` are not reported);
    ``surface_variation`` (M,) float64, a car's median surface variation (0 for other
    classes and cars too sparse to judge; cars above ``car_max_surface_variation`` are not
    reported: foliage); sorted by
    decreasing score. Also ``num_non_finite``, ``num_selected``, ``num_obstacle``,
    ``num_clusters``, ``timings`` (ms per stage: select, ground, cluster, fit) and
    ``top_beam``: the LiDAR's highest beam fitted to the scan, ``up = a + b r + c x + d z`` (m,
    up = -y, r = hypot(x, z)), with ``valid``, ``num_bins`` (envelope bins on it) and
    ``rms_m`` (their residual); ``valid`` False when the scan shows no beam or
    ``person_top_beam_margin_m`` is 0 (docs/detection.md, "Posts cut by the top beam").

Raises
------
ValueError
    Wrong shape, an unknown or out-of-range option.
TypeError
    A non-numeric array, an option of the wrong type or an unknown keyword.
)doc");
  m.def("default_options", [] {
    d::DetectorOptions o;
    return dump_section(field_table(o));
  }, "Every detector option with its default value (units and reasons in docs/detection.md).");
  m.def("option_ranges", [] {
    d::DetectorOptions o;
    return dump_ranges(field_table(o));
  }, "Valid range (lo, hi) of every numeric detector option, inclusive, in its unit.");
}

}  // namespace twistslam::bindings
