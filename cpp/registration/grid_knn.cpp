#include "registration/grid_knn.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace twistslam::registration {

namespace {

// Cell edge = this times the kCellSizeQuantile quantile of the sampled points' k-th neighbour
// distance. Only speed depends on it (every cell within the reach is searched): 0.5-1.5 timed
// within 10 % on the bench's real and simulated car scans (k = 20), 1.0 among the fastest.
constexpr double kCellSizePerRadius = 1.0;
constexpr double kCellSizeQuantile = 0.75;
// Relative slack on the triangle-inequality reach (float rounding of r + |q - p|).
constexpr float kReachSlack = 1.0001f;
// Float coordinates (relative to the grid corner, a few m) are good to ~1e-6 m: the searched
// cells cover the reach plus this margin, so no point within the reach is missed by rounding.
constexpr float kCoverMarginM = 1e-4f;
// First try: the previous point's k-th distance times this (when below the guaranteed reach).
// 1.2 held k points for 87-91 % of the points of the bench's scans (retry: the guaranteed
// reach); 1.1 and 1.4 timed the same within 10 % (more retries vs more candidates ranked).
constexpr float kFirstReachPerRadius = 1.2f;
// A reach holding fewer than k points beyond the guaranteed one (only the first point, or
// coincident points) grows by this.
constexpr float kReachGrowth = 1.5f;
// A last missing member (or a last extra one) after a partition is moved by a branch-free
// minimum (maximum) scan rather than partitioning again. At most 1 such scan per point timed
// fastest on the bench's car scans (scan build 0.374 / 0.389 / 0.399 / 0.440 ms with 1 / 2 /
// 4 / 8, simulated median): the partitions are cheap. >= 1 keeps both sides of a median-of-
// three partition non-empty (at least 4 keys left to split).
constexpr int kMaxOneByOne = 1;
static_assert(kMaxOneByOne >= 1, "a median-of-three pivot needs at least 3 keys");

// Moves the k smallest of keys[0, n) to keys[0, k) (in no particular order); keys are
// distinct. std::nth_element branches on every comparison, and on ~40 unordered candidates
// those branches mispredict about half the time (a third of the k-NN time in perf): here the
// partitions are branch-free (Lomuto with an unconditional swap), the first one around
// `guess` (an estimate of the k-th key), later ones around a median of three; a last missing
// or extra member is placed by a branch-free min / max scan.
void select_smallest(std::uint64_t* keys, int n, int k, std::uint64_t guess) {
  int begin = 0, end = n;  // keys[0, begin) are members, keys[end, n) are not
  bool first = true;
  for (;;) {
    const int need = k - begin, size = end - begin;
    if (need == 0 || need == size) return;
    if (need <= kMaxOneByOne) {
      for (; begin < k; ++begin) {  // the smallest remaining to the front, need times
        int best = begin;
        for (int j = begin + 1; j < end; ++j) best = keys[j] < keys[best] ? j : best;
        std::swap(keys[begin], keys[best]);
      }
      return;
    }
    if (size - need <= kMaxOneByOne) {
      for (; end > k; --end) {  // the largest remaining to the back
        int worst = begin;
        for (int j = begin + 1; j < end; ++j) worst = keys[j] > keys[worst] ? j : worst;
        std::swap(keys[end - 1], keys[worst]);
      }
      return;
    }
    std::uint64_t pivot = guess;
    if (!first) {  // median of three: neither the minimum nor the maximum, so both sides shrink
      const std::uint64_t a = keys[begin], b = keys[begin + size / 2], c = keys[end - 1];
      pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
    }
    first = false;
    int split = begin;  // keys[begin, split) <= pivot < keys[split, j)
    for (int j = begin; j < end; ++j) {
      const std::uint64_t x = keys[j];
      keys[j] = keys[split];
      keys[split] = x;
      split += x <= pivot;
    }
    if (split - begin >= need)
      end = split;
    else
      begin = split;
  }
}

// One row of grid cells: the candidates sorted[j, end) at float coordinates (xs, ys, zs), each
// written as a key (float bits of d2) << 32 | index at keys[kept, ...) and counted when d2 <=
// limit (a candidate outside overwrites the next slot). Returns the new count. keys needs
// kRowKeysPadding slots beyond the last candidate (the wide kernels store whole registers).
struct RowQuery {
  float qx, qy, qz, limit;
};
using RowKeysFn = int (*)(const float* xs, const float* ys, const float* zs, const int* sorted,
                          int j, int end, const RowQuery& q, std::uint64_t* keys, int kept);
constexpr int kRowKeysPadding = 16;

// The candidates left over by a wide kernel, one by one.
inline int row_keys_scalar(const float* xs, const float* ys, const float* zs, const int* sorted,
                           int j, int end, const RowQuery& q, std::uint64_t* keys, int kept) {
  for (; j < end; ++j) {
    const float dx = xs[j] - q.qx, dy = ys[j] - q.qy, dz = zs[j] - q.qz;
    const float d2 = dx * dx + dy * dy + dz * dz;
    std::uint32_t bits;
    std::memcpy(&bits, &d2, sizeof bits);
    keys[kept] = (std::uint64_t{bits} << 32) | static_cast<std::uint32_t>(sorted[j]);
    kept += d2 <= q.limit;  // branch-free: the comparison is unpredictable
  }
  return kept;
}

// Four candidates at a time (SSE2, in every x86-64).
int row_keys_sse2(const float* xs, const float* ys, const float* zs, const int* sorted, int j,
                  int end, const RowQuery& q, std::uint64_t* keys, int kept) {
#if defined(__SSE2__)
  const __m128 limit4 = _mm_set1_ps(q.limit), qx4 = _mm_set1_ps(q.qx), qy4 = _mm_set1_ps(q.qy),
               qz4 = _mm_set1_ps(q.qz);
  for (; j + 4 <= end; j += 4) {
    const __m128 dx = _mm_sub_ps(_mm_loadu_ps(xs + j), qx4);
    const __m128 dy = _mm_sub_ps(_mm_loadu_ps(ys + j), qy4);
    const __m128 dz = _mm_sub_ps(_mm_loadu_ps(zs + j), qz4);
    const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)),
                                 _mm_mul_ps(dz, dz));
    const int inside = _mm_movemask_ps(_mm_cmple_ps(d2, limit4));
    alignas(16) std::uint32_t bits[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(bits), _mm_castps_si128(d2));
    for (int l = 0; l < 4; ++l) {
      keys[kept] = (std::uint64_t{bits[l]} << 32) | static_cast<std::uint32_t>(sorted[j + l]);
      kept += (inside >> l) & 1;
    }
  }
