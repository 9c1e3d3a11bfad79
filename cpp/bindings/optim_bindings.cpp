// Bindings of cpp/optim: pose-only optimisation (camera tracking, paper eq. 3) and local
// bundle adjustment (paper eq. 9, static term). Inputs are numpy arrays, checked here
// (ValueError naming the argument); the solvers run without the GIL.
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "bindings/numpy_checks.hpp"
#include "bindings/options_table.hpp"
#include "geometry/se3.hpp"
#include "geometry/stereo_camera.hpp"
#include "optim/bundle_adjustment.hpp"
#include "optim/pose_optimization.hpp"

namespace twistslam::bindings {
namespace g = twistslam::geometry;
namespace o = twistslam::optim;
using namespace pybind11::literals;

namespace {

// (n,) float64 vector; None gives `fill` repeated n times.
std::vector<double> as_vector(const py::handle& obj, const char* name, py::ssize_t n,
                              double fill) {
  if (obj.is_none()) return std::vector<double>(static_cast<size_t>(n), fill);
  const DoubleArray a = as_double_array(obj, name);
  if (a.ndim() != 1 || a.shape(0) != n) {
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) +
                          ",), got " + shape_string(a));
  }
  return std::vector<double>(a.data(), a.data() + n);
}

// (n,) bool flags from a bool / integer array; None gives all false.
std::vector<bool> as_flags(const py::handle& obj, const char* name, py::ssize_t n) {
  if (obj.is_none()) return std::vector<bool>(static_cast<size_t>(n), false);
  py::array arr = py::array::ensure(obj);
  if (!arr) throw py::type_error(std::string(name) + ": expected a numpy array (or array-like)");
  const char kind = arr.dtype().kind();
  if (kind != 'b' && kind != 'i' && kind != 'u') {
    throw py::type_error(std::string(name) + ": expected a bool array, got dtype " +
                         std::string(py::str(arr.dtype())));
  }
  auto b = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(arr);
  if (b.ndim() != 1 || b.shape(0) != n) {
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) +
                          ",), got " + shape_string(b));
  }
  return std::vector<bool>(b.data(), b.data() + n);
}

// (n,) indices from an integer array, each in [0, limit).
std::vector<int> as_indices(const py::handle& obj, const char* name, py::ssize_t n,
                            py::ssize_t limit, const char* what) {
  py::array arr = py::array::ensure(obj);
  if (!arr) throw py::type_error(std::string(name) + ": expected a numpy array (or array-like)");
  const char kind = arr.dtype().kind();
  if (kind != 'i' && kind != 'u') {
    throw py::type_error(std::string(name) + ": expected an integer array, got dtype " +
                         std::string(py::str(arr.dtype())));
  }
  auto a = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(arr);
  if (a.ndim() != 1 || a.shape(0) != n) {
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) +
                          ",), got " + shape_string(a));
  }
  std::vector<int> out(static_cast<size_t>(n));
  for (py::ssize_t i = 0; i < n; ++i) {
    const std::int64_t v = a.data()[i];
    if (v < 0 || v >= limit) {
      throw py::value_error(std::string(name) + ": index " + std::to_string(v) + " at " +
                            std::to_string(i) + " is outside [0, " + std::to_string(limit) +
                            ") (" + std::to_string(limit) + " " + what + ")");
    }
    out[static_cast<size_t>(i)] = static_cast<int>(v);
  }
  return out;
}

// **options of optimize_pose, with the range of each (inclusive, the option's unit). A gate
// or Huber kink of 0 is undefined, so those start just above 0; the upper bounds lie far past
// any useful value (1e4 is a 100-sigma gate, 1000 iterations "until converged").
FieldTable pose_option_fields(o::PoseOptimizationOptions& opt) {
  return {{"rounds", set(&opt.rounds, 0, 100)},
          {"iterations_per_round", set(&opt.iterations_per_round, 0, 1000)},
          {"chi2_stereo", set(&opt.chi2_stereo, 1e-6, 1e4)},
          {"chi2_mono", set(&opt.chi2_mono, 1e-6, 1e4)},
          {"huber_delta_stereo", set(&opt.huber_delta_stereo, 1e-6, 1e3)},
          {"huber_delta_mono", set(&opt.huber_delta_mono, 1e-6, 1e3)},
          {"min_depth", set(&opt.min_depth, 0.0, 1e3)},  // m
          {"min_inliers", set(&opt.min_inliers, 0, 1000000)}};
}

