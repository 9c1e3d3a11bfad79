#include "lidar/disparity_offset.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace twistslam::lidar {

namespace {

double median_in_place(std::vector<double>& values) {
  const std::size_t n = values.size(), mid = n / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  const double upper = values[mid];
  if (n % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + mid));
}

}  // namespace

DisparityOffset estimate_disparity_offset(const std::vector<double>& disparities_px,
                                          const std::vector<double>& lidar_depths_m,
                                          double fx_baseline,
                                          const DisparityOffsetOptions& options) {
  if (disparities_px.size() != lidar_depths_m.size())
    throw std::invalid_argument("estimate_disparity_offset: " +
                                std::to_string(disparities_px.size()) + " disparities but " +
                                std::to_string(lidar_depths_m.size()) + " LiDAR depths");
  if (!(std::isfinite(fx_baseline) && fx_baseline > 0))
    throw std::invalid_argument("estimate_disparity_offset: fx_baseline = " +
                                std::to_string(fx_baseline) + " must be finite and > 0");
  if (options.min_samples < 1)
    throw std::invalid_argument("DisparityOffsetOptions.min_samples must be >= 1");
  if (!(std::isfinite(options.max_abs_residual_px) && options.max_abs_residual_px > 0))
    throw std::invalid_argument("DisparityOffsetOptions.max_abs_residual_px must be finite and > 0");

  std::vector<double> residuals;
  residuals.reserve(disparities_px.size());
  for (std::size_t i = 0; i < disparities_px.size(); ++i) {
    const double d = disparities_px[i], z = lidar_depths_m[i];
    if (!(std::isfinite(d) && std::isfinite(z) && d > 0 && z > 0)) continue;
    const double r = fx_baseline / z - d;
    if (std::abs(r) <= options.max_abs_residual_px) residuals.push_back(r);
  }
  DisparityOffset out;
  out.num_samples = static_cast<int>(residuals.size());
  if (out.num_samples < options.min_samples) return out;
  const double offset = median_in_place(residuals);
  for (double& r : residuals) r = std::abs(r - offset);
  out.valid = true;
  out.offset_px = offset;
  out.mad_px = median_in_place(residuals);
  return out;
}

}  // namespace twistslam::lidar
