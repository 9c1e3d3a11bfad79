#include "detection/surface_roughness.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include "registration/kdtree.hpp"

namespace twistslam::detection {

namespace {

// Returns whose neighbourhood is evaluated, at most (see surface_roughness).
constexpr std::size_t kMaxSamples = 128;

// The returns kept by a voxel thinning: the first of each voxel_m cube (by member order).
std::vector<Vec3> thin(const std::vector<int>& members, const std::vector<ScenePoint>& pts,
                       double voxel_m) {
  // 21 bits per axis: +-1e6 voxels, +-100 km at 0.1 m (the scene is cut at max_range_m)
  constexpr std::int64_t kOffset = 1 << 20;
  auto cell = [&](float v) { return static_cast<std::int64_t>(std::floor(v / voxel_m)) + kOffset; };
  std::vector<std::pair<std::int64_t, int>> keyed;
  keyed.reserve(members.size());
  for (std::size_t m = 0; m < members.size(); ++m) {
    const ScenePoint& p = pts[members[m]];
    keyed.emplace_back((cell(p.x) << 42) | (cell(p.up) << 21) | cell(p.z), static_cast<int>(m));
  }
  std::sort(keyed.begin(), keyed.end());  // by voxel, then member order
  std::vector<Vec3> kept;
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    if (i > 0 && keyed[i].first == keyed[i - 1].first) continue;
    const ScenePoint& p = pts[members[keyed[i].second]];
    kept.emplace_back(p.x, p.up, p.z);
  }
  return kept;
}

}  // namespace

SurfaceRoughness surface_roughness(const std::vector<int>& members,
                                   const std::vector<ScenePoint>& pts, double voxel_m,
                                   int num_neighbors) {
  if (!(voxel_m > 0) || num_neighbors < 3)
    throw std::invalid_argument("surface_roughness: need voxel_m > 0 and num_neighbors >= 3");
  SurfaceRoughness out;
  const std::vector<Vec3> points = thin(members, pts, voxel_m);
  out.num_points = static_cast<int>(points.size());
  if (out.num_points <= num_neighbors) return out;
  const registration::KdTree tree(points);
  // at most kMaxSamples returns evenly spread through the thinned ones are evaluated (their
  // neighbours come from all of them): a median of 128 is as good as of thousands, and a
  // near car's thousand thinned returns cost ~1 ms each evaluated
  const std::size_t stride = (points.size() + kMaxSamples - 1) / kMaxSamples;
  std::vector<double> variation;
  variation.reserve(kMaxSamples);
  std::vector<registration::Neighbor> nb;
  Eigen::SelfAdjointEigenSolver<Mat3> solver;
  for (std::size_t i = 0; i < points.size(); i += stride) {
    tree.knn(points[i], num_neighbors, &nb);
    Vec3 mean = Vec3::Zero();
    for (const registration::Neighbor& n : nb) mean += points[n.index];
    mean /= static_cast<double>(nb.size());
    Mat3 C = Mat3::Zero();
    for (const registration::Neighbor& n : nb) {
      const Vec3 d = points[n.index] - mean;
      C.noalias() += d * d.transpose();
    }
    solver.computeDirect(C, Eigen::EigenvaluesOnly);
    const Vec3 ev = solver.eigenvalues().cwiseMax(0.0);  // ascending; rounding may dip below 0
    const double sum = ev.sum();
    variation.push_back(sum > 0 ? ev[0] / sum : 0.0);
  }
  const auto mid = variation.begin() + static_cast<std::ptrdiff_t>(variation.size() / 2);
  std::nth_element(variation.begin(), mid, variation.end());
  out.median_variation = *mid;
  return out;
}

}  // namespace twistslam::detection
