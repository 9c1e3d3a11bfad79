#include "objects/twist_estimation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "optim/stereo_projection.hpp"

namespace twistslam::objects {
namespace {

constexpr double kMadToSigma = 1.4826;      // sigma of a Gaussian = 1.4826 MAD
constexpr double kProjectorTolerance = 1e-6;  // |Pi - Pi^T| and eigenvalue distance to {0, 1}
constexpr double kHiddenPenaltySigmas = 1e3;  // cost of a point pushed behind the camera
constexpr int kMaxDampingTries = 10;        // lambda x10 per rejected step, then give up

using Basis = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>;  // orthonormal, 6 x dof
using MatK = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
using VecK = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;
using Mat36 = Eigen::Matrix<double, 3, 6>;

// Residual of one observation, whitened by sqrt(inv_sigma2): e = z - h, J = dh/d eps.
struct Linearized {
  Vec3 e = Vec3::Zero();
  Mat36 J = Mat36::Zero();
  int rows = 0;  // 3 stereo, 2 mono, 0 hidden (closer than min_depth)
};

struct Problem {
  const geometry::StereoCamera& cam;
  const Mat4& T_c_w;
  const std::vector<TwistObservation>& obs;
  std::vector<Vec3> Y;  // points at the previous object pose, world frame: T_w_o_prev X_o
  Basis B;
  const TwistEstimationOptions& opt;
};

// Orthonormal basis of range(Pi); false unless Pi is a finite symmetric projector.
bool subspace_basis(const Mat6& Pi, Basis* B) {
  if (!Pi.allFinite() || (Pi - Pi.transpose()).cwiseAbs().maxCoeff() > kProjectorTolerance) return false;
  const Eigen::SelfAdjointEigenSolver<Mat6> es(Pi);
  int dof = 0;
  for (int i = 0; i < 6; ++i) {
    const double l = es.eigenvalues()(i);
    if (std::abs(l) > kProjectorTolerance && std::abs(l - 1) > kProjectorTolerance) return false;
    dof += l > 0.5;
  }
  if (dof == 0) return false;
  *B = es.eigenvectors().rightCols(dof);  // eigenvalues ascend: the ones are last
  return true;
}

// Residuals (and Jacobians of the left perturbation T <- exp(eps) T) at object motion T_d.
void evaluate(const Problem& p, const Mat4& T_d, bool jacobians, std::vector<Linearized>* out) {
  const Mat3 R_cw = p.T_c_w.topLeftCorner<3, 3>();
  const Mat4 T_c_d = p.T_c_w * T_d;
  for (size_t j = 0; j < p.obs.size(); ++j) {
    const TwistObservation& o = p.obs[j];
    Linearized& l = (*out)[j];
    const Vec3 X_c = T_c_d.topLeftCorner<3, 3>() * p.Y[j] + T_c_d.topRightCorner<3, 1>();
    const double w = std::sqrt(o.inv_sigma2);
    Vec3 z;
    Mat3 Jp;
    l.rows = 0;
    if (o.u_right >= 0) {  // stereo [u, v, u_right], as the BA (optim/stereo_projection.hpp)
      if (!optim::detail::predict_measurement<3>(p.cam, X_c, p.opt.min_depth, &z, &Jp)) continue;
      l.e = w * (Vec3(o.uv.x(), o.uv.y(), o.u_right) - z);
      l.rows = 3;
    } else {
      Vec2 z2;
      Eigen::Matrix<double, 2, 3> J2;
      if (!optim::detail::predict_measurement<2>(p.cam, X_c, p.opt.min_depth, &z2, &J2)) continue;
      l.e << w * (o.uv - z2), 0.0;
      Jp << J2, Eigen::RowVector3d::Zero();
      l.rows = 2;
    }
    if (!jacobians) continue;
    const Vec3 X_w = T_d.topLeftCorner<3, 3>() * p.Y[j] + T_d.topRightCorner<3, 1>();
    Mat36 dX;  // d(exp(eps) X_w)/d eps = [I, -hat(X_w)], rotated into the camera
    dX << Mat3::Identity(), -geometry::hat(X_w);
    l.J = w * Jp * R_cw * dX;
  }
}

// sigma = 1.4826 MAD of the whitened residual components of the visible masked points, floored.
double robust_sigma(const std::vector<Linearized>& lin, const std::vector<std::uint8_t>& mask,
                    double floor_px, std::vector<double>* buf) {
  buf->clear();
  for (size_t j = 0; j < lin.size(); ++j)
    for (int r = 0; mask[j] && r < lin[j].rows; ++r) buf->push_back(lin[j].e(r));
  if (buf->empty()) return floor_px;
  auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double m = median(*buf);
  for (double& x : *buf) x = std::abs(x - m);
  return std::max(floor_px, kMadToSigma * median(*buf));
}

double robust_cost(const Problem& p, const std::vector<Linearized>& lin,
                   const std::vector<std::uint8_t>& mask, double sigma) {
  const double k = p.opt.huber_k;
  double cost = 0;
  for (size_t j = 0; j < lin.size(); ++j) {
    if (!mask[j]) continue;
    const double s = lin[j].rows ? lin[j].e.squaredNorm() / (sigma * sigma)
                                 : kHiddenPenaltySigmas * kHiddenPenaltySigmas;
    cost += optim::detail::huber_rho(s, k);
  }
  return cost;
}

// Gauss-Newton system of the masked visible points in the subspace, weights Huber x 1/sigma^2.
void normal_equations(const Problem& p, const std::vector<Linearized>& lin,
                      const std::vector<std::uint8_t>& mask, double sigma, bool huber, MatK* H, VecK* g) {
  Mat6 H6 = Mat6::Zero();
  Vec6 g6 = Vec6::Zero();
  for (size_t j = 0; j < lin.size(); ++j) {
    const Linearized& l = lin[j];
    if (!mask[j] || l.rows == 0) continue;
    const double s = l.e.squaredNorm() / (sigma * sigma);
    const double w = (huber ? optim::detail::huber_weight(s, p.opt.huber_k) : 1.0) / (sigma * sigma);
    H6.noalias() += w * l.J.transpose() * l.J;
    g6.noalias() += w * l.J.transpose() * l.e;
  }
  *H = p.B.transpose() * H6 * p.B;
  *g = p.B.transpose() * g6;
}

// Levenberg-Marquardt on the Huber cost of the masked points; the scale is re-estimated each
// iteration and held fixed while a step is tried. Returns the iterations run.
int run_lm(const Problem& p, int max_iterations, const std::vector<std::uint8_t>& mask, Mat4* T_d) {
  std::vector<Linearized> lin(p.obs.size()), trial(p.obs.size());
  std::vector<double> buf;
  double lambda = p.opt.initial_lambda;
  int it = 0;
  while (it < max_iterations) {
    evaluate(p, *T_d, true, &lin);
    const double sigma = robust_sigma(lin, mask, p.opt.min_sigma_px, &buf);
    const double cost0 = robust_cost(p, lin, mask, sigma);
    MatK H;
    VecK g;
    normal_equations(p, lin, mask, sigma, true, &H, &g);
    ++it;
    bool accepted = false;
    VecK delta;
    for (int t = 0; t < kMaxDampingTries && !accepted; ++t) {
      MatK A = H;
      A.diagonal() += lambda * H.diagonal().cwiseMax(1e-9);
      delta = A.ldlt().solve(g);
      if (!delta.allFinite()) break;
      const Mat4 T_try = geometry::se3_exp(p.B * delta) * *T_d;
      evaluate(p, T_try, false, &trial);
      if (robust_cost(p, trial, mask, sigma) < cost0) {
        *T_d = T_try;
        lambda = std::max(lambda * 0.1, 1e-12);
        accepted = true;
      } else {
        lambda *= 10;
      }
    }
    if (!accepted || delta.norm() < p.opt.step_tolerance) break;
  }
  return it;
}

void check_options(const TwistEstimationOptions& o) {
  if (o.max_iterations < 1 || o.refine_iterations < 0 || !(o.huber_k > 0) || !(o.min_sigma_px > 0) ||
      !(o.max_sigma_px >= o.min_sigma_px) ||
      !(o.inlier_chi2_stereo > 0) || !(o.inlier_chi2_mono > 0) || o.min_inliers < 1 ||
      !(o.min_depth > 0) || !(o.initial_lambda > 0) || !(o.step_tolerance >= 0))
    throw std::invalid_argument("TwistEstimationOptions: iterations >= 1, thresholds > 0 expected");
}

}  // namespace

TwistEstimate estimate_object_twist(const geometry::StereoCamera& camera, const Mat4& T_c_w,
                                    const Mat4& T_w_o_prev, const Mat6& Pi,
                                    const std::vector<TwistObservation>& observations,
                                    const Vec6& xi_init, const TwistEstimationOptions& options) {
  check_options(options);
  TwistEstimate est;
  const size_t n = observations.size();
  est.inlier.assign(n, 0);
  auto fail = [&est](std::string why) { est.failure = std::move(why); return est; };
  Problem p{camera, T_c_w, observations, {}, {}, options};
  if (!T_c_w.allFinite() || !T_w_o_prev.allFinite() || !xi_init.allFinite())
    return fail("non-finite pose or initial twist");
  if (!subspace_basis(Pi, &p.B)) return fail("Pi is not an orthogonal projector");
  if (static_cast<int>(n) < options.min_inliers)
    return fail("too few observations: " + std::to_string(n));
  p.Y.reserve(n);
  for (const auto& o : observations) {
    if (!o.X_o.allFinite() || !o.uv.allFinite() || !std::isfinite(o.u_right) || !(o.inv_sigma2 > 0))
      return fail("non-finite observation");
    p.Y.push_back(T_w_o_prev.topLeftCorner<3, 3>() * o.X_o + T_w_o_prev.topRightCorner<3, 1>());
  }
  Mat4 T_d = geometry::se3_exp(Pi * xi_init);  // the motion exp(Pi xi) of eq. 4
  std::vector<std::uint8_t> mask(n, 1);
  est.iterations = run_lm(p, options.max_iterations, mask, &T_d);
  std::vector<Linearized> lin(n);
  std::vector<double> buf;
  // chi2 test in robust-sigma units; the scale is taken from `scale_from` (all points first,
  // then the first inliers: 30 % outliers would inflate the MAD by ~1.5x)
  auto classify = [&](const std::vector<std::uint8_t>& scale_from) {
    evaluate(p, T_d, true, &lin);
    est.sigma_px = robust_sigma(lin, scale_from, options.min_sigma_px, &buf);
    est.num_inliers = 0;
    for (size_t j = 0; j < n; ++j) {
      const double chi2 = lin[j].rows == 3 ? options.inlier_chi2_stereo : options.inlier_chi2_mono;
      est.inlier[j] = lin[j].rows > 0 && lin[j].e.squaredNorm() < chi2 * est.sigma_px * est.sigma_px;
      est.num_inliers += est.inlier[j];
    }
  };
  classify(mask);
  if (options.refine_iterations > 0 && est.num_inliers >= options.min_inliers) {
    mask = est.inlier;
    est.iterations += run_lm(p, options.refine_iterations, mask, &T_d);
    classify(mask);
  }
  if (!T_d.allFinite()) return fail("diverged (non-finite pose)");
  if (est.sigma_px > options.max_sigma_px)
    return fail("robust scale " + std::to_string(est.sigma_px) + " px > max_sigma_px");
  if (est.num_inliers < options.min_inliers)
    return fail("too few inliers: " + std::to_string(est.num_inliers));
  MatK H;
  VecK g;
  normal_equations(p, lin, est.inlier, est.sigma_px, false, &H, &g);
  const Eigen::LDLT<MatK> ldlt(H);
  const MatK cov = ldlt.solve(MatK::Identity(H.rows(), H.cols()));
  if (ldlt.info() != Eigen::Success || !cov.allFinite() || cov.diagonal().minCoeff() <= 0)
    return fail("degenerate geometry (singular normal equations)");
  double sq = 0;
  int comps = 0;
  for (size_t j = 0; j < n; ++j)
    if (est.inlier[j]) sq += lin[j].e.squaredNorm(), comps += lin[j].rows;
  est.final_rms_px = std::sqrt(sq / comps);
  est.covariance = p.B * cov * p.B.transpose();
  est.xi = Pi * geometry::se3_log(T_d);  // exact zeros outside range(Pi)
  est.T_w_o = geometry::se3_exp(est.xi) * T_w_o_prev;
  est.valid = true;
  return est;
}

}  // namespace twistslam::objects