o::BALinearSolver linear_solver_from_string(const std::string& s) {
  if (s == "auto") return o::BALinearSolver::kAuto;
  if (s == "builtin_dense_schur") return o::BALinearSolver::kBuiltinDenseSchur;
  if (s == "dense_schur") return o::BALinearSolver::kDenseSchur;
  if (s == "sparse_schur") return o::BALinearSolver::kSparseSchur;
  if (s == "iterative_schur") return o::BALinearSolver::kIterativeSchur;
  throw py::value_error("expected 'auto', 'builtin_dense_schur', 'dense_schur', 'sparse_schur' or "
                        "'iterative_schur', got '" + s + "'");
}

// **options of bundle_adjust (ranges as pose_option_fields).
FieldTable ba_option_fields(o::BundleAdjustmentOptions& opt) {
  return {{"max_iterations_first", set(&opt.max_iterations_first, 0, 1000)},
          {"max_iterations_second", set(&opt.max_iterations_second, 0, 1000)},
          {"huber_delta_stereo", set(&opt.huber_delta_stereo, 1e-6, 1e3)},
          {"huber_delta_mono", set(&opt.huber_delta_mono, 1e-6, 1e3)},
          {"chi2_stereo", set(&opt.chi2_stereo, 1e-6, 1e4)},
          {"chi2_mono", set(&opt.chi2_mono, 1e-6, 1e4)},
          {"remove_outliers", set(&opt.remove_outliers)},
          {"num_threads", set(&opt.num_threads, 1, 256)},
          {"min_depth", set(&opt.min_depth, 0.0, 1e3)},  // m
          {"function_tolerance", set(&opt.function_tolerance, 1e-16, 1.0)},  // relative
          {"initial_trust_region_radius", set(&opt.initial_trust_region_radius, 1e-6, 1e16)},
          {"linear_solver",
           custom([&opt](const py::handle& v) {
                    if (!py::isinstance<py::str>(v))
                      throw py::type_error("expected a str, got " + std::string(py::str(py::type::of(v))));
                    opt.linear_solver = linear_solver_from_string(v.cast<std::string>());
                  },
                  [] { return py::none(); })}};
}

py::array_t<bool> to_bool_array(const std::vector<std::uint8_t>& flags) {
  py::array_t<bool> out(static_cast<py::ssize_t>(flags.size()));
  for (size_t i = 0; i < flags.size(); ++i) out.mutable_data()[i] = flags[i] != 0;
  return out;
}

py::dict optimize_pose_py(const py::handle& T_init, const py::handle& points_w,
                          const py::handle& uv, const py::handle& u_right,
                          const py::handle& inv_sigma2, const g::StereoCamera& cam,
                          const py::kwargs& kwargs) {
  const Mat4 T0 = as_rigid_transform(T_init, "T_c_w_init");
  const DoubleArray P = as_rows(points_w, "points_w", 3);
  const py::ssize_t n = P.shape(0);
  const DoubleArray px = as_rows(uv, "uv", 2);
  if (px.shape(0) != n) {
    throw py::value_error("uv: expected shape (" + std::to_string(n) + ", 2) to match points_w, got " +
                          shape_string(px));
  }
  const std::vector<double> ur = as_vector(u_right, "u_right", n, -1.0);
  const std::vector<double> info = as_vector(inv_sigma2, "inv_sigma2", n, 1.0);

  o::PoseOptimizationOptions opt;
  apply_keywords(kwargs, "optimize_pose", pose_option_fields(opt));

  std::vector<o::StereoObservation> obs(static_cast<size_t>(n));
  for (py::ssize_t i = 0; i < n; ++i) {
    auto& ob = obs[static_cast<size_t>(i)];
    ob.point_w = Vec3(P.data()[3 * i], P.data()[3 * i + 1], P.data()[3 * i + 2]);
    ob.uv = Vec2(px.data()[2 * i], px.data()[2 * i + 1]);
    ob.u_right = ur[static_cast<size_t>(i)];
    ob.inv_sigma2 = info[static_cast<size_t>(i)];
  }
  o::PoseOptimizationResult r;
  {
    py::gil_scoped_release release;
    r = o::optimize_pose(T0, obs, cam, opt);
  }
  py::dict out;
  out["T_c_w"] = to_numpy(r.T_c_w);
  out["inlier"] = to_bool_array(r.inlier);
  out["num_inliers"] = r.num_inliers;
  out["converged"] = r.converged;
  out["final_cost"] = r.final_cost;
  out["iterations"] = r.iterations;
  return out;
}

