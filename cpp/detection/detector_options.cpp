#include "detection/detector_options.hpp"

#include <stdexcept>
#include <string>

namespace twistslam::detection {

namespace {
// Cells of a square grid of half-side `range` m at `cell` m: bounded so that the dense grids
// of the ground and the clustering stay a few tens of MB at most.
constexpr double kMaxGridCells = 16.0e6;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("detection options: " + message);
}
}  // namespace

void validate(const DetectorOptions& options) {
  options::check_ranges(options, "detection.");
  const DetectorOptions& o = options;
  require(o.min_range_m < o.max_range_m, "min_range_m must be below max_range_m");
  require(o.car_length_m <= o.car_max_length_m, "car_length_m must not exceed car_max_length_m");
  require(o.car_width_m <= o.car_max_width_m, "car_width_m must not exceed car_max_width_m");
  require(o.car_min_height_m <= o.car_max_height_m, "car_min_height_m must not exceed car_max_height_m");
  require(o.person_min_height_m <= o.person_max_height_m,
          "person_min_height_m must not exceed person_max_height_m");
  const double side = 2.0 * o.max_range_m;
  require(side / o.cluster_cell_m * side / o.cluster_cell_m <= kMaxGridCells,
          "max_range_m / cluster_cell_m gives a clustering grid of more than 16M cells");
  require(360.0 / o.ground_segment_deg * o.max_range_m / o.ground_cell_m <= kMaxGridCells,
          "ground_segment_deg and max_range_m / ground_cell_m give a ground grid of more than 16M cells");
}

}  // namespace twistslam::detection
