#include "detection/classify.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::detection {

namespace {
// m, smallest box side given to a person: returns cover only the side facing the sensor, and
// KITTI pedestrian boxes measure ~0.84 x 0.66 m (training means).
constexpr double kPersonMinLength = 0.6;
constexpr double kPersonMinWidth = 0.5;
// share of the score kept by a box that the prior extended entirely (a single face): such a
// box is as likely a car, its extent is only less certain.
constexpr double kUnseenAreaWeight = 0.5;

// KITTI rotation_y of a box whose length axis has direction (dx, dz) in (x, z), in
// [-pi/2, pi/2): rotation about y by ry maps the object x axis to (cos ry, -sin ry).
double yaw_of(const BevPoint& d) {
  double ry = std::atan2(-d.z, d.x);
  if (ry >= 0.5 * M_PI) ry -= M_PI;
  if (ry < -0.5 * M_PI) ry += M_PI;
  return ry;
}

Detection make_box(const ClusterShape& s, const BevRectangle& r, int length_axis, double height,
                   ObjectClass cls) {
  Detection d;
  const BevPoint c = r.centre();
  d.centre = Vec3(c.x, -(s.road_up + 0.5 * height), c.z);
  d.length = r.extent(length_axis);
  d.width = r.extent(1 - length_axis);
  d.height = height;
  d.yaw = yaw_of(r.axis_direction(length_axis));
  d.cls = cls;
  d.num_points = s.num_points;
  d.edge_distance_m = r.mean_edge_distance;
  return d;
}

// Whether the returns of the side along `axis` lie closer together than the clustering's gap
// even at its far end: consecutive azimuth steps hit a side seen at angle theta from the
// line of sight at range r about r * step / sin(theta) apart, and a wider spacing may have
// cut the side's far end off into another cluster.
bool side_densely_seen(const BevRectangle& f, int axis, const DetectorOptions& o) {
  const BevPoint centre = f.centre(), a = f.axis_direction(axis);
  const double range = std::hypot(centre.x, centre.z) + 0.5 * f.extent(axis);  // the far end
  const double cos_view = std::abs(a.x * centre.x + a.z * centre.z) / std::hypot(centre.x, centre.z);
  const double sin_view = std::sqrt(std::max(0.0, 1.0 - cos_view * cos_view));
  return range * o.sensor_azimuth_step_deg * M_PI / 180.0 < o.cluster_gap_m * sin_view;
}

// deg, the occlusion of one azimuth side decides which end of a partly seen car is hidden
// only if its length axis is at least this far from the line of sight: nearer to it (a rear
// view) both ends lie at about the same azimuth and the far end is hidden by the car itself.
constexpr double kMinOccludedEndViewDeg = 30.0;

// +1 / -1: the hi / lo end of `axis` is hidden by something nearer (or lies past the field's
// end) while the other end's azimuth side is open; 0: neither or both, or a view along `axis`.
int hidden_end_of(const ClusterShape& s, const BevRectangle& f, int axis) {
  if (s.hidden_low_azimuth == s.hidden_high_azimuth) return 0;
  const BevPoint centre = f.centre(), a = f.axis_direction(axis);
  const double along = std::abs(a.x * centre.x + a.z * centre.z) / std::hypot(centre.x, centre.z);
  if (along > std::cos(kMinOccludedEndViewDeg * M_PI / 180.0)) return 0;
  // the hi end lies at the larger azimuth if moving along +axis turns the bearing right
  // (azimuth atan2(x, z) grows): d(azimuth) ~ (a.x z - a.z x) / r^2
  const bool hi_is_high_azimuth = a.x * centre.z - a.z * centre.x > 0.0;
  return hi_is_high_azimuth == s.hidden_high_azimuth ? +1 : -1;
}

// m, a prior that moved the box centre less than this along its heading left both ends as seen
constexpr double kMinOpenShift = 0.01;

// +1 / -1: the box (yaw's heading (cos, -sin) in (x, z)) grew past the seen footprint towards
// its +x / -x end; 0: it did not grow along its length
int open_end_of(const BevRectangle& seen, const BevRectangle& box, double yaw) {
  const BevPoint a = seen.centre(), b = box.centre();
  const double along = (b.x - a.x) * std::cos(yaw) - (b.z - a.z) * std::sin(yaw);
  return along > kMinOpenShift ? +1 : along < -kMinOpenShift ? -1 : 0;
}

// the car's length axis and its extended footprint, or nullopt if the footprint is no car's
std::optional<Detection> as_car(const ClusterShape& s, const DetectorOptions& o) {
  const BevRectangle& f = s.footprint;
  const int long_axis = f.extent(0) >= f.extent(1) ? 0 : 1;
  const double long_side = f.extent(long_axis), short_side = f.extent(1 - long_axis);
  if (s.top_m < o.car_min_height_m || s.top_m > o.car_max_height_m) return std::nullopt;
  if (f.mean_edge_distance > o.car_max_edge_distance_m) return std::nullopt;  // no faces: clutter
  if (long_side < o.car_min_visible_m || long_side > o.car_max_length_m ||
      short_side > o.car_max_width_m)
    return std::nullopt;
  // a footprint no longer than a car is wide shows the rear or front (and maybe a sliver of a
  // side, seen at a grazing angle): the car's length runs away from the sensor, along the
  // footprint's axis nearer the line of sight. Longer footprints show a side: both faces of
  // an unoccluded car are seen whole.
  const bool rear_or_front = long_side <= o.car_max_width_m;
  int length_axis = long_axis;
  if (rear_or_front) {  // the length is the axis nearer the line of sight
    const BevPoint centre = f.centre(), a = f.axis_direction(long_axis);
    const double along_ray = std::abs(a.x * centre.x + a.z * centre.z) / std::hypot(centre.x, centre.z);
    length_axis = along_ray > M_SQRT1_2 ? long_axis : 1 - long_axis;
  }
  if (rear_or_front && short_side < o.single_face_m && long_side <= o.cyclist_max_length_m &&
      s.top_m >= o.cyclist_min_height_m && s.upper_extent_m < o.cyclist_max_upper_extent_m)
    return std::nullopt;  // a cyclist seen from the side (see classify)
  // an L (two faces, the length side not a rear seen edge-on) at least car_min_length_m long
  // shows the whole length: only the far end, rounded off out of the sensor's sight, is
  // missing. Any other view gives a lower bound: the prior's length behind the visible face.
  const double seen_length = f.extent(length_axis);
  const bool length_seen = !rear_or_front && short_side >= o.single_face_m &&
                           seen_length >= o.car_min_length_m &&
                           side_densely_seen(f, length_axis, o);
  BevRectangle box = f;
  const double length = length_seen ? seen_length + o.car_hidden_end_m : o.car_length_m;
  const int hidden_end = length_seen ? 0 : hidden_end_of(s, f, length_axis);
  if (hidden_end != 0) {
    box.extend_edge(length_axis, length, hidden_end > 0);
  } else {
    box.extend_away_from_sensor(length_axis, length);
  }
  box.extend_away_from_sensor(1 - length_axis, o.car_width_m);
  Detection d = make_box(s, box, length_axis, s.top_m, ObjectClass::kCar);
  d.length_seen = length_seen;
  if (!length_seen) d.open_end = open_end_of(f, box, d.yaw);
  const double seen = std::min(1.0, f.extent(0) * f.extent(1) / (d.length * d.width));
  const double fit = std::exp(-f.mean_edge_distance / o.score_edge_distance_m);
  d.score = fit * (kUnseenAreaWeight + (1.0 - kUnseenAreaWeight) * seen);
  return d;
}
}  // namespace

