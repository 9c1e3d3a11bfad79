#include "optim/schur_lm.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "geometry/so3.hpp"
#include "optim/lm_trust_region.hpp"
#include "optim/stereo_projection.hpp"

namespace twistslam::optim::detail {

namespace {

using Mat36 = Eigen::Matrix<double, 3, 6>;
using Mat63 = Eigen::Matrix<double, 6, 3>;

}  // namespace

// Per observation: the loss-corrected residual and Jacobians (sqrt(rho') times the whitened
// ones; Huber's rho'' is 0 or negative, where Ceres' correction is this plain rescaling), mono
// observations with a zero third row.
struct SchurLM::Linearization {
  std::vector<Vec3> r;
  std::vector<Mat36> J_pose;  // with respect to the pose's tangent [v; w]
  std::vector<Mat3> J_point;
};

SchurLM::SchurLM(const geometry::StereoCamera& camera, double min_depth)
    : camera_(camera), min_depth_(min_depth) {}

int SchurLM::add_pose(double* params7, bool fixed) {
  poses_.push_back(params7);
  pose_free_.push_back(fixed ? -1 : num_free_poses_++);
  return static_cast<int>(poses_.size()) - 1;
}

int SchurLM::add_point(double* params3, bool fixed) {
  points_.push_back(params3);
  point_free_.push_back(fixed ? -1 : num_free_points_++);
  return static_cast<int>(points_.size()) - 1;
}

void SchurLM::add_observation(const SchurLMObservation& o) {
  if (o.pose < 0 || o.pose >= static_cast<int>(poses_.size()) || o.point < 0 ||
      o.point >= static_cast<int>(points_.size()))
    throw std::invalid_argument("SchurLM::add_observation: pose " + std::to_string(o.pose) +
                                " or point " + std::to_string(o.point) + " out of range");
  observations_.push_back(o);
}

double SchurLM::evaluate(const std::vector<double>& poses, const std::vector<double>& points,
                         Linearization* lin) const {
  const size_t P = poses_.size();
  std::vector<Mat3> R(P);
  for (size_t i = 0; i < P; ++i)
    R[i] = Eigen::Map<const Eigen::Quaterniond>(poses.data() + 7 * i + 3).toRotationMatrix();
  if (lin) {
    lin->r.resize(observations_.size());
    lin->J_pose.resize(observations_.size());
    lin->J_point.resize(observations_.size());
  }
  double cost = 0;
  for (size_t e = 0; e < observations_.size(); ++e) {
    const SchurLMObservation& o = observations_[e];
    const Eigen::Map<const Vec3> t(poses.data() + 7 * o.pose);
    const Eigen::Map<const Vec3> X(points.data() + 3 * o.point);
    const Vec3 RX = R[o.pose] * X;
    const Vec3 X_c = RX + t;
    Vec3 r = Vec3::Zero();
    Mat3 Jz = Mat3::Zero();  // d z / d X_c
    if (o.z.z() >= 0) {
      Vec3 z;
      if (!predict_measurement<3>(camera_, X_c, min_depth_, &z, lin ? &Jz : nullptr))
        return std::numeric_limits<double>::infinity();
      r = o.sqrt_info * (z - o.z);
    } else {
      Vec2 z;
      Eigen::Matrix<double, 2, 3> J2;
      if (!predict_measurement<2>(camera_, X_c, min_depth_, &z, lin ? &J2 : nullptr))
        return std::numeric_limits<double>::infinity();
      r.head<2>() = o.sqrt_info * (z - o.z.head<2>());
      if (lin) Jz.topRows<2>() = J2;
    }
    const double s = r.squaredNorm();
    if (!std::isfinite(s)) return std::numeric_limits<double>::infinity();
    double weight = 1;  // sqrt(rho'(s))
    if (o.huber_delta > 0 && s > o.huber_delta * o.huber_delta) {
      const double root = std::sqrt(s);
      cost += 0.5 * (2.0 * o.huber_delta * root - o.huber_delta * o.huber_delta);
      weight = std::sqrt(o.huber_delta / root);
    } else {
      cost += 0.5 * s;
    }
    if (!lin) continue;
    const Mat3 A = (weight * o.sqrt_info) * Jz;
    lin->r[e] = weight * r;
    // X_c = R X + t; d X_c / d v = I, d X_c / d w = -2 [R X]x (|w| is half the angle)
    lin->J_pose[e].leftCols<3>() = A;
    lin->J_pose[e].rightCols<3>() = -2.0 * A * geometry::hat(RX);
    lin->J_point[e] = A * R[o.pose];
  }
  return cost;
}

SchurLMSummary SchurLM::solve(const SchurLMOptions& options) {
  SchurLMSummary out;
  const int P = static_cast<int>(poses_.size()), Q = static_cast<int>(points_.size());
  std::vector<double> xp(7 * P), xq(3 * Q);
  for (int i = 0; i < P; ++i) std::copy(poses_[i], poses_[i] + 7, xp.begin() + 7 * i);
  for (int j = 0; j < Q; ++j) std::copy(points_[j], points_[j] + 3, xq.begin() + 3 * j);

  Linearization lin;
  double cost = evaluate(xp, xq, &lin);
  if (!begin_solve(cost, &out)) return out;

  const int FP = num_free_poses_, FQ = num_free_points_;
  if (FP == 0 && FQ == 0) {  // as Ceres: nothing to move, the state is the solution
    out.usable = true;
    out.final_cost = cost;
    out.message = "no free parameters";
    return out;
  }
  // observations of each free point (CSR), for the elimination
  std::vector<int> start(FQ + 1, 0), of_point(observations_.size());
  for (const auto& o : observations_)
    if (point_free_[o.point] >= 0) ++start[point_free_[o.point] + 1];
  for (int j = 0; j < FQ; ++j) start[j + 1] += start[j];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (size_t e = 0; e < observations_.size(); ++e) {
      const int fj = point_free_[observations_[e].point];
      if (fj >= 0) of_point[fill[fj]++] = static_cast<int>(e);
    }
  }
  // Jacobi scaling from the first Jacobian: column c is multiplied by 1 / (1 + |J_c|)
  Eigen::VectorXd scale_p = Eigen::VectorXd::Zero(6 * FP), scale_q = Eigen::VectorXd::Zero(3 * FQ);
  for (size_t e = 0; e < observations_.size(); ++e) {
    const int fi = pose_free_[observations_[e].pose], fj = point_free_[observations_[e].point];
    if (fi >= 0) scale_p.segment<6>(6 * fi) += lin.J_pose[e].colwise().squaredNorm().transpose();
    if (fj >= 0) scale_q.segment<3>(3 * fj) += lin.J_point[e].colwise().squaredNorm().transpose();
  }
  scale_p = (1.0 + scale_p.array().sqrt()).inverse().matrix();
  scale_q = (1.0 + scale_q.array().sqrt()).inverse().matrix();