py::dict bundle_adjust_py(const py::handle& poses, const py::handle& fixed_poses,
                          const py::handle& points_w, const py::handle& fixed_points,
                          const py::handle& obs_keyframe, const py::handle& obs_point,
                          const py::handle& uv, const py::handle& u_right,
                          const py::handle& inv_sigma2, const g::StereoCamera& cam,
                          const py::kwargs& kwargs) {
  const DoubleArray T = as_double_array(poses, "poses_c_w");
  if (T.ndim() != 3 || T.shape(1) != 4 || T.shape(2) != 4) {
    throw py::value_error("poses_c_w: expected shape (K, 4, 4), got " + shape_string(T));
  }
  const py::ssize_t K = T.shape(0);
  const std::vector<bool> kf_fixed = as_flags(fixed_poses, "fixed_poses", K);
  const DoubleArray P = as_rows(points_w, "points_w", 3);
  const py::ssize_t M = P.shape(0);
  const std::vector<bool> pt_fixed = as_flags(fixed_points, "fixed_points", M);
  const DoubleArray px = as_rows(uv, "uv", 2);
  const py::ssize_t E = px.shape(0);
  const std::vector<int> kf_idx = as_indices(obs_keyframe, "obs_keyframe", E, K, "keyframes");
  const std::vector<int> pt_idx = as_indices(obs_point, "obs_point", E, M, "points");
  const std::vector<double> ur = as_vector(u_right, "u_right", E, -1.0);
  const std::vector<double> info = as_vector(inv_sigma2, "inv_sigma2", E, 1.0);

  o::BundleAdjustmentOptions opt;
  apply_keywords(kwargs, "bundle_adjust", ba_option_fields(opt));

  o::BAProblem problem;
  problem.keyframes.resize(static_cast<size_t>(K));
  for (py::ssize_t k = 0; k < K; ++k) {
    auto& kf = problem.keyframes[static_cast<size_t>(k)];
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) kf.T_c_w(i, j) = T.data()[16 * k + 4 * i + j];
    const std::string problem_text = geometry::rigid_transform_problem(kf.T_c_w, kRigidTolerance);
    if (!problem_text.empty())
      throw py::value_error("poses_c_w[" + std::to_string(k) + "]: not a rigid transform: " + problem_text);
    kf.fixed = kf_fixed[static_cast<size_t>(k)];
  }
  problem.points.resize(static_cast<size_t>(M));
  for (py::ssize_t j = 0; j < M; ++j) {
    auto& p = problem.points[static_cast<size_t>(j)];
    p.X_w = Vec3(P.data()[3 * j], P.data()[3 * j + 1], P.data()[3 * j + 2]);
    p.fixed = pt_fixed[static_cast<size_t>(j)];
  }
  problem.observations.resize(static_cast<size_t>(E));
  for (py::ssize_t e = 0; e < E; ++e) {
    const size_t i = static_cast<size_t>(e);
    problem.observations[i] = {kf_idx[i], pt_idx[i], Vec2(px.data()[2 * e], px.data()[2 * e + 1]),
                               ur[i], info[i]};
  }

  o::BundleAdjustmentReport r;
  {
    py::gil_scoped_release release;
    r = o::bundle_adjust(problem, cam, opt);
  }
  DoubleArray poses_out = new_array({K, 4, 4});
  for (py::ssize_t k = 0; k < K; ++k)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        poses_out.mutable_data()[16 * k + 4 * i + j] = problem.keyframes[static_cast<size_t>(k)].T_c_w(i, j);
  DoubleArray points_out = new_array({M, 3});
  for (py::ssize_t j = 0; j < M; ++j)
    for (int c = 0; c < 3; ++c)
      points_out.mutable_data()[3 * j + c] = problem.points[static_cast<size_t>(j)].X_w[c];

  py::dict out;
  out["poses_c_w"] = poses_out;
  out["points_w"] = points_out;
  out["outlier"] = to_bool_array(r.outlier);
  out["num_outliers"] = r.num_outliers;
  out["initial_rmse_px"] = r.initial_rmse_px;
  out["final_rmse_px"] = r.final_rmse_px;
  out["initial_cost"] = r.initial_cost;
  out["final_cost"] = r.final_cost;
  out["iterations"] = r.iterations;
  out["solve_ms"] = r.solve_ms;
  out["converged"] = r.converged;
  out["num_residuals"] = r.num_residuals;
  out["message"] = r.message;
  return out;
}

}  // namespace

