#include "detection/person_outline.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twistslam::detection {

namespace {

// Visible width (m) of the returns with up in [lo, hi]: their azimuth span times their
// median horizontal range; 0 with fewer than two.
double band_width(const std::vector<int>& members, const std::vector<ScenePoint>& pts, float lo,
                  float hi) {
  double az_lo = std::numeric_limits<double>::infinity(), az_hi = -az_lo;
  std::vector<double> ranges;
  for (const int i : members) {
    if (pts[i].up < lo || pts[i].up > hi) continue;
    const double az = std::atan2(pts[i].x, pts[i].z);  // person-sized: no wrap at +-pi in view
    az_lo = std::min(az_lo, az);
    az_hi = std::max(az_hi, az);
    ranges.push_back(std::hypot(pts[i].x, pts[i].z));
  }
  if (ranges.size() < 2) return 0.0;
  auto mid = ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2);
  std::nth_element(ranges.begin(), mid, ranges.end());
  return (az_hi - az_lo) * *mid;
}

}  // namespace

PersonOutline person_outline(const std::vector<int>& members, const std::vector<ScenePoint>& pts,
                             float top_up) {
  PersonOutline out;
  out.head_width_m = band_width(members, pts, top_up - static_cast<float>(kHeadBandM), top_up);
  out.shoulder_width_m = band_width(members, pts, top_up - static_cast<float>(kShoulderBandToM),
                                    top_up - static_cast<float>(kShoulderBandFromM));
  return out;
}

}  // namespace twistslam::detection
