// Bindings of cpp/registration: GICP scans (points, KD-tree, plane covariances, built once) and
// the alignment of two of them. Options cross as a dict / keyword arguments checked against
// one field table; points are numpy-checked (N, 3) arrays (float32 / float64, NaN rows dropped).
#include <pybind11/stl.h>

#include <stdexcept>
#include <string>

#include "bindings/numpy_checks.hpp"
#include "bindings/options_table.hpp"
#include "registration/gicp.hpp"

namespace twistslam::bindings {
namespace r = twistslam::registration;
using namespace pybind11::literals;

void bind_pcl_gicp(py::module_& m);  // pcl_gicp_bindings.cpp (bench only)

namespace {

FieldTable gicp_fields(r::GicpOptions* o) {
  const double inf = std::numeric_limits<double>::infinity();
  return {
      {"max_correspondence_distance_m", set(&o->max_correspondence_distance_m, 1e-6, inf)},
      {"max_iterations", set(&o->max_iterations, 1, 1000)},
      {"convergence_translation_m", set(&o->convergence_translation_m, 0.0, inf)},
      {"convergence_rotation_rad", set(&o->convergence_rotation_rad, 0.0, inf)},
      {"num_neighbors", set(&o->num_neighbors, 3, 1000)},
      {"huber_threshold", set(&o->huber_threshold, 1e-9, inf)},
      {"min_correspondences", set(&o->min_correspondences, 1, 1e9)},
      {"max_step_halvings", set(&o->max_step_halvings, 0, 1000)},
      {"kernel", custom(
                     [o](const py::handle& v) {
                       const std::string name = py::str(v);
                       if (name == "none") o->kernel = r::RobustKernel::kNone;
                       else if (name == "huber") o->kernel = r::RobustKernel::kHuber;
                       else throw py::value_error("expected 'none' or 'huber', got '" + name + "'");
                     },
                     [o] { return py::str(o->kernel == r::RobustKernel::kHuber ? "huber" : "none"); })},
  };
}

r::GicpOptions gicp_options(const py::object& options, const py::object& projector,
                            const py::kwargs& kwargs) {
  r::GicpOptions o;
  const FieldTable fields = gicp_fields(&o);
  if (!options.is_none()) {
    if (!py::isinstance<py::dict>(options))
      throw py::type_error("gicp options: expected a dict or None");
    apply_section(options.cast<py::dict>(), "gicp", fields);
  }
  apply_section(kwargs, "gicp", fields);
  if (!projector.is_none()) o.projector = as_mat6(projector, "projector");
  try {
    r::validate(o);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  return o;
}

r::GicpScan make_scan(const py::handle& points, int num_neighbors) {
  if (num_neighbors < 3) throw py::value_error("num_neighbors must be >= 3");
  const DoubleArray a = as_rows(points, "points", 3);
  const auto view = points_view(a);
  py::gil_scoped_release release;
  return r::make_gicp_scan(view, num_neighbors);
}

// A GicpScan as given, or one built from an (N, 3) array with the options' neighbour count.
r::GicpScan scan_of(const py::handle& obj, int num_neighbors, const char* name) {
  if (py::isinstance<r::GicpScan>(obj)) return obj.cast<r::GicpScan>();
  const DoubleArray a = as_rows(obj, name, 3);
  const auto view = points_view(a);
  py::gil_scoped_release release;
  return r::make_gicp_scan(view, num_neighbors);
}

r::GicpResult align(const py::handle& source, const py::handle& target, const py::object& T_init,
                    const py::object& options, const py::object& projector,
                    const py::kwargs& kwargs) {
  const r::GicpOptions o = gicp_options(options, projector, kwargs);
  const Mat4 T0 = T_init.is_none() ? Mat4::Identity() : as_rigid_transform(T_init, "T_init");
  // Scans given as GicpScan objects are used in place (no copy of their tree).
  const bool source_is_scan = py::isinstance<r::GicpScan>(source);
  const bool target_is_scan = py::isinstance<r::GicpScan>(target);
  r::GicpScan source_built, target_built;
  if (!source_is_scan) source_built = scan_of(source, o.num_neighbors, "source");
  if (!target_is_scan) target_built = scan_of(target, o.num_neighbors, "target");
  const r::GicpScan& s = source_is_scan ? source.cast<const r::GicpScan&>() : source_built;
  const r::GicpScan& t = target_is_scan ? target.cast<const r::GicpScan&>() : target_built;
  py::gil_scoped_release release;
  return r::gicp(s, t, T0, o);
}

}  // namespace

void bind_registration(py::module_& m) {
  py::class_<r::GicpScan>(m, "GicpScan", R"doc(
A scan ready for GICP: its finite points, KD-tree and plane covariances, built once by
``make_scan`` (the object scan of frame i is the target at i and the source at i + 1).
)doc")
      .def_property_readonly("num_points", [](const r::GicpScan& s) { return s.points.size(); },
                             "Finite points kept.")
      .def_property_readonly("num_dropped_non_finite",
                             [](const r::GicpScan& s) { return s.num_dropped_non_finite; },
                             "NaN / Inf rows left out.")
      .def_property_readonly("num_neighbors", [](const r::GicpScan& s) { return s.num_neighbors; },
                             "Neighbours per covariance.")
      .def_property_readonly("usable", &r::GicpScan::usable,
                             "False when the scan has fewer finite points than num_neighbors.")
      .def_property_readonly("points", [](const r::GicpScan& s) {
        DoubleArray out = new_array({static_cast<py::ssize_t>(s.points.size()), 3});
        for (std::size_t i = 0; i < s.points.size(); ++i)
          for (int j = 0; j < 3; ++j) out.mutable_data()[3 * i + j] = s.points[i][j];
        return out;
      }, "(N, 3) float64 copy of the finite points (m).");

  py::class_<r::GicpResult>(m, "GicpResult", "Outcome of one GICP alignment.")
      .def_property_readonly("T_target_source",
                             [](const r::GicpResult& x) { return to_numpy(x.T_target_source); },
                             "(4, 4) transform taking source points into the target frame.")
      .def_property_readonly("status", [](const r::GicpResult& x) { return r::status_name(x.status); },
                             "'converged', 'max_iterations', 'too_few_points', "
                             "'too_few_correspondences' or 'degenerate'.")
      .def_readonly("converged", &r::GicpResult::converged)
      .def_readonly("iterations", &r::GicpResult::iterations)
      .def_readonly("num_inliers", &r::GicpResult::num_inliers,
                    "Correspondences within the distance at the last linearisation.")
      .def_readonly("rmse_m", &r::GicpResult::rmse_m, "Euclidean RMS of their residuals (m).")
      .def_readonly("cost", &r::GicpResult::cost, "GICP cost (Mahalanobis, or Huber).")
      .def_property_readonly("information",
                             [](const r::GicpResult& x) { return to_numpy(x.information); },
                             "(6, 6) Gauss-Newton Hessian, twist [v; w] in the target frame.")
      .def("__repr__", [](const r::GicpResult& x) {
        return "GicpResult(status=" + r::status_name(x.status) +
               ", iterations=" + std::to_string(x.iterations) +
               ", num_inliers=" + std::to_string(x.num_inliers) +
               ", rmse_m=" + std::to_string(x.rmse_m) + ")";
      });

  m.def("make_scan", &make_scan, "points"_a, "num_neighbors"_a = r::GicpOptions().num_neighbors,
        R"doc(
Build a GICP scan from points.

Parameters
----------
points : (N, 3) array, float32 or float64
    Object scan (m). Rows with NaN / Inf are dropped (counted in num_dropped_non_finite).
num_neighbors : int
    Neighbours per plane covariance (>= 3; itself included).

Returns
-------
GicpScan
    ``usable`` is False when fewer than num_neighbors finite points remain.
)doc");

  m.def("gicp", &align, "source"_a, "target"_a, "T_init"_a = py::none(), "options"_a = py::none(),
        "projector"_a = py::none(), R"doc(
Generalized ICP: the transform T_target_source aligning ``source`` onto ``target``.

Parameters
----------
source, target : GicpScan or (N, 3) array
    Arrays are turned into scans with the options' num_neighbors (scans are reused as built).
T_init : (4, 4) array or None
    Initial guess (rigid; identity when None), e.g. the tracking prediction.
options : dict or None
    GICP options (see ``default_options``); keyword arguments override it.
projector : (6, 6) array or None
    Link projector Pi on the twist [v; w] in the target frame (geometry.projector_planar);
    the update is T <- exp(Pi delta) T. None = free motion.

Returns
-------
GicpResult
    Bad input (too few points, no correspondences) gives ``converged`` False and a status.
)doc");

  m.def("default_options", [] {
    r::GicpOptions o;
    return dump_section(gicp_fields(&o));
  }, "Every GICP option with its default value (units in docs/registration.md).");

  bind_pcl_gicp(m);
}

}  // namespace twistslam::bindings
