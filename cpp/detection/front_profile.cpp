#include "detection/front_profile.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twistslam::detection {

namespace {
// returns a car needs for a profile: a car at ~40 m (fewer are too sparse to span both ends)
constexpr int kMinProfilePoints = 30;
// upper returns needed to place the greenhouse: a few returns of each of two rings
constexpr int kMinUpperPoints = 5;
// the top of the car is this quantile of its returns' heights: one stray high return (an
// antenna, a roof rack's rail, noise) must not lift it
constexpr double kTopQuantile = 0.97;
// +1 / -1: the end of the car's box along its heading (+x / -x) whose azimuth side something
// nearer hides (occlusion.hpp); 2: both sides hidden; 0: neither.
int hidden_end_along_heading(const Detection& car, const ClusterShape& shape) {
  if (shape.hidden_low_azimuth && shape.hidden_high_azimuth) return 2;
  if (!shape.hidden_low_azimuth && !shape.hidden_high_azimuth) return 0;
  // the +x end lies at the larger azimuth (atan2(x, z) grows) if moving along the heading
  // (cos yaw, -sin yaw) in (x, z) turns the bearing right: d(azimuth) ~ (a.x z - a.z x) / r^2
  const double ax = std::cos(car.yaw), az = -std::sin(car.yaw);
  const bool plus_end_is_high = ax * car.centre.z() - az * car.centre.x() > 0.0;
  return plus_end_is_high == shape.hidden_high_azimuth ? +1 : -1;
}
}  // namespace

double profile_gap_difference(const std::vector<ProfilePoint>& points, double upper_fraction) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (static_cast<int>(points.size()) < kMinProfilePoints) return nan;
  std::vector<float> heights;
  heights.reserve(points.size());
  for (const ProfilePoint& p : points) heights.push_back(p.up);
  const auto q = heights.begin() + static_cast<std::ptrdiff_t>(kTopQuantile * (heights.size() - 1));
  std::nth_element(heights.begin(), q, heights.end());
  const double upper = upper_fraction * *q;
  // the extents of all returns (the body, bumper to bumper) and of the upper ones
  float lo = std::numeric_limits<float>::infinity(), hi = -lo, upper_lo = lo, upper_hi = -lo;
  int num_upper = 0;
  for (const ProfilePoint& p : points) {
    lo = std::min(lo, p.along);
    hi = std::max(hi, p.along);
    if (p.up <= upper) continue;
    ++num_upper;
    upper_lo = std::min(upper_lo, p.along);
    upper_hi = std::max(upper_hi, p.along);
  }
  if (num_upper < kMinUpperPoints) return nan;
  // the hood (from the front bumper to the greenhouse) is longer than the trunk
  return (hi - upper_hi) - (upper_lo - lo);
}

int front_from_profile(const std::vector<ProfilePoint>& points, const DetectorOptions& o) {
  const double difference = profile_gap_difference(points, o.front_profile_upper_fraction);
  if (!(std::abs(difference) >= o.front_profile_min_gap_difference_m)) return 0;  // NaN too
  return difference > 0 ? +1 : -1;
}

int front_from_views(const std::vector<double>& differences, int min_views, double min_sigmas,
                     double min_difference_m) {
  double sum = 0, sum2 = 0;
  int n = 0;
  for (const double d : differences) {
    if (!std::isfinite(d)) continue;
    sum += d, sum2 += d * d, ++n;
  }
  if (n < std::max(min_views, 2)) return 0;
  const double mean = sum / n;
  const double variance = std::max(0.0, (sum2 - n * mean * mean) / (n - 1));
  const double standard_error = std::sqrt(variance / n);
  if (std::abs(mean) < min_difference_m || std::abs(mean) < min_sigmas * standard_error) return 0;
  return mean > 0 ? +1 : -1;
}

void tell_front(Detection& car, const ClusterShape& shape, const std::vector<ProfilePoint>& profile,
                const DetectorOptions& o) {
  if (!o.front_from_profile || car.cls != ObjectClass::kCar || !car.length_seen) return;
  // a hidden end may have lost its lid to what hides it, its gap too short (crowded s2's car
  // 69: 3.4 of its 4.64 m seen, the hood behind a nearer object: 10 of 170 fronts wrong)
  const int hidden_end = hidden_end_along_heading(car, shape);
  if (hidden_end == 2) return;
  const int front = front_from_profile(profile, o);
  if (front == 0 || (hidden_end != 0 && front != hidden_end)) return;
  car.heading_known = true;
  if (front < 0) car.yaw = car.yaw >= 0.0 ? car.yaw - M_PI : car.yaw + M_PI;
}

}  // namespace twistslam::detection
