// Pose-only optimisation (paper eq. 3). A dense 6-DoF Levenberg-Marquardt on the left-
// multiplied twist T <- exp(delta) T (delta = [v; w], docs/design.md), Huber-robustified
// (iteratively reweighted normal equations), inside rounds that re-classify every observation
// as inlier / outlier with a chi2 test, so that an outlier of one round can come back later.
// With ~600 observations one LM iteration costs a few microseconds per observation, far less
// than the setup of a general sparse solver; that is why this does not go through Ceres.
#include "optim/pose_optimization.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "optim/stereo_projection.hpp"

namespace twistslam::optim {

namespace {

using detail::huber_rho;
using detail::huber_weight;
using detail::predict_measurement;

bool valid_observation(const StereoObservation& o) {
  return o.point_w.allFinite() && o.uv.allFinite() && std::isfinite(o.u_right) &&
         std::isfinite(o.inv_sigma2) && o.inv_sigma2 > 0;
}

bool valid_camera(const geometry::StereoCamera& cam) {
  return std::isfinite(cam.fx) && std::isfinite(cam.fy) && cam.fx > 0 && cam.fy > 0 &&
         std::isfinite(cam.cx) && std::isfinite(cam.cy) && cam.t_left.allFinite() &&
         cam.t_right.allFinite();
}

// Whitened squared error of one observation at pose T, and optionally its (weighted)
// contribution to the normal equations. Returns false if the point is behind a camera.
class PoseProblem {
 public:
  PoseProblem(const std::vector<StereoObservation>& obs, const geometry::StereoCamera& cam,
              const PoseOptimizationOptions& opt)
      : obs_(obs), cam_(cam), opt_(opt) {}

  bool chi2(const Mat4& T, const StereoObservation& o, double* s) const {
    const Vec3 Xc = T.topLeftCorner<3, 3>() * o.point_w + T.topRightCorner<3, 1>();
    if (o.is_stereo()) {
      Vec3 z;
      if (!predict_measurement<3>(cam_, Xc, opt_.min_depth, &z, nullptr)) return false;
      *s = o.inv_sigma2 * (z - Vec3(o.uv.x(), o.uv.y(), o.u_right)).squaredNorm();
    } else {
      Vec2 z;
      if (!predict_measurement<2>(cam_, Xc, opt_.min_depth, &z, nullptr)) return false;
      *s = o.inv_sigma2 * (z - o.uv).squaredNorm();
    }
    return true;
  }

  double delta(const StereoObservation& o) const {
    return o.is_stereo() ? opt_.huber_delta_stereo : opt_.huber_delta_mono;
  }
  double threshold(const StereoObservation& o) const {
    return o.is_stereo() ? opt_.chi2_stereo : opt_.chi2_mono;
  }

  // 0.5 * sum of Huber(chi2) over the active observations. A point that a trial step moves
  // behind the camera costs as much as a gross outlier, which keeps steps from doing so.
  double cost(const Mat4& T, const std::vector<std::uint8_t>& active) const {
    double c = 0;
    for (size_t i = 0; i < obs_.size(); ++i) {
      if (!active[i]) continue;
      const double d = delta(obs_[i]);
      double s;
      if (!chi2(T, obs_[i], &s)) s = 1e4 * d * d;
      c += 0.5 * huber_rho(s, d);
    }
    return c;
  }

  // Gauss-Newton normal equations H delta = -g of the IRLS-weighted problem at T.
  double linearize(const Mat4& T, const std::vector<std::uint8_t>& active, Mat6* H,
                   Vec6* g) const {
    H->setZero();
    g->setZero();
    double c = 0;
    const Mat3 R = T.topLeftCorner<3, 3>();
    const Vec3 t = T.topRightCorner<3, 1>();
    for (size_t i = 0; i < obs_.size(); ++i) {
      if (!active[i]) continue;
      const StereoObservation& o = obs_[i];
      const double d = delta(o);
      const Vec3 Xc = R * o.point_w + t;
      Eigen::Matrix<double, 3, 6> dX;  // dX_c / d delta for T <- exp(delta) T
      dX.leftCols<3>().setIdentity();
      dX.rightCols<3>() = -geometry::hat(Xc);
      if (o.is_stereo()) {
        Vec3 z;
        Mat3 Jz;
        if (!predict_measurement<3>(cam_, Xc, opt_.min_depth, &z, &Jz)) {
          c += 0.5 * huber_rho(1e4 * d * d, d);
          continue;
        }
        accumulate<3>(z - Vec3(o.uv.x(), o.uv.y(), o.u_right), Jz * dX, o.inv_sigma2, d, H, g,
                      &c);
      } else {
        Vec2 z;
        Eigen::Matrix<double, 2, 3> Jz;
        if (!predict_measurement<2>(cam_, Xc, opt_.min_depth, &z, &Jz)) {
          c += 0.5 * huber_rho(1e4 * d * d, d);
          continue;
        }
        accumulate<2>(z - o.uv, Jz * dX, o.inv_sigma2, d, H, g, &c);
      }
    }
    return c;
  }

