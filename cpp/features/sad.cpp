#include "features/sad.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

// The cost loops over the disparities vectorise; GCC builds them for baseline x86-64 (SSE2,
// 4 floats) and AVX2 (8), and the loader picks the widest this CPU runs. Every disparity's sum
// keeps its order (no FMA: avx2 alone does not enable it), so both give the same costs.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define TWISTSLAM_SAD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define TWISTSLAM_SAD_CLONES
#endif

namespace twistslam::features {

namespace {

constexpr int kMaxWindowPixels = (2 * kMaxSadHalfWidth + 1) * (2 * kMaxSadHalfHeight + 1);

// The left window's supported pixels as (row, column) offsets.
struct SupportPixels {
  std::array<std::uint8_t, kMaxWindowPixels> row, col;
  int count = 0;
};

SupportPixels support_pixels(int rows, int cols, const std::uint8_t* support) {
  SupportPixels s;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      if (support[r * cols + c]) {
        s.row[s.count] = static_cast<std::uint8_t>(r);
        s.col[s.count] = static_cast<std::uint8_t>(c);
        ++s.count;
      }
  return s;
}

// The left window around (xl, y) into `left` (rows x cols floats), minus the mean of its
// supported pixels; returns their contrast (sum of absolute deviations).
float supported_left(const cv::Mat& L, int xl, int y, int half_width, int half_height,
                     const SupportPixels& used, float* left) {
  const int cols = 2 * half_width + 1, rows = 2 * half_height + 1;
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* p = L.ptr<std::uint8_t>(y - half_height + r) + xl - half_width;
    for (int c = 0; c < cols; ++c) left[r * cols + c] = p[c];
  }
  float sum = 0;
  for (int k = 0; k < used.count; ++k) sum += left[used.row[k] * cols + used.col[k]];
  const float mean = sum / static_cast<float>(used.count);
  float contrast = 0;
  for (int k = 0; k < rows * cols; ++k) left[k] -= mean;
  for (int k = 0; k < used.count; ++k) contrast += std::abs(left[used.row[k] * cols + used.col[k]]);
  return contrast;
}

// Zero-mean SAD over the supported pixels of the left window (`left`, its mean removed) against
// the right band (rows of `span` floats) at every offset d in [0, num): cost[d]. Two passes
// over the pixels, each a contiguous loop over d: the right windows' means over the same
// pixels, then the absolute differences.
TWISTSLAM_SAD_CLONES void supported_costs(const float* left, const SupportPixels& used, int cols,
                                          const float* band, int span, int num, float* cost) {
  if (num <= 0) return;
  thread_local std::vector<float> mean_right;
  mean_right.assign(num, 0.0f);
  for (int k = 0; k < used.count; ++k) {
    const float* b = band + static_cast<size_t>(used.row[k]) * span + used.col[k];
    for (int d = 0; d < num; ++d) mean_right[d] += b[d];
  }
  const float inv = 1.0f / static_cast<float>(used.count);
  for (int d = 0; d < num; ++d) mean_right[d] *= inv;
  std::fill(cost, cost + num, 0.0f);
  for (int k = 0; k < used.count; ++k) {
    const float l = left[used.row[k] * cols + used.col[k]];
    const float* b = band + static_cast<size_t>(used.row[k]) * span + used.col[k];
    for (int d = 0; d < num; ++d) cost[d] += std::abs(l - (b[d] - mean_right[d]));
  }
}

}  // namespace

float vertex_offset(float cm, float c0, float cp) {
  const float rise = std::max(cm, cp) - c0;
  if (!(rise > 0)) return 0.0f;
  return 0.5f * (cm - cp) / rise;
}

SadRefined refine_sad(const cv::Mat& L, const cv::Mat& R, int xl, int y, int xr0, float dy,
                      int half_width, int half_height, int range, const std::uint8_t* support) {
  SadRefined out;
  const int cols = 2 * half_width + 1, rows = 2 * half_height + 1, n = cols * rows;
  const int span = 2 * range + cols, x_begin = xr0 - range - half_width;
  const float yr = static_cast<float>(y - half_height) + dy;
  const int y0 = static_cast<int>(std::floor(yr));
  const float a = yr - static_cast<float>(y0);
  if (y - half_height < 0 || y + half_height >= L.rows || xl - half_width < 0 ||
      xl + half_width >= L.cols || x_begin < 0 || x_begin + span > R.cols || y0 < 0 ||
      y0 + rows >= R.rows)
    return out;

  std::array<float, kMaxWindowPixels> left;
  // Right band, rows interpolated at the predicted offset; column sums give window means.
  std::array<float, (2 * kMaxSadRange + 2 * kMaxSadHalfWidth + 1) * (2 * kMaxSadHalfHeight + 1)> band;
  std::array<float, 2 * kMaxSadRange + 2 * kMaxSadHalfWidth + 1> column{};
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* p0 = R.ptr<std::uint8_t>(y0 + r) + x_begin;
    const std::uint8_t* p1 = R.ptr<std::uint8_t>(y0 + r + 1) + x_begin;
    float* b = band.data() + r * span;
    for (int c = 0; c < span; ++c) {
      b[c] = (1.0f - a) * p0[c] + a * p1[c];
      column[c] += b[c];
    }
  }
  std::array<float, 2 * kMaxSadRange + 1> cost;
  float contrast = 0;
  int best = 0;
  if (support != nullptr) {
    const SupportPixels used = support_pixels(rows, cols, support);
    if (used.count == 0) return out;
    contrast = supported_left(L, xl, y, half_width, half_height, used, left.data());
    supported_costs(left.data(), used, cols, band.data(), span, 2 * range + 1, cost.data());
    for (int d = 1; d <= 2 * range; ++d)
      if (cost[d] < cost[best]) best = d;
  } else {
    float sum_left = 0;
    for (int r = 0; r < rows; ++r) {
      const std::uint8_t* p = L.ptr<std::uint8_t>(y - half_height + r) + xl - half_width;
      for (int c = 0; c < cols; ++c) {
        left[r * cols + c] = p[c];
        sum_left += p[c];
      }
    }
    const float mean_left = sum_left / n;
    for (int k = 0; k < n; ++k) {
      left[k] -= mean_left;
      contrast += std::abs(left[k]);
    }
    for (int d = 0; d <= 2 * range; ++d) {
      float sum_right = 0;
      for (int c = 0; c < cols; ++c) sum_right += column[d + c];
      const float mean_right = sum_right / n;
      float sad = 0;
      for (int r = 0; r < rows; ++r) {
        const float* b = band.data() + r * span + d;
        const float* l = left.data() + r * cols;
        for (int c = 0; c < cols; ++c) sad += std::abs(l[c] - (b[c] - mean_right));
      }
      cost[d] = sad;
      if (sad < cost[best]) best = d;
    }
  }
  if (best == 0 || best == 2 * range) return out;  // minimum on the border: no true minimum
  const float delta = vertex_offset(cost[best - 1], cost[best], cost[best + 1]);
  out.u_level = static_cast<float>(x_begin + half_width + best) + delta;
  out.cost = cost[best] / (contrast + 1.0f);
  out.ok = true;
  return out;
}

