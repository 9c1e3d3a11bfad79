#pragma once
// Every point's k nearest neighbours within one small scan (an object scan: a few hundred to a
// few thousand points), through a dense voxel grid instead of one KD-tree descent per point.
// The points are visited in the KD-tree's leaf order (consecutive points close together); the
// previous point p's k-th distance r bounds the current point q's by r + |q - p| (triangle
// inequality), so the cells within that reach of q hold its k nearest: their distances are
// computed in one flat, branch-free float loop and the k smallest selected (nth_element). A
// tighter first reach (1.2 r) is tried first and widened when it holds fewer than k points.
// Exact: the KD-tree's k-NN up to ties closer than ~1e-6 m (float coordinates relative to the
// grid's corner).
#include <vector>

#include "geometry/types.hpp"
#include "registration/kdtree.hpp"
#include "registration/point_grid.hpp"

namespace twistslam::registration {

// Each point's neighbours (itself included): their indices, in no particular order, at
// [i * size, (i + 1) * size) of `indices`, and the squared distance to the farthest of them in
// `radius2_m2` (computed in double from the points).
struct Neighborhoods {
  int size = 0;                    // neighbours per point
  std::vector<int> indices;        // points.size() * size
  std::vector<double> radius2_m2;  // points.size()
};

// The candidate-distance loop's instruction set: the widest this CPU runs (AVX-512 when it has
// it, checked once at run time; else SSE2, which every x86-64 has), or SSE2 / plain C++ (tests
// compare the two). Both give the same neighbours: the distances are computed the same way.
enum class KnnKernel { kWidest, kPortable };

// What the grid did (for tests and profiling).
struct GridKnnStats {
  double cell_size_m = 0.0;
  int num_cells = 0;
  int num_reach_retries = 0;  // searches repeated with a wider reach
  bool avx512 = false;        // the AVX-512 kernel ran
};

// Fills `out` with the k nearest neighbours of every point of `points` (finite; k <=
// points.size()); `tree` was built from `points` (its leaf order and a few queries that size
// the cells). With `grid`, the grid is handed over there. Throws std::invalid_argument unless
// 1 <= k <= points.size() == tree.size().
void all_knn(const std::vector<Vec3>& points, const KdTree& tree, int k, Neighborhoods* out,
             GridKnnStats* stats = nullptr, PointGrid* grid = nullptr,
             KnnKernel kernel = KnnKernel::kWidest);

// Sampled points per scan whose KD-tree k-th distance sets the grid's cell size (16 queries:
// ~5 % of the k-NN time of a 400-point scan).
inline constexpr int kCellSizeSamples = 16;

}  // namespace twistslam::registration