  LMControl control(options, &out);
  std::vector<Mat63> W(observations_.size());
  std::vector<Mat3> V(FQ);
  std::vector<Eigen::Matrix<double, 6, 6>> U(FP);
  Eigen::VectorXd gp(6 * FP), gq(3 * FQ), dp(6 * FP), dq(3 * FQ);
  std::vector<double> cand_p(xp.size()), cand_q(xq.size());

  while (control.next_step()) {
    // normal equations of the scaled Jacobian J S: H = S J^T J S, g = S J^T r
    for (auto& u : U) u.setZero();
    for (auto& v : V) v.setZero();
    gp.setZero();
    gq.setZero();
    for (size_t e = 0; e < observations_.size(); ++e) {
      const SchurLMObservation& o = observations_[e];
      const int fi = pose_free_[o.pose], fj = point_free_[o.point];
      Mat36 Ap;
      Mat3 Aq;
      if (fi >= 0) {
        Ap = lin.J_pose[e] * scale_p.segment<6>(6 * fi).asDiagonal();
        U[fi].noalias() += Ap.transpose() * Ap;
        gp.segment<6>(6 * fi).noalias() += Ap.transpose() * lin.r[e];
      }
      if (fj >= 0) {
        Aq = lin.J_point[e] * scale_q.segment<3>(3 * fj).asDiagonal();
        V[fj].noalias() += Aq.transpose() * Aq;
        gq.segment<3>(3 * fj).noalias() += Aq.transpose() * lin.r[e];
      }
      if (fi >= 0 && fj >= 0) W[e].noalias() = Ap.transpose() * Aq;
    }
    // Levenberg-Marquardt: (H + diag(clamp(diag H)) / radius) x = -g, points eliminated
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(6 * FP, 6 * FP);
    Eigen::VectorXd rhs = -gp;
    for (int i = 0; i < FP; ++i) {
      for (int a = 0; a < 6; ++a)
        U[i](a, a) += lm_damping(U[i](a, a), control.radius());
      S.block<6, 6>(6 * i, 6 * i) = U[i];
    }
    std::vector<Mat3> V_inv(FQ);
    for (int j = 0; j < FQ; ++j) {
      for (int c = 0; c < 3; ++c)
        V[j](c, c) += lm_damping(V[j](c, c), control.radius());
      V_inv[j] = V[j].llt().solve(Mat3::Identity());
      for (int a = start[j]; a < start[j + 1]; ++a) {
        const int e = of_point[a], fi = pose_free_[observations_[e].pose];
        if (fi < 0) continue;
        const Mat63 Y = W[e] * V_inv[j];
        rhs.segment<6>(6 * fi).noalias() += Y * gq.segment<3>(3 * j);
        for (int b = start[j]; b < start[j + 1]; ++b) {
          const int f = of_point[b], fk = pose_free_[observations_[f].pose];
          if (fk < fi) continue;  // the upper triangle; mirrored below
          S.block<6, 6>(6 * fi, 6 * fk).noalias() -= Y * W[f].transpose();
        }
      }
    }
    bool solved = true;
    if (FP > 0) {
      S.triangularView<Eigen::StrictlyLower>() = S.transpose();
      const Eigen::LLT<Eigen::MatrixXd> llt(S);
      solved = llt.info() == Eigen::Success;
      if (solved) dp = llt.solve(rhs);
    }
    if (solved) {
      for (int j = 0; j < FQ; ++j) {
        Vec3 b = -gq.segment<3>(3 * j);
        for (int a = start[j]; a < start[j + 1]; ++a) {
          const int e = of_point[a], fi = pose_free_[observations_[e].pose];
          if (fi >= 0) b.noalias() -= W[e].transpose() * dp.segment<6>(6 * fi);
        }
        dq.segment<3>(3 * j) = V_inv[j] * b;
      }
      solved = dp.allFinite() && dq.allFinite();
    }
    // the model's cost decrease: -(J x) . (r + J x / 2), unscaled step delta = S x
    double model_change = -1;
    if (solved) {
      dp = dp.cwiseProduct(scale_p);
      dq = dq.cwiseProduct(scale_q);
      model_change = 0;
      for (size_t e = 0; e < observations_.size(); ++e) {
        const int fi = pose_free_[observations_[e].pose], fj = point_free_[observations_[e].point];
        Vec3 m = Vec3::Zero();
        if (fi >= 0) m.noalias() += lin.J_pose[e] * dp.segment<6>(6 * fi);
        if (fj >= 0) m.noalias() += lin.J_point[e] * dq.segment<3>(3 * fj);
        model_change -= m.dot(lin.r[e] + 0.5 * m);
      }
    }
    if (!(model_change > 0)) {  // an invalid step: shrink the region and solve again
      if (control.invalid_step()) break;
      continue;
    }
    cand_p = xp;
    cand_q = xq;
    double step_sq = 0, x_sq = 0;
    for (int i = 0; i < P; ++i) {
      const int fi = pose_free_[i];
      if (fi < 0) continue;
      pose_plus(xp.data() + 7 * i, dp.data() + 6 * fi, cand_p.data() + 7 * i);
      for (int k = 0; k < 7; ++k) {
        step_sq += (cand_p[7 * i + k] - xp[7 * i + k]) * (cand_p[7 * i + k] - xp[7 * i + k]);
        x_sq += xp[7 * i + k] * xp[7 * i + k];
      }
    }
    for (int j = 0; j < Q; ++j) {
      const int fj = point_free_[j];
      if (fj < 0) continue;
      for (int c = 0; c < 3; ++c) {
        cand_q[3 * j + c] = xq[3 * j + c] + dq[3 * fj + c];
        step_sq += dq[3 * fj + c] * dq[3 * fj + c];
        x_sq += xq[3 * j + c] * xq[3 * j + c];
      }
    }
    if (control.step_too_short(std::sqrt(step_sq), std::sqrt(x_sq))) break;
    const LMControl::Verdict verdict = control.judge(cost, evaluate(cand_p, cand_q, nullptr), model_change);
    if (verdict == LMControl::Verdict::kStop) break;
    if (verdict == LMControl::Verdict::kReject) continue;
    xp.swap(cand_p);
    xq.swap(cand_q);
    cost = evaluate(xp, xq, &lin);
    double g_max = 0;  // the unscaled gradient J^T r
    for (size_t e = 0; e < observations_.size(); ++e) {
      const int fi = pose_free_[observations_[e].pose], fj = point_free_[observations_[e].point];
      if (fi >= 0) g_max = std::max(g_max, (lin.J_pose[e].transpose() * lin.r[e]).cwiseAbs().maxCoeff());
      if (fj >= 0) g_max = std::max(g_max, (lin.J_point[e].transpose() * lin.r[e]).cwiseAbs().maxCoeff());
    }
    if (g_max <= options.gradient_tolerance) {
      out.message = "gradient tolerance reached";
      break;
    }
  }
  out.usable = control.usable();
  if (!out.usable) return out;
  for (int i = 0; i < P; ++i) std::copy(xp.begin() + 7 * i, xp.begin() + 7 * i + 7, poses_[i]);
  for (int j = 0; j < Q; ++j) std::copy(xq.begin() + 3 * j, xq.begin() + 3 * j + 3, points_[j]);
  out.final_cost = cost;
  return out;
}