TWISTSLAM_SAD_CLONES SadScan scan_sad(const cv::Mat& L, const cv::Mat& R, int xl, int y,
                                      int x_first, int x_last, int half_width, int half_height,
                                      const std::uint8_t* support) {
  SadScan out;
  out.second_cost = std::numeric_limits<float>::infinity();
  const int cols = 2 * half_width + 1, rows = 2 * half_height + 1, n = cols * rows;
  if (y - half_height < 0 || y + half_height >= L.rows || y + half_height >= R.rows ||
      xl - half_width < 0 || xl + half_width >= L.cols)
    return out;
  x_first = std::max(x_first, half_width);
  x_last = std::min(x_last, R.cols - 1 - half_width);
  if (x_first > x_last) return out;

  // The right band as floats once, and each window's mean from the column sums. The cost
  // then accumulates one left pixel at a time over every disparity: a contiguous loop over
  // the band that the compiler vectorises (the scan is the stereo search's hot spot), with
  // each disparity's terms summed in the same order as a window-by-window loop would.
  const int x_begin = x_first - half_width, span = x_last - x_first + cols;
  const int num_columns = x_last - x_first + 1;
  thread_local std::vector<float> band, column, mean_right, cost;
  band.resize(static_cast<size_t>(rows) * span);
  column.assign(span, 0.0f);
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* p = R.ptr<std::uint8_t>(y - half_height + r) + x_begin;
    float* b = band.data() + static_cast<size_t>(r) * span;
    for (int c = 0; c < span; ++c) column[c] += b[c] = p[c];
  }
  std::array<float, kMaxWindowPixels> left;
  float contrast = 0;
  cost.assign(num_columns, 0.0f);
  if (support != nullptr) {
    const SupportPixels used = support_pixels(rows, cols, support);
    if (used.count == 0) return out;
    contrast = supported_left(L, xl, y, half_width, half_height, used, left.data());
    supported_costs(left.data(), used, cols, band.data(), span, num_columns, cost.data());
  } else {
    float sum_left = 0;
    for (int r = 0; r < rows; ++r) {
      const std::uint8_t* p = L.ptr<std::uint8_t>(y - half_height + r) + xl - half_width;
      for (int c = 0; c < cols; ++c) sum_left += left[r * cols + c] = p[c];
    }
    const float mean_left = sum_left / n;
    for (int k = 0; k < n; ++k) contrast += std::abs(left[k] -= mean_left);
    mean_right.resize(num_columns);
    for (int d = 0; d < num_columns; ++d) {
      float sum_right = 0;
      for (int c = 0; c < cols; ++c) sum_right += column[d + c];
      mean_right[d] = sum_right / n;
    }
    float* __restrict const cost_d = cost.data();
    const float* __restrict const mean_d = mean_right.data();
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const float l = left[r * cols + c];
        const float* b = band.data() + static_cast<size_t>(r) * span + c;
        for (int d = 0; d < num_columns; ++d) cost_d[d] += std::abs(l - (b[d] - mean_d[d]));
      }
    }
  }
  int best = 0;
  for (int d = 1; d < num_columns; ++d)
    if (cost[d] < cost[best]) best = d;
  // the second-best local minimum: the best one's own valley (its slopes) is no competitor
  float second = std::numeric_limits<float>::infinity();
  const int m = static_cast<int>(cost.size());
  for (int d = 0; d < m; ++d) {
    if (std::abs(d - best) < 2) continue;
    const bool minimum = (d == 0 || cost[d] <= cost[d - 1]) && (d == m - 1 || cost[d] <= cost[d + 1]);
    if (minimum) second = std::min(second, cost[d]);
  }
  const float norm = contrast + 1.0f;
  out.best_column = x_first + best;
  out.best_cost = cost[best] / norm;
  out.second_cost = second / norm;
  return out;
}

}  // namespace twistslam::features