const char* to_string(ObjectClass cls) {
  switch (cls) {
    case ObjectClass::kCar: return "Car";
    case ObjectClass::kPedestrian: return "Pedestrian";
    case ObjectClass::kCyclist: return "Cyclist";
  }
  return "?";
}

std::optional<Detection> classify(const ClusterShape& s, const DetectorOptions& o) {
  if (s.bottom_m > o.max_ground_gap_m || s.num_points <= 0) return std::nullopt;  // floating
  const double count = 1.0 - std::exp(-s.num_points / o.score_points_scale);
  std::optional<Detection> d = as_car(s, o);
  if (!d) {
    const BevRectangle& f = s.footprint;
    const int long_axis = f.extent(0) >= f.extent(1) ? 0 : 1;
    const double long_side = f.extent(long_axis), short_side = f.extent(1 - long_axis);
    const bool person_height = s.top_m >= o.person_min_height_m && s.top_m <= o.person_max_height_m;
    if (!person_height || short_side > o.person_max_width_m) return std::nullopt;
    ObjectClass cls;
    if (long_side <= o.pedestrian_max_length_m) {
      cls = ObjectClass::kPedestrian;
    } else if (long_side <= o.cyclist_max_length_m) {
      cls = ObjectClass::kCyclist;
    } else {
      return std::nullopt;
    }
    BevRectangle box = f;
    box.extend_away_from_sensor(long_axis, kPersonMinLength);
    box.extend_away_from_sensor(1 - long_axis, kPersonMinWidth);
    d = make_box(s, box, long_axis, s.top_m, cls);
    d->score = 1.0;  // a person's footprint has no edges to score
  }
  d->score *= count;
  return d;
}

}  // namespace twistslam::detection