#endif
  return row_keys_scalar(xs, ys, zs, sorted, j, end, q, keys, kept);
}

#if defined(__x86_64__) && defined(__GNUC__)
// GCC 12's AVX-512 headers pass an undefined register as the unused merge source of unmasked
// intrinsics, which -Wmaybe-uninitialized reports at every use.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Sixteen at a time with AVX-512 (chosen at run time, cpu_has_avx512): the keys of the
// candidates inside are packed into consecutive slots by a register compress (a compress
// straight to memory is slow on some CPUs), 8 keys per store. A row's last step is masked
// (a row of a small scan's grid holds ~5-10 candidates: mostly that step alone): its
// masked-off lanes load nothing (and cannot fault) and count as outside.
__attribute__((target("avx512f"))) int row_keys_avx512(const float* xs, const float* ys,
                                                        const float* zs, const int* sorted,
                                                        int j, int end, const RowQuery& q,
                                                        std::uint64_t* keys, int kept) {
  const __m512 limit16 = _mm512_set1_ps(q.limit), qx16 = _mm512_set1_ps(q.qx),
               qy16 = _mm512_set1_ps(q.qy), qz16 = _mm512_set1_ps(q.qz);
  for (; j < end; j += 16) {
    const __mmask16 lanes = end - j >= 16 ? static_cast<__mmask16>(0xFFFF)
                                          : static_cast<__mmask16>((1u << (end - j)) - 1u);
    const __m512 dx = _mm512_sub_ps(_mm512_maskz_loadu_ps(lanes, xs + j), qx16);
    const __m512 dy = _mm512_sub_ps(_mm512_maskz_loadu_ps(lanes, ys + j), qy16);
    const __m512 dz = _mm512_sub_ps(_mm512_maskz_loadu_ps(lanes, zs + j), qz16);
    const __m512 d2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)),
                                    _mm512_mul_ps(dz, dz));
    const __mmask16 inside = _mm512_mask_cmp_ps_mask(lanes, d2, limit16, _CMP_LE_OQ);
    const __m512i bits = _mm512_castps_si512(d2);
    const __m512i index = _mm512_maskz_loadu_epi32(lanes, sorted + j);
    const __m512i key_lo = _mm512_or_si512(
        _mm512_slli_epi64(_mm512_cvtepu32_epi64(_mm512_castsi512_si256(bits)), 32),
        _mm512_cvtepu32_epi64(_mm512_castsi512_si256(index)));
    const __m512i key_hi = _mm512_or_si512(
        _mm512_slli_epi64(_mm512_cvtepu32_epi64(_mm512_extracti64x4_epi64(bits, 1)), 32),
        _mm512_cvtepu32_epi64(_mm512_extracti64x4_epi64(index, 1)));
    const __mmask8 in_lo = static_cast<__mmask8>(inside), in_hi = static_cast<__mmask8>(inside >> 8);
    _mm512_storeu_si512(keys + kept, _mm512_maskz_compress_epi64(in_lo, key_lo));
    kept += __builtin_popcount(in_lo);
    _mm512_storeu_si512(keys + kept, _mm512_maskz_compress_epi64(in_hi, key_hi));
    kept += __builtin_popcount(in_hi);
  }
  return kept;
}
#pragma GCC diagnostic pop
#endif

