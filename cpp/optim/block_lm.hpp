#pragma once
// Private (Ceres cost functions, not its solver): Levenberg-Marquardt over ProblemBuilder's
// blocks and residuals for small problems with points to eliminate -- the per-object windows
// of the visual tracking (optim/visual_object_window.cpp): ~10 object poses, a few hundred
// object-frame points, every object term of eq. 9. The residuals are the builder's own Ceres
// cost functions and losses; what it replaces is Ceres' solver, whose set-up, generic
// (dynamic-size) Schur elimination and per-residual bookkeeping cost more than the
// arithmetic of a problem this small. The steps follow Ceres' DENSE_SCHUR by the rules of
// schur_lm.hpp (the same trust region, scaling, tolerances and iteration count), with Ceres'
// loss correction (the Triggs correction where rho'' > 0, a plain rescaling elsewhere) and
// the pose manifold of pose_parameterization.hpp. A free block is a pose or an eliminated
// 3-vector; a residual holds at most one eliminated block, 4 blocks and 8 rows (the per-residual
// matrices live on the stack: block_lm_terms.hpp).
#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <memory>
#include <vector>

#include "optim/schur_lm.hpp"

namespace twistslam::optim::detail {

struct BlockLMBlock {
  double* data = nullptr;
  int size = 0;
  bool is_pose = false;    // a 7-vector [t, q] on the pose manifold (tangent 6)
  bool fixed = false;
  bool eliminate = false;  // a point: eliminated by its 3x3 block (size 3)
};

struct BlockLMResidual {
  const ceres::CostFunction* cost = nullptr;  // not owned
  const ceres::LossFunction* loss = nullptr;  // not owned; nullptr: plain least squares
  std::vector<int> blocks;                    // indices into the blocks, in the cost's order
};

// True when solve() can take these: every free block a pose or an eliminated 3-vector, at
// most one eliminated block, 4 blocks and 8 rows in a residual.
bool block_lm_supports(const std::vector<BlockLMBlock>& blocks,
                       const std::vector<BlockLMResidual>& residuals);

// Refines the free blocks in place (see SchurLM::solve for the summary's meaning). Throws
// std::invalid_argument for a problem block_lm_supports() refuses.
SchurLMSummary solve_block_lm(const std::vector<BlockLMBlock>& blocks,
                              const std::vector<BlockLMResidual>& residuals,
                              const SchurLMOptions& options);

}  // namespace twistslam::optim::detail
