#include "detection/occlusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twistslam::detection {

namespace {
// deg, azimuth bin: ~5 HDL-64 steps (0.09 deg), 2-3 of the simulator's (0.2 deg), so that a
// bin of a surface always holds a return.
constexpr double kAzimuthBinDeg = 0.5;
// deg, elevation bin: about one HDL-64 / simulated beam spacing (0.4 deg).
constexpr double kElevationBinDeg = 0.5;
// deg, elevations covered (returns outside are clamped to the end bins): the HDL-64 looks
// from -24.8 to +2 deg; objects above the sensor are cut at max_object_height_m anyway.
constexpr double kLowestElevationDeg = -30.0, kHighestElevationDeg = 10.0;
// deg, how far past a cluster's edge an occluder is looked for: the first bins decide.
constexpr double kLookDeg = 2.0;
// m, an occluder must be this much nearer than the cluster's edge return: the cluster's own
// rounded corner, one bin over, is not an occluder.
constexpr double kOccluderMarginM = 0.5;
}  // namespace

double azimuth_of(double x, double z) { return std::atan2(x, z); }

OcclusionMap::OcclusionMap(const std::vector<ScenePoint>& points, const std::vector<char>& obstacle,
                           double half_angle_deg)
    : half_angle_rad_(half_angle_deg * M_PI / 180.0),
      azimuth_bins_(static_cast<int>(std::ceil(2.0 * half_angle_deg / kAzimuthBinDeg)) + 1) {
  const int elevation_bins =
      static_cast<int>(std::ceil((kHighestElevationDeg - kLowestElevationDeg) / kElevationBinDeg)) + 1;
  nearest_.assign(static_cast<std::size_t>(azimuth_bins_) * elevation_bins,
                  std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!obstacle[i]) continue;
    const ScenePoint& p = points[i];
    const double range = std::hypot(p.x, p.z);
    float& n = nearest_[static_cast<std::size_t>(azimuth_bin(azimuth_of(p.x, p.z))) * elevation_bins +
                        elevation_bin(p.up, range)];
    n = std::min(n, static_cast<float>(range));
  }
}

int OcclusionMap::azimuth_bin(double az_rad) const {
  const int b = static_cast<int>(std::floor((az_rad + half_angle_rad_) * 180.0 / M_PI / kAzimuthBinDeg));
  return std::clamp(b, 0, azimuth_bins_ - 1);
}

int OcclusionMap::elevation_bin(double up_m, double range_m) const {
  const int top = static_cast<int>(std::ceil((kHighestElevationDeg - kLowestElevationDeg) / kElevationBinDeg));
  const double el_deg = std::atan2(up_m, range_m) * 180.0 / M_PI;
  return std::clamp(static_cast<int>(std::floor((el_deg - kLowestElevationDeg) / kElevationBinDeg)), 0, top);
}

bool OcclusionMap::hidden_beyond(const std::vector<ScenePoint>& points, const std::vector<int>& members,
                                 int side) const {
  double edge = side > 0 ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  for (const int i : members) {
    const double az = azimuth_of(points[i].x, points[i].z);
    edge = side > 0 ? std::max(edge, az) : std::min(edge, az);
  }
  const double bin = kAzimuthBinDeg * M_PI / 180.0, look = kLookDeg * M_PI / 180.0;
  // the field ends here (a whole turn has no end: it wraps to the other side)
  if (std::abs(edge + side * look) > half_angle_rad_) return half_angle_rad_ < M_PI;
  const int elevation_bins = static_cast<int>(nearest_.size()) / azimuth_bins_;
  int edge_returns = 0, hidden = 0;
  for (const int i : members) {
    const ScenePoint& p = points[i];
    const double az = azimuth_of(p.x, p.z);
    if (std::abs(az - edge) > bin) continue;  // not at the edge
    ++edge_returns;
    const double range = std::hypot(p.x, p.z);
    const int el = elevation_bin(p.up, range);
    bool nearer = false;
    for (double d = bin; d <= look + 1e-12 && !nearer; d += bin) {
      const int a = azimuth_bin(az + side * d);
      for (int e = std::max(0, el - 1); e <= std::min(elevation_bins - 1, el + 1) && !nearer; ++e)
        nearer = nearest_[static_cast<std::size_t>(a) * elevation_bins + e] < range - kOccluderMarginM;
    }
    hidden += nearer;
  }
  return edge_returns > 0 && 2 * hidden >= edge_returns;
}

}  // namespace twistslam::detection