// True when this CPU runs AVX-512 (checked once).
bool cpu_has_avx512() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool has = __builtin_cpu_supports("avx512f");
  return has;
#else
  return false;
#endif
}

}  // namespace

void all_knn(const std::vector<Vec3>& points, const KdTree& tree, int k, Neighborhoods* out,
             GridKnnStats* stats, PointGrid* grid_out, KnnKernel kernel) {
  const int n = static_cast<int>(points.size());
  if (k < 1 || k > n || tree.size() != n)
    throw std::invalid_argument("all_knn: need 1 <= k <= points.size() == tree.size()");
  out->size = k;
  out->indices.resize(static_cast<std::size_t>(n) * k);
  out->radius2_m2.resize(n);

  // Cell size from a few KD-tree queries (spread over the scan).
  std::vector<Neighbor> neighbors;
  std::vector<double> sampled_r2;
  const int step = std::max(1, n / kCellSizeSamples);
  for (int i = 0; i < n; i += step) {
    tree.knn(points[i], k, &neighbors);
    sampled_r2.push_back(neighbors.back().squared_distance_m2);
  }
  auto quantile = sampled_r2.begin() + static_cast<std::ptrdiff_t>(
                                           kCellSizeQuantile * (sampled_r2.size() - 1));
  std::nth_element(sampled_r2.begin(), quantile, sampled_r2.end());
  // Coincident points (radius 0) still need a positive cell (1 mm: below any LiDAR spacing).
  PointGrid grid = make_point_grid(points, std::max(kCellSizePerRadius * std::sqrt(*quantile), 1e-3));
  const double cell = grid.cell_m;
  const float cell_f = static_cast<float>(cell);
  const int* dims = grid.dims;
  const int nx = dims[0], nxy = dims[0] * dims[1];
  const int num_cells = grid.num_cells();
  const std::vector<int>& start = grid.start;
  const std::vector<int>& sorted = grid.index;
  // float coordinates relative to the grid's corner
  std::vector<float> xs(n), ys(n), zs(n);
  for (int s = 0; s < n; ++s) {
    xs[s] = static_cast<float>(grid.points[s][0] - grid.origin[0]);
    ys[s] = static_cast<float>(grid.points[s][1] - grid.origin[1]);
    zs[s] = static_cast<float>(grid.points[s][2] - grid.origin[2]);
  }
  const Vec3& origin = grid.origin;
  // every point lies within the grid's box, so within its diagonal of any point
  const float whole_grid_reach = static_cast<float>(
      cell * std::sqrt(static_cast<double>(dims[0]) * dims[0] + static_cast<double>(dims[1]) * dims[1] +
                       static_cast<double>(dims[2]) * dims[2])) + cell_f;

  // (float bits of d2) << 32 | index: positive floats order like their bits, so one integer
  // comparison ranks by distance (ties by index) in nth_element.
  std::vector<std::uint64_t> keys(n + kRowKeysPadding);
  // AVX-512: scan builds 5-6 % faster on the bench's car scans (the same neighbours)
  const bool avx512 = kernel == KnnKernel::kWidest && cpu_has_avx512();
  RowKeysFn row_keys = row_keys_sse2;
#if defined(__x86_64__) && defined(__GNUC__)
  if (avx512) row_keys = row_keys_avx512;
#endif
  int retries = 0;
  // Points in the KD-tree's leaf order, so consecutive points are close: the previous point's
  // k-th distance r and position p bound q's, r + |q - p| (p's k neighbours are that close to
  // q), so every cell within that reach of q holds at least k candidates.
  float reach = static_cast<float>(cell);  // first point: a guess, grown when too short
  float previous_r = -1.0f;
  float px = 0.0f, py = 0.0f, pz = 0.0f;
  for (const int i : tree.leaf_order()) {
    const float qx = static_cast<float>(points[i][0] - origin[0]);
    const float qy = static_cast<float>(points[i][1] - origin[1]);
    const float qz = static_cast<float>(points[i][2] - origin[2]);
    // Guaranteed reach (triangle inequality) and a tighter first try.
    float sure_reach = 0.0f;
    if (previous_r >= 0.0f) {
      sure_reach = (previous_r + std::sqrt((qx - px) * (qx - px) + (qy - py) * (qy - py) +
                                           (qz - pz) * (qz - pz))) * kReachSlack;
      reach = std::min(sure_reach, previous_r * kFirstReachPerRadius);
    }
    int kept = 0;
    for (;;) {
      const RowQuery query{qx, qy, qz, reach * reach};
      const float span = reach + kCoverMarginM;
      int lo_cell[3], hi_cell[3];
      const float q[3] = {qx, qy, qz};
      for (int a = 0; a < 3; ++a) {
        lo_cell[a] = std::max(0, static_cast<int>((q[a] - span) / cell_f));
        hi_cell[a] = std::min(dims[a] - 1, static_cast<int>((q[a] + span) / cell_f));
      }
      kept = 0;
      for (int z = lo_cell[2]; z <= hi_cell[2]; ++z)
        for (int y = lo_cell[1]; y <= hi_cell[1]; ++y) {
          const int row = y * nx + z * nxy;
          kept = row_keys(xs.data(), ys.data(), zs.data(), sorted.data(),
                          start[row + lo_cell[0]], start[row + hi_cell[0] + 1], query,
                          keys.data(), kept);
        }
      if (kept >= k) break;
      // A reach past the grid's diagonal holds every point (k <= n): a kernel that still
      // counts fewer than k is broken, and growing on would never end.
      if (reach > whole_grid_reach)
        throw std::logic_error("all_knn: a reach over the whole grid kept fewer than k points");
      reach = reach < sure_reach ? sure_reach : std::max(reach * kReachGrowth, cell_f);
      ++retries;
    }
    if (kept > k) {
      // The first pivot: this point's k-th distance is about the previous point's.
      const float guess_d2 = previous_r >= 0.0f ? previous_r * previous_r : reach * reach;
      std::uint32_t guess_bits;
      std::memcpy(&guess_bits, &guess_d2, sizeof guess_bits);
      select_smallest(keys.data(), kept, k, (std::uint64_t{guess_bits} << 32) | 0xffffffffu);
    }
    int* dst = out->indices.data() + static_cast<std::size_t>(i) * k;
    double r2 = 0.0;
    for (int j = 0; j < k; ++j) {
      dst[j] = static_cast<int>(keys[j] & 0xffffffffu);
      r2 = std::max(r2, (points[dst[j]] - points[i]).squaredNorm());
    }
    out->radius2_m2[i] = r2;
    previous_r = static_cast<float>(std::sqrt(r2));
    px = qx, py = qy, pz = qz;
  }
  if (stats != nullptr) *stats = GridKnnStats{cell, num_cells, retries, avx512};
  if (grid_out != nullptr) *grid_out = std::move(grid);
}

}  // namespace twistslam::registration
