// Bindings of cpp/optim: pose-only optimisation (camera tracking, paper eq. 3) and local
// bundle adjustment (paper eq. 9, static term). Inputs are numpy arrays, checked here
// (ValueError naming the argument); the solvers run without the GIL.
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bindings/numpy_checks.hpp"
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

// **options -> fields of an options struct; unknown names raise TypeError like Python does.
class OptionSetter {
 public:
  explicit OptionSetter(std::string function) : function_(std::move(function)) {}
  OptionSetter& add_int(const std::string& name, int* field, int min_value) {
    setters_[name] = [=](const py::handle& v) {
      const int x = v.cast<int>();
      if (x < min_value) {
        throw py::value_error(name + ": must be >= " + std::to_string(min_value) + ", got " +
                              std::to_string(x));
      }
      *field = x;
    };
    return *this;
  }
  OptionSetter& add_double(const std::string& name, double* field, bool allow_zero = false) {
    setters_[name] = [=](const py::handle& v) {
      const double x = v.cast<double>();
      if (!std::isfinite(x) || x < 0 || (!allow_zero && x == 0)) {
        throw py::value_error(name + ": must be finite and " + (allow_zero ? ">= 0" : "> 0") +
                              ", got " + std::to_string(x));
      }
      *field = x;
    };
    return *this;
  }
  OptionSetter& add_bool(const std::string& name, bool* field) {
    setters_[name] = [=](const py::handle& v) { *field = v.cast<bool>(); };
    return *this;
  }
  OptionSetter& add(const std::string& name, std::function<void(const py::handle&)> f) {
    setters_[name] = std::move(f);
    return *this;
  }
  void apply(const py::kwargs& kwargs) const {
    for (const auto& item : kwargs) {
      const std::string key = py::str(item.first);
      auto it = setters_.find(key);
      if (it == setters_.end()) {
        std::string known;
        for (const auto& s : setters_) known += (known.empty() ? "" : ", ") + s.first;
        throw py::type_error(function_ + "() got an unexpected keyword argument '" + key +
                             "' (options: " + known + ")");
      }
      try {
        it->second(item.second);
      } catch (const py::cast_error&) {
        throw py::type_error(key + ": wrong type " +
                             std::string(py::str(py::type::of(item.second))));
      }
    }
  }

 private:
  std::string function_;
  std::map<std::string, std::function<void(const py::handle&)>> setters_;
};

py::array_t<bool> to_bool_array(const std::vector<std::uint8_t>& flags) {
  py::array_t<bool> out(static_cast<py::ssize_t>(flags.size()));
  for (size_t i = 0; i < flags.size(); ++i) out.mutable_data()[i] = flags[i] != 0;
  return out;
}

py::dict optimize_pose_py(const py::handle& T_init, const py::handle& points_w,
                          const py::handle& uv, const py::handle& u_right,
                          const py::handle& inv_sigma2, const g::StereoCamera& cam,
                          const py::kwargs& kwargs) {
  const Mat4 T0 = as_mat4(T_init, "T_c_w_init");
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
  OptionSetter("optimize_pose")
      .add_int("rounds", &opt.rounds, 0)
      .add_int("iterations_per_round", &opt.iterations_per_round, 0)
      .add_double("chi2_stereo", &opt.chi2_stereo)
      .add_double("chi2_mono", &opt.chi2_mono)
      .add_double("huber_delta_stereo", &opt.huber_delta_stereo)
      .add_double("huber_delta_mono", &opt.huber_delta_mono)
      .add_double("min_depth", &opt.min_depth, true)
      .add_int("min_inliers", &opt.min_inliers, 0)
      .apply(kwargs);

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
  OptionSetter("bundle_adjust")
      .add_int("max_iterations_first", &opt.max_iterations_first, 0)
      .add_int("max_iterations_second", &opt.max_iterations_second, 0)
      .add_double("huber_delta_stereo", &opt.huber_delta_stereo)
      .add_double("huber_delta_mono", &opt.huber_delta_mono)
      .add_double("chi2_stereo", &opt.chi2_stereo)
      .add_double("chi2_mono", &opt.chi2_mono)
      .add_bool("remove_outliers", &opt.remove_outliers)
      .add_int("num_threads", &opt.num_threads, 1)
      .add_double("min_depth", &opt.min_depth, true)
      .add_double("function_tolerance", &opt.function_tolerance)
      .add_double("initial_trust_region_radius", &opt.initial_trust_region_radius)
      .add("linear_solver",
           [&opt](const py::handle& v) {
             const std::string s = v.cast<std::string>();
             if (s == "auto") opt.linear_solver = o::BALinearSolver::kAuto;
             else if (s == "dense_schur") opt.linear_solver = o::BALinearSolver::kDenseSchur;
             else if (s == "sparse_schur") opt.linear_solver = o::BALinearSolver::kSparseSchur;
             else if (s == "iterative_schur") opt.linear_solver = o::BALinearSolver::kIterativeSchur;
             else
               throw py::value_error("linear_solver: expected 'auto', 'dense_schur', "
                                     "'sparse_schur' or 'iterative_schur', got '" + s + "'");
           })
      .apply(kwargs);

  o::BAProblem problem;
  problem.keyframes.resize(static_cast<size_t>(K));
  for (py::ssize_t k = 0; k < K; ++k) {
    auto& kf = problem.keyframes[static_cast<size_t>(k)];
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) kf.T_c_w(i, j) = T.data()[16 * k + 4 * i + j];
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
    Wrong array shapes or option values. Non-finite data never raises: such observations
    are outliers, a bad initial pose gives ``converged=False``.
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
    linear_solver ('auto' | 'dense_schur' | 'sparse_schur' | 'iterative_schur').

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
    Wrong shapes, an index out of range (naming ``obs_keyframe`` / ``obs_point``), or bad
    option values.
)doc");
}

}  // namespace twistslam::bindings
