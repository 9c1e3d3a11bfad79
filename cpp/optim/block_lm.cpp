#include "optim/block_lm.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "optim/lm_trust_region.hpp"

namespace twistslam::optim::detail {

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

int tangent_size(const BlockLMBlock& b) { return b.is_pose ? 6 : b.size; }

// The problem's layout: each block's parameters in one state vector, the free blocks'
// tangent columns in the reduced system (not eliminated) or their point index (eliminated).
struct Layout {
  std::vector<int> offset;   // into the state vector
  std::vector<int> column;   // first column in the reduced system; -1: fixed or eliminated
  std::vector<int> point;    // index among the eliminated free blocks; -1: other
  int num_columns = 0, num_points = 0, state_size = 0;

  explicit Layout(const std::vector<BlockLMBlock>& blocks) {
    for (const BlockLMBlock& b : blocks) {
      offset.push_back(state_size);
      state_size += b.size;
      column.push_back(!b.fixed && !b.eliminate ? num_columns : -1);
      if (!b.fixed && !b.eliminate) num_columns += tangent_size(b);
      point.push_back(!b.fixed && b.eliminate ? num_points++ : -1);
    }
  }
};

// One residual linearised: loss-corrected residual and tangent Jacobians of its free blocks
struct Linearized {
  Eigen::VectorXd r;
  std::vector<RowMatrix> J;  // per block of the residual; empty for a fixed block
};

// 0.5 sum rho(|f|^2) at `x`; +inf when a residual cannot be evaluated. With `lin`, the
// corrected residuals and tangent Jacobians (Ceres' Corrector: J <- sqrt(rho') (J - alpha / s
// r r^T J), r <- sqrt(rho') / (1 - alpha) r, alpha = 1 - sqrt(1 + 2 s rho'' / rho'), a plain
// sqrt(rho') rescaling where rho'' <= 0).
double evaluate(const std::vector<BlockLMBlock>& blocks, const std::vector<BlockLMResidual>& residuals,
                const Layout& layout, const std::vector<double>& x, std::vector<Linearized>* lin) {
  double cost = 0;
  std::vector<const double*> params;
  std::vector<double*> jac_ptrs;
  std::vector<RowMatrix> ambient;
  for (size_t k = 0; k < residuals.size(); ++k) {
    const BlockLMResidual& res = residuals[k];
    const int m = res.cost->num_residuals();
    params.clear();
    for (int b : res.blocks) params.push_back(x.data() + layout.offset[b]);
    Eigen::VectorXd r(m);
    if (lin) {
      ambient.resize(res.blocks.size());
      jac_ptrs.assign(res.blocks.size(), nullptr);
      for (size_t i = 0; i < res.blocks.size(); ++i) {
        const BlockLMBlock& b = blocks[res.blocks[i]];
        if (b.fixed) continue;
        ambient[i].resize(m, b.size);
        jac_ptrs[i] = ambient[i].data();
      }
    }
    if (!res.cost->Evaluate(params.data(), r.data(), lin ? jac_ptrs.data() : nullptr) ||
        !r.allFinite())
      return std::numeric_limits<double>::infinity();
    const double s = r.squaredNorm();
    double rho[3] = {s, 1.0, 0.0};
    if (res.loss) res.loss->Evaluate(s, rho);
    cost += 0.5 * rho[0];
    if (!lin) continue;
    Linearized& out = (*lin)[k];
    const double sqrt_rho1 = std::sqrt(rho[1]);
    double residual_scaling = sqrt_rho1, alpha_sq_norm = 0;
    if (s > 0 && rho[2] > 0) {
      const double alpha = 1.0 - std::sqrt(1.0 + 2.0 * s * rho[2] / rho[1]);
      residual_scaling = sqrt_rho1 / (1.0 - alpha);
      alpha_sq_norm = alpha / s;
    }
    out.J.resize(res.blocks.size());
    for (size_t i = 0; i < res.blocks.size(); ++i) {
      const BlockLMBlock& b = blocks[res.blocks[i]];
      if (b.fixed) {
        out.J[i].resize(0, 0);
        continue;
      }
      out.J[i] = b.is_pose ? RowMatrix(ambient[i] * pose_plus_jacobian(params[i])) : ambient[i];
      if (alpha_sq_norm != 0) out.J[i] -= alpha_sq_norm * r * (r.transpose() * out.J[i]);
      out.J[i] *= sqrt_rho1;
    }
    out.r = residual_scaling * r;
  }
  return cost;
}

}  // namespace

bool block_lm_supports(const std::vector<BlockLMBlock>& blocks,
                       const std::vector<BlockLMResidual>& residuals) {
  for (const BlockLMBlock& b : blocks)
    if (b.eliminate && (b.size != 3 || b.is_pose)) return false;
  for (const BlockLMResidual& res : residuals) {
    int eliminated = 0;
    for (int b : res.blocks) {
      if (b < 0 || b >= static_cast<int>(blocks.size())) return false;
      eliminated += blocks[b].eliminate && !blocks[b].fixed;
    }
    if (eliminated > 1 || !res.cost) return false;
  }
  return true;
}

