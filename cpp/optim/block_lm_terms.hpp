#pragma once
// Private to block_lm.cpp (Eigen, Ceres' CostFunction): the problem's layout worked out once
// per solve and the per-residual arithmetic of the built-in window solver, on stack-sized
// matrices whose row count is a compile-time constant for the common terms (dispatch_rows).
#include <Eigen/Core>
#include <ceres/cost_function.h>

#include <type_traits>
#include <utility>
#include <vector>

#include "optim/block_lm.hpp"
#include "optim/lm_trust_region.hpp"

namespace twistslam::optim::detail::block_lm_terms {

// Fixed upper bounds keep every per-residual matrix on the stack (what makes this solver
// faster than Ceres on a window: block_lm_supports() refuses anything larger)
constexpr int kMaxRows = 8;              // rows of one residual (the object terms: 1-6)
constexpr int kMaxBlocksPerResidual = 4;
constexpr int kPoseAmbient = 7, kPoseTangent = 6;

// A residual's Jacobian block (Rows x Cols, row-major as Ceres writes it) and residual:
// fixed-size for the common row counts (dispatch_rows), else dynamic rows up to kMaxRows
template <int Rows, int Cols>
using JacobianBlock = Eigen::Matrix<double, Rows, Cols, Cols == 1 ? Eigen::ColMajor : Eigen::RowMajor,
                                    Rows == Eigen::Dynamic ? kMaxRows : Rows, Cols>;
template <int Rows>
using ResidualVector = Eigen::Matrix<double, Rows, 1, 0, Rows == Eigen::Dynamic ? kMaxRows : Rows, 1>;
template <int Cols>
using RowBlock = JacobianBlock<Eigen::Dynamic, Cols>;
using Residual = ResidualVector<Eigen::Dynamic>;
using Mat63 = Eigen::Matrix<double, 6, 3>;

// f(std::integral_constant<int, rows>) for the row counts of the window's terms (e_dyna's 2
// and 3, the twist terms' 6), f(integral_constant<int, Dynamic>) for any other
template <class F>
void dispatch_rows(int rows, F&& f) {
  switch (rows) {
    case 2: f(std::integral_constant<int, 2>{}); break;
    case 3: f(std::integral_constant<int, 3>{}); break;
    case 6: f(std::integral_constant<int, 6>{}); break;
    default: f(std::integral_constant<int, Eigen::Dynamic>{});
  }
}

// One residual's place in the problem, worked out once: which of its blocks are free poses
// (their columns in the reduced system), which is the eliminated point, and where its
// residual and tangent Jacobians live in the flat buffers.
struct Term {
  int rows = 0, num_blocks = 0;
  int block[kMaxBlocksPerResidual] = {};
  int column[kMaxBlocksPerResidual] = {};  // free pose: first column; else -1
  int jacobian[kMaxBlocksPerResidual] = {};  // free block: offset into the Jacobian buffer; else -1
  int point_slot = -1, point = -1;         // the eliminated free point's position and index
  int residual = 0;                        // offset into the residual buffer
};

struct Problem {
  const std::vector<BlockLMBlock>& blocks;
  const std::vector<BlockLMResidual>& residuals;
  std::vector<int> offset;  // block -> state vector
  std::vector<Term> terms;
  int num_columns = 0, num_points = 0, state_size = 0, jacobian_size = 0, residual_size = 0;
  // W entries (a free pose of a residual with a point), grouped by point
  std::vector<int> entry_begin;             // per point, + 1 at the end
  std::vector<int> entry_term, entry_slot;  // residual and its block position