void bind_optim(py::module_& m) {
  m.def("optimize_pose", &optimize_pose_py, "T_c_w_init"_a, "points_w"_a, "uv"_a, "u_right"_a,
        "inv_sigma2"_a, "camera"_a,
        R"doc(Pose-only optimisation of a camera from known world points (paper eq. 3).

Levenberg-Marquardt on T_c_w <- exp(delta) T_c_w (delta = [v; w]) with a Huber loss on the
whitened reprojection error, in ``rounds`` rounds; after each round every observation is
re-classified as inlier / outlier by a chi2 test (7.815 stereo, 5.991 mono), and only
inliers take part in the next round.

Parameters
----------
T_c_w_init : (4, 4) array_like
    Initial pose (world -> camera), e.g. from a constant-velocity model.
points_w : (N, 3) array_like
    World points.
uv : (N, 2) array_like
    Observed left-image pixels.
u_right : (N,) array_like or None
    Observed right-image column; a negative value marks a mono observation. None: all mono.
inv_sigma2 : (N,) array_like or None
    Information weight 1 / sigma^2 of each keypoint (sigma = scale of its octave).
    None: all 1.
camera : twistslam.geometry.StereoCamera
**options
    rounds (4), iterations_per_round (10), chi2_stereo (7.815), chi2_mono (5.991),
    huber_delta_stereo (sqrt 7.815), huber_delta_mono (sqrt 5.991), min_depth (0.1 m),
    min_inliers (10).

Returns
-------
dict
    ``T_c_w`` (4, 4): the optimised pose, or ``T_c_w_init`` if not converged;
    ``inlier`` (N,) bool; ``num_inliers`` int; ``converged`` bool (finite pose with at
    least min_inliers inliers); ``final_cost`` float (0.5 sum Huber(chi2) over inliers);
    ``iterations`` int.

Raises
------
ValueError
    Wrong array shapes, an option value out of range, or a ``T_c_w_init`` that is not a
    finite rigid transform (R^T R = I within 1e-4, det R > 0, last row [0, 0, 0, 1]).
    Non-finite observations never raise: they are outliers. A pose that sees every point
    behind it gives ``converged=False``.
TypeError
    An unknown option or an option value of the wrong type.
)doc");

  m.def("bundle_adjust", &bundle_adjust_py, "poses_c_w"_a, "fixed_poses"_a, "points_w"_a,
        "fixed_points"_a, "obs_keyframe"_a, "obs_point"_a, "uv"_a, "u_right"_a,
        "inv_sigma2"_a, "camera"_a,
        R"doc(Local bundle adjustment of keyframe poses and points (paper eq. 9, e_stat).

Ceres, Levenberg-Marquardt with a Schur-complement linear solver (points eliminated first),
Huber loss. Two passes: ``max_iterations_first`` iterations on every observation, then the
observations failing the chi2 test (or behind the camera) are removed and
``max_iterations_second`` more iterations run on the rest.

Parameters
----------
poses_c_w : (K, 4, 4) array_like
    Keyframe poses (world -> camera).
fixed_poses : (K,) bool array_like or None
    Poses held constant (covisible keyframes outside the window; at least one fixes the
    gauge). None: all free.
points_w : (M, 3) array_like
    World points.
fixed_points : (M,) bool array_like or None
    Points held constant. None: all free.
obs_keyframe, obs_point : (E,) int array_like
    Keyframe and point index of each observation.
uv : (E, 2) array_like
    Observed left-image pixels.
u_right : (E,) array_like or None
    Observed right-image column, negative for mono observations. None: all mono.
inv_sigma2 : (E,) array_like or None
    1 / sigma^2 of each keypoint's octave. None: all 1.
camera : twistslam.geometry.StereoCamera
**options
    max_iterations_first (5), max_iterations_second (10), huber_delta_stereo,
    huber_delta_mono, chi2_stereo (7.815), chi2_mono (5.991), remove_outliers (True),
    num_threads (2), min_depth (0.1 m), function_tolerance (1e-6),
    initial_trust_region_radius (10),
    linear_solver ('auto' | 'builtin_dense_schur' | 'dense_schur' | 'sparse_schur' |
    'iterative_schur'): 'auto' solves a problem of up to 100 free poses with the built-in
    Levenberg-Marquardt (points eliminated, dense reduced system; Ceres' rules), larger
    ones with Ceres' sparse Schur; the others name Ceres' linear solvers.

Returns
-------
dict
    ``poses_c_w`` (K, 4, 4) and ``points_w`` (M, 3): refined copies (fixed and unobserved
    entries unchanged); ``outlier`` (E,) bool at the final state; ``num_outliers``;
    ``initial_rmse_px`` / ``final_rmse_px`` (RMS pixel error per coordinate over the final
    inliers); ``initial_cost`` / ``final_cost`` (0.5 sum Huber(chi2) over all valid
    observations); ``iterations``; ``solve_ms``; ``converged`` (False: nothing was solved,
    inputs returned unchanged); ``num_residuals``; ``message``.

Raises
------
ValueError
    Wrong shapes, an index out of range (naming ``obs_keyframe`` / ``obs_point``), a pose
    that is not a finite rigid transform (naming ``poses_c_w[k]``), or an option value out of
    range. Non-finite points and observations are outliers, not errors.
TypeError
    An unknown option or an option value of the wrong type.
)doc");
}

}  // namespace twistslam::bindings