 private:
  template <int N>
  static void accumulate(const Eigen::Matrix<double, N, 1>& e,
                         const Eigen::Matrix<double, N, 6>& J, double info, double delta,
                         Mat6* H, Vec6* g, double* c) {
    const double s = info * e.squaredNorm();
    const double w = info * huber_weight(s, delta);
    H->noalias() += w * J.transpose() * J;
    g->noalias() += w * J.transpose() * e;
    *c += 0.5 * huber_rho(s, delta);
  }

  const std::vector<StereoObservation>& obs_;
  const geometry::StereoCamera& cam_;
  const PoseOptimizationOptions& opt_;
};

// Levenberg-Marquardt (Nielsen's damping update) from T over the active observations.
// Returns the number of iterations run.
int levenberg_marquardt(const PoseProblem& prob, const std::vector<std::uint8_t>& active,
                        int max_iterations, Mat4* T) {
  double lambda = -1, nu = 2;
  int it = 0;
  for (; it < max_iterations; ++it) {
    Mat6 H;
    Vec6 g;
    const double c = prob.linearize(*T, active, &H, &g);
    if (!std::isfinite(c) || !H.allFinite()) break;
    const Vec6 D = H.diagonal().cwiseMax(1e-9);
    if (lambda < 0) lambda = 1e-5 * D.maxCoeff();
    bool accepted = false;
    Vec6 step = Vec6::Zero();
    for (int attempt = 0; attempt < 10 && !accepted; ++attempt) {
      Mat6 A = H;
      A.diagonal() += lambda * D;
      step = A.ldlt().solve(-g);
      if (!step.allFinite()) {
        lambda *= nu;
        nu *= 2;
        continue;
      }
      const Mat4 T_new = geometry::se3_exp(step) * *T;
      const double c_new = prob.cost(T_new, active);
      const double predicted = 0.5 * step.dot(lambda * D.cwiseProduct(step) - g);
      if (std::isfinite(c_new) && c_new < c) {
        *T = T_new;
        const double gain = predicted > 0 ? (c - c_new) / predicted : 1.0;
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * gain - 1.0, 3));
        nu = 2;
        accepted = true;
        if (c - c_new < 1e-10 * c) return it + 1;
      } else {
        lambda *= nu;
        nu *= 2;
      }
    }
    if (!accepted || step.norm() < 1e-10) return it + 1;
  }
  return it;
}

}  // namespace

PoseOptimizationResult optimize_pose(const Mat4& T_c_w_init,
                                     const std::vector<StereoObservation>& obs,
                                     const geometry::StereoCamera& cam,
                                     const PoseOptimizationOptions& options) {
  PoseOptimizationResult result;
  result.T_c_w = T_c_w_init;
  result.inlier.assign(obs.size(), 0);
  if (!T_c_w_init.allFinite() || !geometry::is_rigid_transform(T_c_w_init, 1e-3) ||
      !valid_camera(cam) || obs.empty()) {
    return result;
  }
  // Re-orthonormalise a pose that is rigid up to round-off (e.g. read from float32).
  Mat4 T = geometry::make_pose(
      Eigen::Quaterniond(Mat3(T_c_w_init.topLeftCorner<3, 3>())).normalized().toRotationMatrix(),
      T_c_w_init.topRightCorner<3, 1>());

  const PoseProblem prob(obs, cam, options);
  std::vector<std::uint8_t> valid(obs.size()), active(obs.size());
  int num_active = 0;
  for (size_t i = 0; i < obs.size(); ++i) {
    double s;
    valid[i] = valid_observation(obs[i]);
    active[i] = valid[i] && prob.chi2(T, obs[i], &s) && std::isfinite(s);
    num_active += active[i];
  }

  const int min_inliers = std::max(options.min_inliers, 3);
  for (int round = 0; round < options.rounds && num_active >= min_inliers; ++round) {
    result.iterations += levenberg_marquardt(prob, active, options.iterations_per_round, &T);
    // Re-classify every valid observation, including the previous round's outliers.
    num_active = 0;
    for (size_t i = 0; i < obs.size(); ++i) {
      double s;
      active[i] = valid[i] && prob.chi2(T, obs[i], &s) && s <= prob.threshold(obs[i]);
      num_active += active[i];
    }
  }

  result.inlier = active;
  result.num_inliers = num_active;
  result.final_cost = prob.cost(T, active);
  result.converged = T.allFinite() && num_active >= min_inliers && options.rounds > 0;
  result.T_c_w = result.converged ? T : T_c_w_init;
  return result;
}

}  // namespace twistslam::optim
