#include "lidar/lidar_depth_options.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace twistslam::lidar {

namespace {

void require(bool ok, const char* name, double value, const char* rule) {
  if (!ok)
    throw std::invalid_argument(std::string("LidarDepthOptions.") + name + " = " +
                                std::to_string(value) + ": must be " + rule);
}

}  // namespace

void validate(const LidarDepthOptions& o) {
  // Upper bounds keep the bucket grid and the per-keypoint search from exploding (a radius
  // of 1e30 px would visit every bucket for every keypoint).
  require(std::isfinite(o.cell_size_px) && o.cell_size_px >= 1 && o.cell_size_px <= 1024,
          "cell_size_px", o.cell_size_px, "in [1, 1024]");
  require(std::isfinite(o.search_radius_px) && o.search_radius_px > 0 && o.search_radius_px <= 64,
          "search_radius_px", o.search_radius_px, "in (0, 64]");
  require(std::isfinite(o.min_depth_m) && o.min_depth_m > 0, "min_depth_m", o.min_depth_m, "> 0");
  require(std::isfinite(o.max_depth_m) && o.max_depth_m > o.min_depth_m, "max_depth_m",
          o.max_depth_m, "finite and > min_depth_m");
  require(o.min_returns >= 3 && o.min_returns <= 10000, "min_returns", o.min_returns,
          "in [3, 10000] (a plane has 3 parameters)");
  require(std::isfinite(o.max_fit_residual) && o.max_fit_residual > 0, "max_fit_residual",
          o.max_fit_residual, "finite and > 0");
  require(std::isfinite(o.layer_gap) && o.layer_gap > 0, "layer_gap", o.layer_gap,
          "finite and > 0");
}

}  // namespace twistslam::lidar