SchurLMSummary solve_block_lm(const std::vector<BlockLMBlock>& blocks,
                              const std::vector<BlockLMResidual>& residuals,
                              const SchurLMOptions& options) {
  if (!block_lm_supports(blocks, residuals))
    throw std::invalid_argument("solve_block_lm: an eliminated block is not a 3-vector, or a "
                                "residual holds two of them or an unknown block");
  SchurLMSummary out;
  const Layout layout(blocks);
  std::vector<double> x(layout.state_size);
  for (size_t b = 0; b < blocks.size(); ++b)
    std::copy(blocks[b].data, blocks[b].data + blocks[b].size, x.begin() + layout.offset[b]);
  std::vector<Linearized> lin(residuals.size());
  double cost = evaluate(blocks, residuals, layout, x, &lin);
  if (!std::isfinite(cost)) {
    out.message = "the initial state cannot be evaluated";
    return out;
  }
  out.initial_cost = cost;
  out.iterations = 1;
  const int N = layout.num_columns, NP = layout.num_points;
  if (N == 0 && NP == 0) {
    out.usable = true;
    out.final_cost = cost;
    out.message = "no free parameters";
    return out;
  }
  // each point's (residual, position of the point in it)
  std::vector<std::vector<std::pair<int, int>>> of_point(NP);
  for (size_t k = 0; k < residuals.size(); ++k)
    for (size_t i = 0; i < residuals[k].blocks.size(); ++i) {
      const int p = layout.point[residuals[k].blocks[i]];
      if (p >= 0) of_point[p].push_back({static_cast<int>(k), static_cast<int>(i)});
    }
  // Jacobi scaling of the columns from the first Jacobian
  Eigen::VectorXd scale_f = Eigen::VectorXd::Zero(N), scale_p = Eigen::VectorXd::Zero(3 * NP);
  for (size_t k = 0; k < residuals.size(); ++k)
    for (size_t i = 0; i < residuals[k].blocks.size(); ++i) {
      const int b = residuals[k].blocks[i];
      if (lin[k].J[i].size() == 0) continue;
      const Eigen::VectorXd sq = lin[k].J[i].colwise().squaredNorm().transpose();
      if (layout.column[b] >= 0) scale_f.segment(layout.column[b], sq.size()) += sq;
      else scale_p.segment<3>(3 * layout.point[b]) += sq;
    }
  scale_f = (1.0 + scale_f.array().sqrt()).inverse().matrix();
  scale_p = (1.0 + scale_p.array().sqrt()).inverse().matrix();
  // scaled Jacobian of block position i of residual k
  const auto scaled = [&](int k, int i) -> RowMatrix {
    const int b = residuals[k].blocks[i];
    if (layout.column[b] >= 0)
      return lin[k].J[i] * scale_f.segment(layout.column[b], lin[k].J[i].cols()).asDiagonal();
    return lin[k].J[i] * scale_p.segment<3>(3 * layout.point[b]).asDiagonal();
  };

  LMControl control(options, &out);
  Eigen::VectorXd dx(N), dp(3 * NP);
  std::vector<double> candidate(x.size());
  while (control.next_step()) {
    // normal equations of the scaled Jacobian, the points' blocks apart
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(N, N);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(N), gp = Eigen::VectorXd::Zero(3 * NP);
    std::vector<Mat3> V(NP, Mat3::Zero());
    // per residual with a point: W_i = A_i^T A_point for its reduced-system blocks i
    std::vector<std::vector<Eigen::MatrixXd>> W(residuals.size());
    std::vector<int> point_pos(residuals.size(), -1);
    for (size_t k = 0; k < residuals.size(); ++k) {
      const auto& blks = residuals[k].blocks;
      std::vector<RowMatrix> A(blks.size());
      for (size_t i = 0; i < blks.size(); ++i)
        if (lin[k].J[i].size() > 0) A[i] = scaled(static_cast<int>(k), static_cast<int>(i));
      for (size_t i = 0; i < blks.size(); ++i) {
        if (A[i].size() == 0) continue;
        const int ci = layout.column[blks[i]];
        if (ci < 0) {  // the point
          point_pos[k] = static_cast<int>(i);
          const int p = layout.point[blks[i]];
          V[p].noalias() += A[i].transpose() * A[i];
          gp.segment<3>(3 * p).noalias() += A[i].transpose() * lin[k].r;
          continue;
        }
        g.segment(ci, A[i].cols()).noalias() += A[i].transpose() * lin[k].r;
        for (size_t j = 0; j < blks.size(); ++j) {
          const int cj = layout.column[blks[j]];
          if (A[j].size() == 0 || cj < 0) continue;
          S.block(ci, cj, A[i].cols(), A[j].cols()).noalias() += A[i].transpose() * A[j];
        }
      }
      if (point_pos[k] >= 0) {
        W[k].resize(blks.size());
        for (size_t i = 0; i < blks.size(); ++i)
          if (A[i].size() > 0 && layout.column[blks[i]] >= 0)
            W[k][i] = A[i].transpose() * A[point_pos[k]];
      }
    }
    for (int c = 0; c < N; ++c) S(c, c) += lm_damping(S(c, c), control.radius());
    Eigen::VectorXd rhs = -g;
    std::vector<Mat3> V_inv(NP);
    for (int p = 0; p < NP; ++p) {
      for (int c = 0; c < 3; ++c) V[p](c, c) += lm_damping(V[p](c, c), control.radius());
      V_inv[p] = V[p].llt().solve(Mat3::Identity());
      for (const auto& [k, pk] : of_point[p]) {
        const auto& blks = residuals[k].blocks;
        for (size_t i = 0; i < blks.size(); ++i) {
          if (W[k].empty() || W[k][i].size() == 0) continue;
          const int ci = layout.column[blks[i]];
          const Eigen::MatrixXd Y = W[k][i] * V_inv[p];
          rhs.segment(ci, Y.rows()).noalias() += Y * gp.segment<3>(3 * p);
          for (const auto& [l, pl] : of_point[p]) {
            const auto& blks_l = residuals[l].blocks;
            for (size_t j = 0; j < blks_l.size(); ++j) {
              if (W[l].empty() || W[l][j].size() == 0) continue;
              const int cj = layout.column[blks_l[j]];
              S.block(ci, cj, Y.rows(), W[l][j].rows()).noalias() -= Y * W[l][j].transpose();
            }
          }
        }
        (void)pk;
      }
    }
    bool solved = true;
    if (N > 0) {
      const Eigen::LLT<Eigen::MatrixXd> llt(S);
      solved = llt.info() == Eigen::Success;
      if (solved) dx = llt.solve(rhs);
    }
    if (solved) {
      for (int p = 0; p < NP; ++p) {
        Vec3 b = -gp.segment<3>(3 * p);
        for (const auto& [k, pk] : of_point[p]) {
          const auto& blks = residuals[k].blocks;
          for (size_t i = 0; i < blks.size(); ++i)
            if (!W[k].empty() && W[k][i].size() > 0)
              b.noalias() -= W[k][i].transpose() * dx.segment(layout.column[blks[i]], W[k][i].rows());
          (void)pk;
        }
        dp.segment<3>(3 * p) = V_inv[p] * b;
      }
      solved = dx.allFinite() && dp.allFinite();
    }
    double model_change = -1;
    if (solved) {
      dx = dx.cwiseProduct(scale_f);
      dp = dp.cwiseProduct(scale_p);
      model_change = 0;
      for (size_t k = 0; k < residuals.size(); ++k) {
        Eigen::VectorXd m = Eigen::VectorXd::Zero(lin[k].r.size());
        for (size_t i = 0; i < residuals[k].blocks.size(); ++i) {
          if (lin[k].J[i].size() == 0) continue;
          const int b = residuals[k].blocks[i];
          m.noalias() += layout.column[b] >= 0
                             ? Eigen::VectorXd(lin[k].J[i] * dx.segment(layout.column[b], lin[k].J[i].cols()))
                             : Eigen::VectorXd(lin[k].J[i] * dp.segment<3>(3 * layout.point[b]));
        }
        model_change -= m.dot(lin[k].r + 0.5 * m);
      }
    }
    if (!(model_change > 0)) {
      if (control.invalid_step()) break;
      continue;
    }
    candidate = x;
    double step_sq = 0, x_sq = 0;
    for (size_t b = 0; b < blocks.size(); ++b) {
      const BlockLMBlock& blk = blocks[b];
      if (blk.fixed) continue;
      const int o = layout.offset[b];
      const double* delta = layout.column[b] >= 0 ? dx.data() + layout.column[b]
                                                  : dp.data() + 3 * layout.point[b];
      if (blk.is_pose) {
        pose_plus(x.data() + o, delta, candidate.data() + o);
      } else {
        for (int c = 0; c < blk.size; ++c) candidate[o + c] = x[o + c] + delta[c];
      }
      for (int c = 0; c < blk.size; ++c) {
        step_sq += (candidate[o + c] - x[o + c]) * (candidate[o + c] - x[o + c]);
        x_sq += x[o + c] * x[o + c];
      }
    }
    if (control.step_too_short(std::sqrt(step_sq), std::sqrt(x_sq))) break;
    const LMControl::Verdict verdict =
        control.judge(cost, evaluate(blocks, residuals, layout, candidate, nullptr), model_change);
    if (verdict == LMControl::Verdict::kStop) break;
    if (verdict == LMControl::Verdict::kReject) continue;
    x.swap(candidate);
    cost = evaluate(blocks, residuals, layout, x, &lin);
  }
  out.usable = control.usable();
  if (!out.usable) return out;
  for (size_t b = 0; b < blocks.size(); ++b)
    if (!blocks[b].fixed)
      std::copy(x.begin() + layout.offset[b], x.begin() + layout.offset[b] + blocks[b].size, blocks[b].data);
  out.final_cost = cost;
  return out;
}

}  // namespace twistslam::optim::detail
