#pragma once
// Generalized ICP between two object scans (Segal et al. 2009; TwistSLAM++ eq. 6-7): finds
// T_target_source minimising sum_i e_i^T (C_t + R C_s R^T)^-1 e_i, e_i = t_j - T s_i, with
// nearest-neighbour correspondences re-found every iteration. Gauss-Newton on SE(3) with the
// left update T <- exp(Pi delta) T, delta = [v; w] expressed in the target scan's frame and Pi
// the link projector (geometry/link_projection.hpp; identity = free motion).
#include <string>
#include <vector>

#include "geometry/types.hpp"
#include "registration/kdtree.hpp"
#include "registration/point_covariances.hpp"
#include "registration/point_grid.hpp"

namespace twistslam::registration {

// A scan ready for GICP: finite points, their KD-tree and plane covariances. Build it once;
// the scan of frame i serves as the target at i and as the source at i + 1.
struct GicpScan {
  std::vector<Vec3> points;
  // Each point's plane normal (its covariance is plane_covariance(normal)); empty when the scan
  // has too few points.
  std::vector<Vec3> normals;
  Neighborhoods neighborhoods;    // each point's num_neighbors nearest (correspondence search)
  PointGrid grid;                 // the points by voxel (correspondences not found nearby)
  KdTree tree;
  int num_neighbors = 0;
  int num_dropped_non_finite = 0;  // NaN / Inf rows left out of `points`

  // True when there are normals (covariances), i.e. at least num_neighbors finite points.
  bool usable() const { return !normals.empty(); }
};

// Builds a scan from (N, 3) points (m); NaN / Inf rows are dropped and counted. With fewer than
// num_neighbors finite points the scan is returned without normals (usable() false).
// Throws std::invalid_argument when num_neighbors < 3.
GicpScan make_gicp_scan(const Eigen::Ref<const Points3>& points, int num_neighbors);

// The point of `scan` nearest to q within sqrt(max_d2) (index -1 when none), exact: equal to
// scan.tree.nearest. With `hint` (e.g. q's neighbour at the previous GICP iteration; -1 =
// none) at distance rho from q, the answer lies within 2 rho of the hint, so when that fits in
// the hint's stored neighbourhood it is found there without the tree; else the closest point of
// that neighbourhood becomes the hint (at most kMaxNeighborhoodHops tries), then the scan's
// voxel grid within the nearest candidate seen (the tree when the scan has no grid).
Neighbor nearest_in_scan(const GicpScan& scan, const Vec3& q, double max_d2, int hint);

// Same, and in *clearance_m a lower bound (m) on the distance from q to every other point of
// the scan (0 when unknown: after a tree search). GICP keeps a correspondence without a search
// while the source point has moved by less than clearance - |q - neighbour| (the neighbour is
// then still the nearest).
Neighbor nearest_in_scan(const GicpScan& scan, const Vec3& q, double max_d2, int hint,
                         double* clearance_m);

// Neighbourhood tries before the tree search. 2: on the bench's pairs 55-74 % of all GICP
// correspondence searches (64-87 % of those with a previous neighbour) end in a neighbourhood,
// the second try adding 7-8 points; it cut the alignment's time by a further 5-8 % on the
// simulated pairs, 4 tries no more than noise.
inline constexpr int kMaxNeighborhoodHops = 2;

enum class RobustKernel { kNone, kHuber };

// GicpOptions' default neighbour count as a compile-time constant (GicpOptions holds an Eigen
// matrix, so it is not a literal type and GicpOptions().num_neighbors is not constexpr).
inline constexpr int kDefaultNumNeighbors = 20;

struct GicpOptions {
  // Source / target pairs farther apart (after the current estimate) are not correspondences.
  // 1 m: a car at 10 Hz moves < 3 m per frame and the prediction removes most of it; 0.25-1 m
  // gave the same errors on the bench's real pairs (within 0.5 cm / 0.3 deg).
  double max_correspondence_distance_m = 1.0;
  // 30: converged pairs took 5-16 iterations on average in the bench.
  int max_iterations = 30;
  // Converged when an update moves less than both of these. 1 mm / 1e-3 rad (0.06 deg): on
  // the bench's real and simulated car pairs the errors are the same as with 1e-4 (within
  // 0.01 cm / 0.002 deg), with 40 % fewer iterations and 87-100 % of pairs converged (60-83 %).
  double convergence_translation_m = 1e-3;
  double convergence_rotation_rad = 1e-3;
  // Neighbours per covariance (itself included); used when gicp() builds the scans. 20
  // (small_gicp's default): 10 and 30 were less accurate on the bench's real-known and
  // simulated pairs (median rotation error 0.15-0.16 vs 0.14 deg; 0.41-0.57 vs 0.36 deg).
  int num_neighbors = kDefaultNumNeighbors;
  RobustKernel kernel = RobustKernel::kNone;
  // Huber threshold on the Mahalanobis residual sqrt(e^T C^-1 e) (C has unit in-plane
  // variance, so this is m along a plane and ~sqrt(eps) m across it). Off by default: Huber
  // (0.05-0.1) did not help on the known-motion pairs and doubled the iterations.
  double huber_threshold = 0.1;
  // Projector onto the twist sub-space the link allows, in the target frame.
  Mat6 projector = Mat6::Identity();
  // Fewer correspondences than this leave the estimate unconstrained: stop, not converged
  // (6 unknowns; 10 leaves a margin over a minimal set).
  int min_correspondences = 10;
  // A step that raises the mean cost is retried at half length at most this many times in a
  // row; then the last accepted estimate is returned as converged. 1: on the bench's 180 pairs
  // the median errors of unlimited halving within 0.08 cm / 0.001 deg (means 0.07 cm / 0.03
  // deg) with about half the iterations (median 13 -> 7 on real consecutive pairs): a step
  // still rejected at half length was mostly rejected down to the thresholds (the
  // re-associated cost has a kink there).
  int max_step_halvings = 1;
};

// Throws std::invalid_argument naming the first bad field.
void validate(const GicpOptions& options);

enum class GicpStatus {
  kConverged,
  kMaxIterations,         // the last update was still above the thresholds
  kTooFewPoints,          // a scan has fewer finite points than num_neighbors
  kTooFewCorrespondences, // fewer than min_correspondences within the distance
  kDegenerate,            // the system (restricted to the link) is singular
};
std::string status_name(GicpStatus status);

struct GicpResult {
  Mat4 T_target_source = Mat4::Identity();
  GicpStatus status = GicpStatus::kTooFewPoints;
  bool converged = false;
  int iterations = 0;
  // The next four are from the last linearisation, one update before T_target_source (an
  // update below the convergence thresholds when converged): no extra correspondence pass.
  int num_inliers = 0;    // correspondences within max_correspondence_distance_m
  double rmse_m = 0.0;    // Euclidean RMS of those correspondences' residuals
  double cost = 0.0;      // the GICP cost (sum of squared Mahalanobis residuals, or Huber)
  // Gauss-Newton Hessian J^T W J (twist [v; w], target frame, left perturbation; not
  // projected): the information of T for weighting e_reg.
  Mat6 information = Mat6::Zero();
};

// Aligns `source` onto `target` starting from T_init (the tracking prediction).
GicpResult gicp(const GicpScan& source, const GicpScan& target, const Mat4& T_init,
                const GicpOptions& options = GicpOptions());

// Convenience: builds both scans with options.num_neighbors, then aligns.
GicpResult gicp(const Eigen::Ref<const Points3>& source, const Eigen::Ref<const Points3>& target,
                const Mat4& T_init, const GicpOptions& options = GicpOptions());

}  // namespace twistslam::registration
