#include "registration/gicp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "geometry/se3.hpp"
#include "registration/gicp_terms.hpp"
#include "registration/point_covariances.hpp"

namespace twistslam::registration {

GicpScan make_gicp_scan(const Eigen::Ref<const Points3>& points, int num_neighbors) {
  if (num_neighbors < 3)
    throw std::invalid_argument("make_gicp_scan: num_neighbors must be >= 3 (a plane needs 3)");
  GicpScan scan;
  scan.num_neighbors = num_neighbors;
  scan.points.reserve(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Vec3 p = points.row(i).transpose();
    if (p.allFinite())
      scan.points.push_back(p);
    else
      ++scan.num_dropped_non_finite;
  }
  scan.tree = KdTree(scan.points);
  // Only the normals are kept: linearize() uses the covariances' closed-form pair information
  // (plane_pair_information), never the 3x3 matrices.
  if (static_cast<int>(scan.points.size()) >= num_neighbors)
    scan.normals = plane_normals(scan.points, scan.tree, num_neighbors, &scan.neighborhoods,
                                 &scan.grid);
  return scan;
}

void validate(const GicpOptions& o) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("GicpOptions: ") + what);
  };
  require(std::isfinite(o.max_correspondence_distance_m) && o.max_correspondence_distance_m > 0,
          "max_correspondence_distance_m must be finite and > 0");
  require(o.max_iterations >= 1, "max_iterations must be >= 1");
  require(std::isfinite(o.convergence_translation_m) && o.convergence_translation_m >= 0,
          "convergence_translation_m must be finite and >= 0");
  require(std::isfinite(o.convergence_rotation_rad) && o.convergence_rotation_rad >= 0,
          "convergence_rotation_rad must be finite and >= 0");
  require(o.num_neighbors >= 3, "num_neighbors must be >= 3");
  require(std::isfinite(o.huber_threshold) && o.huber_threshold > 0,
          "huber_threshold must be finite and > 0");
  require(o.projector.allFinite(), "projector must be finite");
  require(o.min_correspondences >= 1, "min_correspondences must be >= 1");
  require(o.max_step_halvings >= 0, "max_step_halvings must be >= 0");
}

std::string status_name(GicpStatus status) {
  switch (status) {
    case GicpStatus::kConverged: return "converged";
    case GicpStatus::kMaxIterations: return "max_iterations";
    case GicpStatus::kTooFewPoints: return "too_few_points";
    case GicpStatus::kTooFewCorrespondences: return "too_few_correspondences";
    case GicpStatus::kDegenerate: return "degenerate";
  }
  return "unknown";
}

namespace {

// The normal equations at one estimate of T.
struct Linearization {
  Mat6 H = Mat6::Zero();
  Vec6 b = Vec6::Zero();
  double cost = 0.0;
  double sum_squared_error_m2 = 0.0;
  int num_inliers = 0;
};

// Slack (m) taken off a clearance: the neighbourhoods are exact up to the grid k-NN's float
// rounding (~1e-6 m, grid_knn.hpp), so a point that close to the radius may be missing.
constexpr double kClearanceSlackM = 1e-5;

}  // namespace

