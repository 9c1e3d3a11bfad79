#include "optim/block_lm.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "optim/block_lm_terms.hpp"
#include "optim/lm_trust_region.hpp"

namespace twistslam::optim::detail {

using namespace block_lm_terms;  // the layout and per-residual arithmetic

namespace {

// 0.5 sum rho(|f|^2) at `x`; +inf when a residual cannot be evaluated. With `lin`, the
// corrected residuals and tangent Jacobians as Ceres' ResidualBlock makes them: the ambient
// Jacobian times the manifold's Plus Jacobian, then the loss Corrector (J <- sqrt(rho') (J -
// alpha / s r r^T J), r <- sqrt(rho') / (1 - alpha) r, alpha = 1 - sqrt(1 + 2 s rho'' / rho');
// a plain sqrt(rho') rescaling where rho'' <= 0).
double evaluate(const Problem& p, const std::vector<double>& x, Linearization* lin) {
  double cost = 0;
  const double* params[kMaxBlocksPerResidual];
  double* jac_ptrs[kMaxBlocksPerResidual];
  double ambient[kMaxBlocksPerResidual][kMaxRows * kPoseAmbient];
  double r[kMaxRows];
  for (size_t k = 0; k < p.terms.size(); ++k) {
    const Term& t = p.terms[k];
    for (int i = 0; i < t.num_blocks; ++i) {
      params[i] = x.data() + p.offset[t.block[i]];
      jac_ptrs[i] = lin && t.jacobian[i] >= 0 ? ambient[i] : nullptr;
    }
    if (!p.residuals[k].cost->Evaluate(params, r, lin ? jac_ptrs : nullptr))
      return std::numeric_limits<double>::infinity();
    const Eigen::Map<const Residual> f(r, t.rows);
    if (!f.allFinite()) return std::numeric_limits<double>::infinity();
    const double s = f.squaredNorm();
    double rho[3] = {s, 1.0, 0.0};
    if (p.residuals[k].loss) p.residuals[k].loss->Evaluate(s, rho);
    cost += 0.5 * rho[0];
    if (!lin) continue;
    const double sqrt_rho1 = std::sqrt(rho[1]);
    double residual_scaling = sqrt_rho1, alpha_sq_norm = 0;
    if (s > 0 && rho[2] > 0) {
      const double alpha = 1.0 - std::sqrt(1.0 + 2.0 * s * rho[2] / rho[1]);
      residual_scaling = sqrt_rho1 / (1.0 - alpha);
      alpha_sq_norm = alpha / s;
    }
    dispatch_rows(t.rows, [&](auto rows_c) {
      linearize_term<decltype(rows_c)::value>(t, params, ambient, r, sqrt_rho1, alpha_sq_norm,
                                              residual_scaling, lin);
    });
  }
  return cost;
}

// Each free block's Jacobian columns times its scaling (Ceres scales the Jacobian in place)
void scale_columns(const Problem& p, const Eigen::VectorXd& scale_f, const Eigen::VectorXd& scale_p,
                   Linearization* lin) {
  for (const Term& t : p.terms)
    for (int i = 0; i < t.num_blocks; ++i) {
      if (t.jacobian[i] < 0) continue;
      double* out = lin->J.data() + t.jacobian[i];
      if (t.column[i] >= 0) {
        Eigen::Map<RowBlock<kPoseTangent>> J(out, t.rows, kPoseTangent);
        J = J * scale_f.segment<kPoseTangent>(t.column[i]).asDiagonal();
      } else {
        Eigen::Map<RowBlock<3>> J(out, t.rows, 3);
        J = J * scale_p.segment<3>(3 * t.point).asDiagonal();
      }
    }
}

}  // namespace

bool block_lm_supports(const std::vector<BlockLMBlock>& blocks,
                       const std::vector<BlockLMResidual>& residuals) {
  for (const BlockLMBlock& b : blocks) {
    if (b.fixed) continue;
    if (b.eliminate ? (b.size != 3 || b.is_pose) : !b.is_pose) return false;
  }
  for (const BlockLMResidual& res : residuals) {
    if (!res.cost || res.cost->num_residuals() > kMaxRows ||
        res.blocks.size() > static_cast<size_t>(kMaxBlocksPerResidual))
      return false;
    int eliminated = 0;
    for (int b : res.blocks) {
      if (b < 0 || b >= static_cast<int>(blocks.size())) return false;
      eliminated += blocks[b].eliminate && !blocks[b].fixed;
    }
    if (eliminated > 1) return false;
  }
  return true;
}

SchurLMSummary solve_block_lm(const std::vector<BlockLMBlock>& blocks,
                              const std::vector<BlockLMResidual>& residuals,
                              const SchurLMOptions& options) {
  if (!block_lm_supports(blocks, residuals))
    throw std::invalid_argument(
        "solve_block_lm: a free block is neither a pose nor an eliminated 3-vector, a residual "
        "holds two eliminated blocks, an unknown block, more than 4 blocks or more than 8 rows");
  SchurLMSummary out;
  const Problem p(blocks, residuals);
  std::vector<double> x(p.state_size);
  for (size_t b = 0; b < blocks.size(); ++b)
    std::copy(blocks[b].data, blocks[b].data + blocks[b].size, x.begin() + p.offset[b]);
  Linearization lin(p);
  double cost = evaluate(p, x, &lin);
  if (!begin_solve(cost, &out)) return out;
  const int N = p.num_columns, NP = p.num_points;
  if (N == 0 && NP == 0) {
    out.usable = true;
    out.final_cost = cost;
    out.message = "no free parameters";
    return out;
  }
  // Jacobi scaling of the columns from the first Jacobian: 1 / (1 + |column|)
  Eigen::VectorXd scale_f = Eigen::VectorXd::Zero(N), scale_p = Eigen::VectorXd::Zero(3 * NP);
  for (const Term& t : p.terms)
    for (int i = 0; i < t.num_blocks; ++i) {
      if (t.jacobian[i] < 0) continue;
      const double* J = lin.J.data() + t.jacobian[i];
      if (t.column[i] >= 0)
        scale_f.segment<kPoseTangent>(t.column[i]) +=
            Eigen::Map<const RowBlock<kPoseTangent>>(J, t.rows, kPoseTangent).colwise().squaredNorm().transpose();
      else
        scale_p.segment<3>(3 * t.point) +=
            Eigen::Map<const RowBlock<3>>(J, t.rows, 3).colwise().squaredNorm().transpose();
    }
  scale_f = (1.0 + scale_f.array().sqrt()).inverse().matrix();
  scale_p = (1.0 + scale_p.array().sqrt()).inverse().matrix();
  scale_columns(p, scale_f, scale_p, &lin);

  LMControl control(options, &out);
  Eigen::MatrixXd S(N, N);
  Eigen::VectorXd g(N), rhs(N), dx(N), gp(3 * NP), dp(3 * NP);
  std::vector<Mat3> V(NP), V_inv(NP);
  std::vector<Mat63> W(p.entry_term.size());  // A_pose^T A_point per entry
  std::vector<double> candidate(x.size());
  Eigen::LLT<Eigen::MatrixXd> llt(N);
  while (control.next_step()) {
    // normal equations of the scaled Jacobian, the points' 3x3 blocks apart
    S.setZero();
    g.setZero();
    gp.setZero();
    for (Mat3& v : V) v.setZero();
    for (const Term& t : p.terms)
      dispatch_rows(t.rows, [&](auto rows_c) {
        add_normal_equations<decltype(rows_c)::value>(t, lin, S, g, V, gp);
      });
    for (size_t e = 0; e < W.size(); ++e) {
      const Term& t = p.terms[p.entry_term[e]];
      dispatch_rows(t.rows, [&](auto rows_c) {
        W[e] = pose_point_block<decltype(rows_c)::value>(t, p.entry_slot[e], lin);
      });
    }
    for (int c = 0; c < N; ++c) S(c, c) += lm_damping(S(c, c), control.radius());
    rhs = -g;
    // Schur complement of the points: S -= W V^-1 W^T, rhs += W V^-1 gp
    for (int pt = 0; pt < NP; ++pt) {
      for (int c = 0; c < 3; ++c) V[pt](c, c) += lm_damping(V[pt](c, c), control.radius());
      V_inv[pt] = V[pt].llt().solve(Mat3::Identity());
      const Vec3 gp_p = gp.segment<3>(3 * pt);
      for (int a = p.entry_begin[pt]; a < p.entry_begin[pt + 1]; ++a) {
        const int ca = p.terms[p.entry_term[a]].column[p.entry_slot[a]];
        const Mat63 Y = W[a] * V_inv[pt];
        rhs.segment<kPoseTangent>(ca).noalias() += Y * gp_p;
        for (int b = p.entry_begin[pt]; b < p.entry_begin[pt + 1]; ++b) {
          const int cb = p.terms[p.entry_term[b]].column[p.entry_slot[b]];
          S.block<kPoseTangent, kPoseTangent>(ca, cb).noalias() -= Y * W[b].transpose();
        }
      }
    }
    bool solved = true;
    if (N > 0) {
      llt.compute(S);
      solved = llt.info() == Eigen::Success;
      if (solved) dx = llt.solve(rhs);
    }
    if (solved) {
      for (int pt = 0; pt < NP; ++pt) {
        Vec3 b = -gp.segment<3>(3 * pt);
        for (int a = p.entry_begin[pt]; a < p.entry_begin[pt + 1]; ++a) {
          const int ca = p.terms[p.entry_term[a]].column[p.entry_slot[a]];
          b.noalias() -= W[a].transpose() * dx.segment<kPoseTangent>(ca);
        }
        dp.segment<3>(3 * pt) = V_inv[pt] * b;
      }
      solved = dx.allFinite() && dp.allFinite();
    }
    // the model's decrease in the scaled space, -(J s)^T (f + J s / 2), as Ceres computes it
    double model_change = -1;
    if (solved) {
      model_change = 0;
      for (const Term& t : p.terms)
        dispatch_rows(t.rows, [&](auto rows_c) {
          model_change += model_change_of<decltype(rows_c)::value>(t, lin, dx, dp);
        });
      dx = dx.cwiseProduct(scale_f);
      dp = dp.cwiseProduct(scale_p);
    }
    if (!(model_change > 0)) {
      if (control.invalid_step()) break;
      continue;
    }
    candidate = x;
    double step_sq = 0, x_sq = 0;
    // free poses in block order take consecutive columns, free points consecutive indices
    int column = 0, point = 0;
    for (size_t b = 0; b < blocks.size(); ++b) {
      const BlockLMBlock& blk = blocks[b];
      if (blk.fixed) continue;
      const int o = p.offset[b];
      if (blk.eliminate) {
        for (int c = 0; c < 3; ++c) candidate[o + c] = x[o + c] + dp[3 * point + c];
        ++point;
      } else {
        pose_plus(x.data() + o, dx.data() + column, candidate.data() + o);
        column += kPoseTangent;
      }
      for (int c = 0; c < blk.size; ++c) {
        step_sq += (candidate[o + c] - x[o + c]) * (candidate[o + c] - x[o + c]);
        x_sq += x[o + c] * x[o + c];
      }
    }
    if (control.step_too_short(std::sqrt(step_sq), std::sqrt(x_sq))) break;
    const LMControl::Verdict verdict = control.judge(cost, evaluate(p, candidate, nullptr), model_change);
    if (verdict == LMControl::Verdict::kStop) break;
    if (verdict == LMControl::Verdict::kReject) continue;
    x.swap(candidate);
    cost = evaluate(p, x, &lin);
    scale_columns(p, scale_f, scale_p, &lin);
  }
  out.usable = control.usable();
  if (!out.usable) return out;
  for (size_t b = 0; b < blocks.size(); ++b)
    if (!blocks[b].fixed)
      std::copy(x.begin() + p.offset[b], x.begin() + p.offset[b] + blocks[b].size, blocks[b].data);
  out.final_cost = cost;
  return out;
}

}  // namespace twistslam::optim::detail