int SchurLM::remove_gated_outliers() {
  std::vector<SchurLMObservation> kept;
  kept.reserve(observations_.size());
  for (const SchurLMObservation& o : observations_) {
    if (!(o.chi2_gate > 0)) {
      kept.push_back(o);
      continue;
    }
    const Eigen::Map<const Eigen::Quaterniond> q(poses_[o.pose] + 3);
    const Vec3 X_c = q.toRotationMatrix() * Eigen::Map<const Vec3>(points_[o.point]) +
                     Eigen::Map<const Vec3>(poses_[o.pose]);
    double chi2 = std::numeric_limits<double>::infinity();
    if (o.z.z() >= 0) {
      Vec3 z;
      if (predict_measurement<3>(camera_, X_c, min_depth_, &z, nullptr))
        chi2 = (o.sqrt_info * (z - o.z)).squaredNorm();
    } else {
      Vec2 z;
      if (predict_measurement<2>(camera_, X_c, min_depth_, &z, nullptr))
        chi2 = (o.sqrt_info * (z - o.z.head<2>())).squaredNorm();
    }
    if (std::isfinite(chi2) && chi2 <= o.chi2_gate) kept.push_back(o);
  }
  const int removed = static_cast<int>(observations_.size() - kept.size());
  observations_.swap(kept);
  return removed;
}

}  // namespace twistslam::optim::detail