// When the neighbourhood certifies the answer, the points within R - rho of q (R the hint's
// neighbourhood radius, rho its distance to q) are all among its candidates, so the clearance
// is the smaller of that and the second-nearest candidate's distance.
Neighbor nearest_in_scan(const GicpScan& scan, const Vec3& q, double max_d2, int hint,
                         double* clearance_m) {
  *clearance_m = 0.0;
  const Neighborhoods& nb = scan.neighborhoods;
  if (nb.size == 0 || scan.grid.empty()) return scan.tree.nearest(q, max_d2, hint);
  double bound2 = std::numeric_limits<double>::infinity();  // a point seen is this near
  for (int hop = 0; hop < kMaxNeighborhoodHops && hint >= 0; ++hop) {
    const double rho2 = (scan.points[hint] - q).squaredNorm();
    const int* candidates = nb.indices.data() + static_cast<std::size_t>(hint) * nb.size;
    // The hint is among its own neighbours (or, with k coincident copies, ties with them).
    // Branch-free: which candidate is nearer is unpredictable.
    int best_index = hint;
    double best2 = std::numeric_limits<double>::infinity(), second2 = best2;
    for (int j = 0; j < nb.size; ++j) {
      const int c = candidates[j];
      const double d2 = (scan.points[c] - q).squaredNorm();
      second2 = std::min(second2, std::max(best2, d2));
      const bool nearer = d2 < best2;
      best_index = nearer ? c : best_index;
      best2 = nearer ? d2 : best2;
    }
    Neighbor best{best_index, best2};
    // The nearest point is no farther from q than the best candidate (best_d), so within
    // rho + best_d of the hint: inside the hint's neighbourhood when that fits in its radius
    // (best_d <= rho: the hint is a candidate; the bound 2 rho sent 7 % more of the simulated
    // bench's searches to the grid).
    const double rho = std::sqrt(rho2), best_d = std::sqrt(best2);
    const double radius = std::sqrt(nb.radius2_m2[hint]);
    if (rho + best_d <= radius) {
      if (best.squared_distance_m2 >= max_d2) best.index = -1;
      *clearance_m = std::max(0.0, std::min(std::sqrt(second2), radius - rho) -
                                       kClearanceSlackM);
      return best;
    }
    bound2 = best2;
    if (best.index == hint) break;
    hint = best.index;  // closer to q: its neighbourhood may certify
  }
  const Neighbor found = scan.grid.nearest(q, max_d2, bound2, clearance_m);
  *clearance_m = std::max(0.0, *clearance_m - kClearanceSlackM);
  return found;
}

Neighbor nearest_in_scan(const GicpScan& scan, const Vec3& q, double max_d2, int hint) {
  double clearance_m;
  return nearest_in_scan(scan, q, max_d2, hint, &clearance_m);
}

namespace {

// A source point's correspondence at the last search: the target neighbour (-1 = none), where
// the point was then (target frame) and a lower bound on its distance to every other target
// point (0 = unknown). While the point has moved by delta < clearance - |q - neighbour| since,
// the neighbour is still the nearest (triangle inequality) and is kept without a search.
struct Correspondence {
  int neighbor = -1;
  double clearance_m = 0.0;
  Vec3 searched_at = Vec3::Zero();
};

// `previous` holds each source point's last correspondence and is updated: it is kept when
// certified (above), else it seeds the next search, which mostly ends right there.
Linearization linearize(const GicpScan& source, const GicpScan& target, const Mat4& T,
                        const GicpOptions& o, std::vector<Correspondence>* previous) {
  Linearization lin;
  const Mat3 R = T.topLeftCorner<3, 3>();
  const Vec3 t = T.topRightCorner<3, 1>();
  const double max_d2 = o.max_correspondence_distance_m * o.max_correspondence_distance_m;
  // J = [-I, hat(q)] for e(delta) = e - delta_v + q x delta_w (T <- exp(delta) T) and
  // W = (C_t + R C_s R^T)^-1 = 0.5 I + a_u u u^T + a_v v v^T (plane_pair_information), so
  // J^T W J = 0.5 J^T J + a_u g_u g_u^T + a_v g_v g_v^T with g = J^T u = [-u; u x q]: the
  // 0.5 J^T J part is [I, -hat(q); hat(q), |q|^2 I - q q^T], summed from the moments of q at
  // the end, the rest two 6-vector outer products per correspondence (no 3x3 inverse, fewer
  // multiplications than the 3x3 blocks of W, W hat(q) and hat(q) W hat(q)). The search below
  // collects each correspondence's vectors; sum_normal_equations sums them eight at a time.
  thread_local GicpTerms terms;
  terms.reset(static_cast<int>(source.points.size()));
  // Source points in their tree's leaf order: consecutive points are close, so a point without
  // a previous neighbour (first iteration) borrows the last one found as its hint.
  int last_found = -1;
  for (const int i : source.tree.leaf_order()) {
    const Vec3 q = R * source.points[i] + t;
    Correspondence& c = (*previous)[i];
    Neighbor nn{-1, 0.0};
    bool kept = false;
    if (c.neighbor >= 0 && c.clearance_m > 0.0) {
      const double moved = (q - c.searched_at).norm();
      const double reach = c.clearance_m - moved;
      const double d2 = (target.points[c.neighbor] - q).squaredNorm();
      if (reach > 0.0 && d2 < reach * reach) {
        kept = true;
        nn = Neighbor{d2 < max_d2 ? c.neighbor : -1, d2};
      }
    }
    if (!kept) {
      const int hint = c.neighbor >= 0 ? c.neighbor : last_found;
      nn = nearest_in_scan(target, q, max_d2, hint, &c.clearance_m);
      c.searched_at = q;
    }
    c.neighbor = nn.index;
    if (nn.index < 0) continue;
    last_found = nn.index;
    terms.add(q, target.points[nn.index] - q, target.normals[nn.index], R * source.normals[i]);
  }
  lin.num_inliers = terms.size();
  const GicpNormalEquations sums =
      sum_normal_equations(terms, o.kernel == RobustKernel::kHuber, o.huber_threshold);
  lin.H = sums.H;
  lin.b = sums.b;
  lin.cost = sums.cost;
  lin.sum_squared_error_m2 = sums.sum_squared_error_m2;
  return lin;
}

}  // namespace

