#include "geometry/plane_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace twistslam::geometry {
namespace {

Vec4 oriented(const Vec3& n, double d) {
  // Fix the sign so the same plane always comes out the same: camera origin on the + side.
  return d < 0 ? Vec4(-n.x(), -n.y(), -n.z(), -d) : Vec4(n.x(), n.y(), n.z(), d);
}

double plane_distance(const Points3& P, Eigen::Index i, const Vec4& plane) {
  return P(i, 0) * plane.x() + P(i, 1) * plane.y() + P(i, 2) * plane.z() + plane.w();
}

int mark_inliers(const Points3& P, const Vec4& plane, double thr, std::vector<std::uint8_t>* flags) {
  int count = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const bool in = std::abs(plane_distance(P, i, plane)) <= thr;
    if (flags) (*flags)[i] = in;
    count += in;
  }
  return count;
}

// The inliers of a RANSAC hypothesis, or -1 once it can no longer exceed `to_beat` (even if
// every point left were an inlier): most samples are off the plane and stop early.
int count_inliers_above(const Points3& P, const Vec4& plane, double thr, int to_beat) {
  constexpr Eigen::Index kBlock = 256;  // points between two checks
  const Eigen::Index n = P.rows();
  int count = 0;
  for (Eigen::Index start = 0; start < n; start += kBlock) {
    const Eigen::Index end = std::min(n, start + kBlock);
    for (Eigen::Index i = start; i < end; ++i) count += std::abs(plane_distance(P, i, plane)) <= thr;
    if (count + (n - end) <= to_beat) return -1;
  }
  return count;
}

Points3 gather(const Points3& P, const std::vector<std::uint8_t>& flags, int count) {
  Points3 out(count, 3);
  int k = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (flags[i]) out.row(k++) = P.row(i);
  return out;
}

}  // namespace

Vec4 fit_plane_svd(const Points3& points) {
  if (points.rows() < 3) throw std::invalid_argument("fit_plane_svd: needs at least 3 points");
  const Eigen::RowVector3d centroid = points.colwise().mean();
  // The smallest right singular vector of the centred points is the eigenvector of their 3x3
  // scatter matrix with the smallest eigenvalue: the same plane, without an SVD of an N x 3
  // matrix (a LiDAR ground of 40k points took milliseconds per refit).
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Vec3 d = (points.row(i) - centroid).transpose();
    scatter.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);  // eigenvalues ascending
  const Vec3 n = eig.eigenvectors().col(0).normalized();
  return oriented(n, -n.dot(centroid.transpose()));
}

PlaneFit fit_plane_ransac(const Points3& points, const PlaneFitOptions& options) {
  const Eigen::Index n = points.rows();
  if (n < 3) throw std::invalid_argument("fit_plane_ransac: needs at least 3 points, got " +
                                         std::to_string(n));
  if (!points.allFinite()) throw std::invalid_argument("fit_plane_ransac: points contain NaN/inf");
  if (!(options.inlier_threshold > 0) || options.iterations < 1)
    throw std::invalid_argument("fit_plane_ransac: inlier_threshold must be > 0, iterations >= 1");

  // hypotheses are scored on an evenly strided subset of at most max_scored_points points
  // (the refits below use all of them)
  const Eigen::Index stride =
      options.max_scored_points > 0 ? std::max<Eigen::Index>(1, (n + options.max_scored_points - 1) / options.max_scored_points) : 1;
  Points3 strided;
  if (stride > 1) {
    strided.resize((n + stride - 1) / stride, 3);
    for (Eigen::Index i = 0, k = 0; i < n; i += stride, ++k) strided.row(k) = points.row(i);
  }
  const Points3& scored = stride > 1 ? strided : points;
  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<Eigen::Index> pick(0, scored.rows() - 1);
  Vec4 best = Vec4::Zero();
  int best_count = -1;
  for (int it = 0; it < options.iterations; ++it) {
    const Vec3 a = scored.row(pick(rng)), b = scored.row(pick(rng)), c = scored.row(pick(rng));
    const Vec3 normal = (b - a).cross(c - a);
    const double len = normal.norm();
    if (len < 1e-12) continue;  // collinear or repeated sample
    const Vec3 u = normal / len;
    const Vec4 candidate = oriented(u, -u.dot(a));
    const int count = count_inliers_above(scored, candidate, options.inlier_threshold, best_count);
    if (count > best_count) {
      best_count = count;
      best = candidate;
    }
  }
  if (best_count < 3) throw std::invalid_argument("fit_plane_ransac: points are degenerate "
                                                  "(all collinear)");
  PlaneFit fit;
  fit.inliers.assign(n, 0);
  fit.plane = best;
  // Two refits: the least-squares plane can gain inliers the sampled plane missed.
  for (int round = 0; round < 2; ++round) {
    const int count = mark_inliers(points, fit.plane, options.inlier_threshold, &fit.inliers);
    if (count < 3) break;
    fit.plane = fit_plane_svd(gather(points, fit.inliers, count));
  }
  fit.num_inliers = mark_inliers(points, fit.plane, options.inlier_threshold, &fit.inliers);
  const Points3 in = gather(points, fit.inliers, fit.num_inliers);
  double sum_sq = 0;
  for (Eigen::Index i = 0; i < in.rows(); ++i) sum_sq += std::pow(plane_distance(in, i, fit.plane), 2);
  fit.rms = fit.num_inliers > 0 ? std::sqrt(sum_sq / fit.num_inliers) : 0.0;
  return fit;
}

}  // namespace twistslam::geometry
