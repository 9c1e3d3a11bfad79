#include "detection/detector.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "detection/euclidean_clustering.hpp"
#include "detection/front_profile.hpp"
#include "detection/ground_removal.hpp"
#include "detection/occlusion.hpp"
#include "detection/person_outline.hpp"
#include "detection/top_beam.hpp"
#include "detection/scene_points.hpp"
#include "detection/surface_roughness.hpp"

namespace twistslam::detection {

namespace {
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// m, a detection whose centre lies this close to (or inside) a better-scored car box is a
// piece of that car: a face seen edge-on leaves isolated columns of returns ~1-2 m apart
// (one per azimuth step) along the car's far side, inside its prior-extended box or just
// outside it.
constexpr double kCarPieceMarginM = 0.3;

// returns below footprint_max_height_m a sparse cluster needs for its heading to come from
// them alone: 3 define an L (measured: the six simulated sequences' 40-60 m yaw p90 9 -> 5 deg
// with 3 instead of min_cluster_points, see docs/detection.md)
constexpr int kMinHeadingPoints = 3;

bool inside_car(const Detection& car, const Vec3& p, double margin) {
  // the car's length axis is (cos yaw, -sin yaw) in (x, z), its width axis (sin yaw, cos yaw)
  const double dx = p.x() - car.centre.x(), dz = p.z() - car.centre.z();
  const double c = std::cos(car.yaw), s = std::sin(car.yaw);
  const double along = dx * c - dz * s, across = dx * s + dz * c;
  return std::abs(along) <= 0.5 * car.length + margin && std::abs(across) <= 0.5 * car.width + margin;
}

// Whether the box's centre lies within half_angle_deg of the camera axis.
bool centre_in_view(const Detection& d, double half_angle_deg) {
  return std::abs(std::atan2(d.centre.x(), d.centre.z())) <= half_angle_deg * M_PI / 180.0;
}

// Detections sorted by decreasing score, without those whose centre lies in a kept car box.
std::vector<Detection> drop_car_pieces(std::vector<Detection> all) {
  std::stable_sort(all.begin(), all.end(),
                   [](const Detection& a, const Detection& b) { return a.score > b.score; });
  std::vector<Detection> kept;
  for (const Detection& d : all) {
    bool piece = false;
    for (const Detection& k : kept)
      piece = piece || (k.cls == ObjectClass::kCar && inside_car(k, d.centre, kCarPieceMarginM));
    if (!piece) kept.push_back(d);
  }
  return kept;
}

// The profile of a car's returns along its box's heading, for tell_front.
std::vector<ProfilePoint> profile_of(const Detection& car, const ClusterShape& shape,
                                     const std::vector<int>& members, const std::vector<ScenePoint>& pts) {
  const double c = std::cos(car.yaw), s = std::sin(car.yaw);  // heading (c, -s) in (x, z)
  std::vector<ProfilePoint> profile;
  profile.reserve(members.size());
  for (const int i : members)
    profile.push_back({static_cast<float>((pts[i].x - car.centre.x()) * c - (pts[i].z - car.centre.z()) * s),
                       static_cast<float>(pts[i].up - shape.road_up)});
  return profile;
}

// A person-sized cluster whose top is as wide as its shoulders (person_outline.hpp), judged
// only when the shoulders span person_outline_min_steps azimuth steps.
bool is_post(const std::vector<int>& members, const std::vector<ScenePoint>& pts,
             const ClusterShape& shape, const DetectorOptions& o) {
  const PersonOutline outline =
      person_outline(members, pts, static_cast<float>(shape.road_up + shape.top_m));
  if (outline.shoulder_width_m <= 0) return false;
  double range = 0;
  for (const int i : members) range = std::max(range, static_cast<double>(std::hypot(pts[i].x, pts[i].z)));
  const double step_m = o.sensor_azimuth_step_deg * M_PI / 180.0 * range;
  if (outline.shoulder_width_m < o.person_outline_min_steps * step_m) return false;
  return outline.head_width_m >= o.person_max_head_ratio * outline.shoulder_width_m;
}

ClusterShape shape_of(const std::vector<int>& members, const std::vector<ScenePoint>& pts,
                      const std::vector<float>& above, const OcclusionMap& occlusion,
                      const DetectorOptions& o) {
  ClusterShape s;
  // whether something nearer (or the field's end) hides what lies past the azimuth edges
  // (all returns: the footprint's low ones miss the near part of a car beside the sensor,
  // below the lowest beam)
  s.hidden_low_azimuth = occlusion.hidden_beyond(pts, members, -1);
  s.hidden_high_azimuth = occlusion.hidden_beyond(pts, members, +1);
  s.num_points = static_cast<int>(members.size());
  std::vector<BevPoint> bev;
  bev.reserve(members.size());
  // heights relative to the lowest road bin under the cluster: the road seen beside the
  // object rather than one that carried a raised height behind it
  float road = std::numeric_limits<float>::infinity();
  float top = -std::numeric_limits<float>::infinity(), low = -top;
  for (const int i : members) {
    road = std::min(road, pts[i].up - above[i]);  // the road of the point's bin
    top = std::max(top, pts[i].up);
    low = std::min(low, pts[i].up);
  }
  for (const int i : members)
    if (pts[i].up - road <= o.footprint_max_height_m) bev.push_back({pts[i].x, pts[i].z});
  if (static_cast<int>(bev.size()) >= o.min_cluster_points) {
    s.footprint = fit_rectangle(bev, o);
  } else {
    // a sparse (far) car: its few rings above the footprint cross the roof and windows, each
    // a line of returns across the line of sight that the fit takes for a face; the heading
    // comes from the low returns if there are a few, the extent from all returns
    std::vector<BevPoint> all;
    all.reserve(members.size());
    for (const int i : members) all.push_back({pts[i].x, pts[i].z});
    const bool low_heading = static_cast<int>(bev.size()) >= kMinHeadingPoints;
    s.footprint = enclosing_rectangle(all, fit_heading(low_heading ? bev : all, o));
  }
  const int long_axis = s.footprint.extent(0) >= s.footprint.extent(1) ? 0 : 1;
  const BevPoint a = s.footprint.axis_direction(long_axis);
  float upper_lo = std::numeric_limits<float>::infinity(), upper_hi = -upper_lo;
  for (const int i : members) {
    if (pts[i].up - road <= o.footprint_max_height_m) continue;
    const float t = static_cast<float>(a.x * pts[i].x + a.z * pts[i].z);
    upper_lo = std::min(upper_lo, t);
    upper_hi = std::max(upper_hi, t);
  }
  s.upper_extent_m = upper_hi >= upper_lo ? upper_hi - upper_lo : 0.0;
  s.road_up = road;
  s.top_m = top - road;
  s.bottom_m = low - road;
  return s;
}
}  // namespace

DetectorResult detect(const Eigen::Ref<const Points3>& points_c, const DetectorOptions& options) {
  validate(options);
  DetectorResult out;
  auto t = Clock::now();
  const SceneSelection scene = select_scene_points(points_c, options);
  out.num_non_finite = scene.num_non_finite;
  out.num_selected = static_cast<int>(scene.points.size());
  out.timings.select_ms = ms_since(t);

  t = Clock::now();
  const GroundGrid ground = estimate_ground(scene.points, options);
  const std::vector<float> above = height_above_road(scene.points, ground);
  std::vector<char> obstacle(scene.points.size(), 0);
  for (std::size_t i = 0; i < above.size(); ++i) {
    obstacle[i] = above[i] > options.ground_margin_m && above[i] < options.max_object_height_m;
    out.num_obstacle += obstacle[i];
  }
  out.timings.ground_ms = ms_since(t);

  t = Clock::now();
  const std::vector<std::vector<int>> clusters = cluster_bev(scene.points, obstacle, options);
  const OcclusionMap occlusion(scene.points, obstacle,
                               options.front_only ? selection_half_angle_deg(options) : 180.0);
  out.num_clusters = static_cast<int>(clusters.size());
  out.timings.cluster_ms = ms_since(t);

  t = Clock::now();
  // only when a person could be dropped: the fit is one pass over the selection
  if (options.person_top_beam_margin_m > 0) out.top_beam = fit_top_beam(scene.points);
  const TopBeam& top_beam = out.top_beam;
  std::vector<Detection> candidates;
  for (const std::vector<int>& members : clusters) {
    const ClusterShape shape = shape_of(members, scene.points, above, occlusion, options);
    if (std::optional<Detection> d = classify(shape, options)) {
      if (d->cls == ObjectClass::kCar && options.car_max_surface_variation > 0) {
        const SurfaceRoughness rough = surface_roughness(
            members, scene.points, options.surface_voxel_m, options.surface_neighbors);
        if (rough.num_points >= options.surface_min_points) {
          if (rough.median_variation > options.car_max_surface_variation) continue;  // foliage
          d->surface_variation = rough.median_variation;
        }
      }
      if (d->cls != ObjectClass::kCar && options.person_max_head_ratio > 0 &&
          is_post(members, scene.points, shape, options))
        continue;
      if (d->cls != ObjectClass::kCar && options.person_top_beam_margin_m > 0 &&
          cut_by_top_beam(members, scene.points, top_beam, options.person_top_beam_margin_m))
        continue;
      if (options.front_from_profile && d->cls == ObjectClass::kCar && d->length_seen)
        tell_front(*d, shape, profile_of(*d, shape, members, scene.points), options);
      candidates.push_back(*d);
    }
  }
  out.detections = drop_car_pieces(std::move(candidates));
  if (options.front_only && selection_half_angle_deg(options) > options.fov_half_angle_deg) {
    // the margin only serves to see border cars whole: boxes centred in it are not reported
    // (after drop_car_pieces, so that a margin car still removes its pieces in the view)
    std::vector<Detection>& d = out.detections;
    d.erase(std::remove_if(d.begin(), d.end(), [&](const Detection& det) {
              return !centre_in_view(det, options.fov_half_angle_deg);
            }), d.end());
  }
  out.timings.fit_ms = ms_since(t);
  return out;
}

}  // namespace twistslam::detection