  Problem(const std::vector<BlockLMBlock>& b, const std::vector<BlockLMResidual>& r)
      : blocks(b), residuals(r) {
    std::vector<int> column(b.size(), -1), point(b.size(), -1);
    offset.reserve(b.size());
    for (size_t i = 0; i < b.size(); ++i) {
      offset.push_back(state_size);
      state_size += b[i].size;
      if (b[i].fixed) continue;
      if (b[i].eliminate) {
        point[i] = num_points++;
      } else {
        column[i] = num_columns;
        num_columns += kPoseTangent;
      }
    }
    entry_begin.assign(num_points + 1, 0);  // first: each point's entry count, at [point + 1]
    terms.resize(r.size());
    for (size_t k = 0; k < r.size(); ++k) {
      Term& t = terms[k];
      t.rows = r[k].cost->num_residuals();
      t.num_blocks = static_cast<int>(r[k].blocks.size());
      t.residual = residual_size;
      residual_size += t.rows;
      for (int i = 0; i < t.num_blocks; ++i) {
        const int blk = r[k].blocks[i];
        t.block[i] = blk;
        t.column[i] = column[blk];
        t.jacobian[i] = -1;
        if (column[blk] >= 0) {
          t.jacobian[i] = jacobian_size;
          jacobian_size += t.rows * kPoseTangent;
        } else if (point[blk] >= 0) {
          t.jacobian[i] = jacobian_size;
          jacobian_size += t.rows * 3;
          t.point_slot = i;
          t.point = point[blk];
        }
      }
      if (t.point < 0) continue;
      for (int i = 0; i < t.num_blocks; ++i) entry_begin[t.point + 1] += t.column[i] >= 0;
    }
    // grouped by point in residual order (a counting sort: no list per point); a point without
    // a free pose in any residual keeps an empty group and still gets its 3x3 solve
    for (int pt = 0; pt < num_points; ++pt) entry_begin[pt + 1] += entry_begin[pt];
    entry_term.resize(entry_begin[num_points]);
    entry_slot.resize(entry_begin[num_points]);
    std::vector<int> next(entry_begin.begin(), entry_begin.end() - 1);
    for (size_t k = 0; k < terms.size(); ++k) {
      const Term& t = terms[k];
      if (t.point < 0) continue;
      for (int i = 0; i < t.num_blocks; ++i) {
        if (t.column[i] < 0) continue;
        entry_term[next[t.point]] = static_cast<int>(k);
        entry_slot[next[t.point]++] = i;
      }
    }
  }
};

// The current linearisation: loss-corrected residuals and tangent Jacobians (Jacobi-scaled
// once the scaling is known), in flat buffers laid out by the terms.
struct Linearization {
  std::vector<double> r, J;
  explicit Linearization(const Problem& p) : r(p.residual_size), J(p.jacobian_size) {}
};

// One residual's tangent Jacobians (the ambient ones times the manifold's Plus Jacobian),
// loss-corrected, and its corrected residual into `lin`
template <int R>
void linearize_term(const Term& t, const double* const* params,
                    const double (*ambient)[kMaxRows * kPoseAmbient], const double* r,
                    double sqrt_rho1, double alpha_sq_norm, double residual_scaling,
                    Linearization* lin) {
  const Eigen::Map<const ResidualVector<R>> f(r, t.rows);
  for (int i = 0; i < t.num_blocks; ++i) {
    if (t.jacobian[i] < 0) continue;
    double* out = lin->J.data() + t.jacobian[i];
    if (t.column[i] >= 0) {
      Eigen::Map<JacobianBlock<R, kPoseTangent>> J(out, t.rows, kPoseTangent);
      J.noalias() = Eigen::Map<const JacobianBlock<R, kPoseAmbient>>(ambient[i], t.rows, kPoseAmbient) *
                    pose_plus_jacobian(params[i]);
      if (alpha_sq_norm != 0) {
        const Eigen::Matrix<double, 1, kPoseTangent> rJ = f.transpose() * J;
        J.noalias() -= (alpha_sq_norm * f) * rJ;
      }
      J *= sqrt_rho1;
    } else {
      Eigen::Map<JacobianBlock<R, 3>> J(out, t.rows, 3);
      J = Eigen::Map<const JacobianBlock<R, 3>>(ambient[i], t.rows, 3);
      if (alpha_sq_norm != 0) {
        const Eigen::RowVector3d rJ = f.transpose() * J;
        J.noalias() -= (alpha_sq_norm * f) * rJ;
      }
      J *= sqrt_rho1;
    }
  }
  Eigen::Map<ResidualVector<R>>(lin->r.data() + t.residual, t.rows) = residual_scaling * f;
}

// The term's share of the reduced system (pose-pose blocks, pose gradient) and of its
// point's 3x3 block and gradient
template <int R>
void add_normal_equations(const Term& t, const Linearization& lin, Eigen::MatrixXd& S,
                          Eigen::VectorXd& g, std::vector<Mat3>& V, Eigen::VectorXd& gp) {
  const Eigen::Map<const ResidualVector<R>> f(lin.r.data() + t.residual, t.rows);
  for (int i = 0; i < t.num_blocks; ++i) {
    if (t.column[i] < 0) continue;
    const Eigen::Map<const JacobianBlock<R, kPoseTangent>> Ji(lin.J.data() + t.jacobian[i], t.rows, kPoseTangent);
    g.segment<kPoseTangent>(t.column[i]).noalias() += Ji.transpose() * f;
    for (int j = 0; j < t.num_blocks; ++j) {
      if (t.column[j] < 0) continue;
      const Eigen::Map<const JacobianBlock<R, kPoseTangent>> Jj(lin.J.data() + t.jacobian[j], t.rows, kPoseTangent);
      S.block<kPoseTangent, kPoseTangent>(t.column[i], t.column[j]).noalias() += Ji.transpose() * Jj;
    }
  }
  if (t.point < 0) return;
  const Eigen::Map<const JacobianBlock<R, 3>> Jp(lin.J.data() + t.jacobian[t.point_slot], t.rows, 3);
  V[t.point].noalias() += Jp.transpose() * Jp;
  gp.segment<3>(3 * t.point).noalias() += Jp.transpose() * f;
}

// A_pose^T A_point of the pose at block position `slot` of a term with a point
template <int R>
Mat63 pose_point_block(const Term& t, int slot, const Linearization& lin) {
  const Eigen::Map<const JacobianBlock<R, kPoseTangent>> Ji(lin.J.data() + t.jacobian[slot], t.rows, kPoseTangent);
  const Eigen::Map<const JacobianBlock<R, 3>> Jp(lin.J.data() + t.jacobian[t.point_slot], t.rows, 3);
  return Ji.transpose() * Jp;
}

// The term's share of the model's decrease for the scaled step (dx, dp): -(J s)^T (f + J s / 2)
template <int R>
double model_change_of(const Term& t, const Linearization& lin, const Eigen::VectorXd& dx,
                       const Eigen::VectorXd& dp) {
  const Eigen::Map<const ResidualVector<R>> f(lin.r.data() + t.residual, t.rows);
  ResidualVector<R> m = ResidualVector<R>::Zero(t.rows);
  for (int i = 0; i < t.num_blocks; ++i) {
    if (t.column[i] < 0) continue;
    m.noalias() += Eigen::Map<const JacobianBlock<R, kPoseTangent>>(lin.J.data() + t.jacobian[i], t.rows, kPoseTangent) *
                   dx.segment<kPoseTangent>(t.column[i]);
  }
  if (t.point >= 0)
    m.noalias() += Eigen::Map<const JacobianBlock<R, 3>>(lin.J.data() + t.jacobian[t.point_slot], t.rows, 3) *
                   dp.segment<3>(3 * t.point);
  return -m.dot(f + 0.5 * m);
}

}  // namespace twistslam::optim::detail::block_lm_terms