GicpResult gicp(const GicpScan& source, const GicpScan& target, const Mat4& T_init,
                const GicpOptions& options) {
  validate(options);
  GicpResult result;
  result.T_target_source = T_init;
  if (!source.usable() || !target.usable()) {
    result.status = GicpStatus::kTooFewPoints;
    return result;
  }
  const Mat6& Pi = options.projector;
  // Identity on the directions the link forbids, so the restricted system stays invertible and
  // those directions get a zero update.
  const Mat6 locked = Mat6::Identity() - Pi;
  Mat4 T = T_init;
  std::vector<Correspondence> correspondences(source.points.size());
  result.status = GicpStatus::kMaxIterations;
  // Backtracking: nearest-neighbour correspondences change between iterations, and on real
  // scans plain Gauss-Newton can then cycle between two estimates ~1 mm apart (measured on
  // 0001: 4 in 10 consecutive pairs never met the thresholds). A step that raises the mean
  // cost is undone and retried at half length.
  Mat4 T_accepted = T;
  Vec6 step = Vec6::Zero();
  double accepted_mean_cost = std::numeric_limits<double>::infinity();
  int halvings = 0;  // consecutive rejected steps
  auto small = [&](const Vec6& d) {
    return d.head<3>().norm() < options.convergence_translation_m &&
           d.tail<3>().norm() < options.convergence_rotation_rad;
  };
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    result.iterations = iteration;
    const Linearization lin = linearize(source, target, T, options, &correspondences);
    if (lin.num_inliers < options.min_correspondences) {
      result.num_inliers = lin.num_inliers;
      result.status = GicpStatus::kTooFewCorrespondences;
      break;
    }
    const double mean_cost = lin.cost / lin.num_inliers;
    if (mean_cost > accepted_mean_cost) {
      step *= 0.5;
      T = geometry::se3_exp(step) * T_accepted;
      if (small(step) || ++halvings > options.max_step_halvings) {
        T = T_accepted;
        result.status = GicpStatus::kConverged;
        break;
      }
      continue;
    }
    T_accepted = T;
    accepted_mean_cost = mean_cost;
    halvings = 0;
    result.num_inliers = lin.num_inliers;
    result.cost = lin.cost;
    result.rmse_m = std::sqrt(lin.sum_squared_error_m2 / lin.num_inliers);
    result.information = lin.H;
    const Mat6 H = Pi * lin.H * Pi + locked;
    const Eigen::LDLT<Mat6> ldlt(H);
    step = Pi * ldlt.solve(-(Pi * lin.b));
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !step.allFinite()) {
      result.status = GicpStatus::kDegenerate;
      break;
    }
    T = geometry::se3_exp(step) * T;
    if (small(step)) {
      result.status = GicpStatus::kConverged;
      break;
    }
  }
  result.T_target_source = T;
  result.converged = result.status == GicpStatus::kConverged;
  return result;
}

GicpResult gicp(const Eigen::Ref<const Points3>& source, const Eigen::Ref<const Points3>& target,
                const Mat4& T_init, const GicpOptions& options) {
  validate(options);
  const GicpScan s = make_gicp_scan(source, options.num_neighbors);
  const GicpScan t = make_gicp_scan(target, options.num_neighbors);
  return gicp(s, t, T_init, options);
}

}  // namespace twistslam::registration
