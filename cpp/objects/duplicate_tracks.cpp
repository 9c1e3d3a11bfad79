#include "objects/duplicate_tracks.hpp"

#include <cmath>

#include "geometry/se3.hpp"

namespace twistslam::objects {
namespace {

// whether track a ranks above track b (index order breaks ties). The axis rank first: a far car
// the classical detector read end-on (its prior length laid along the line of sight) in most
// of its boxes and from the side in the nearer ones got two tracks, one per axis, and the one
// with more boxes was the quarter-turned one (classical urban s11's car 22, stopped across the
// road at 35-48 m: yaw error 91 deg)
bool ranks_above(const TrackFootprint& a, size_t index_a, const TrackFootprint& b, size_t index_b) {
  if (a.axis_rank != b.axis_rank) return a.axis_rank > b.axis_rank;
  if (a.boxes != b.boxes) return a.boxes > b.boxes;
  return index_a < index_b;
}

}  // namespace

std::vector<int> duplicate_owners(const std::vector<TrackFootprint>& tracks, double margin_m) {
  std::vector<int> owner(tracks.size(), -1);
  if (!(margin_m >= 0)) return owner;
  for (size_t a = 0; a < tracks.size(); ++a) {
    const TrackFootprint& box = tracks[a];
    if (!box.canonical || !(box.size.minCoeff() > 0)) continue;
    const Mat4 T_o_w = geometry::se3_inverse(box.T_w_o);
    // box axes: x length, y down, z width
    const double half_length = box.size.x() / 2 + margin_m, half_width = box.size.y() / 2 + margin_m;
    for (size_t b = 0; b < tracks.size(); ++b) {
      const TrackFootprint& other = tracks[b];
      if (b == a || other.class_id != box.class_id || !ranks_above(box, a, other, b)) continue;
      const Vec3 p = T_o_w.topLeftCorner<3, 3>() * other.T_w_o.topRightCorner<3, 1>() +
                     T_o_w.topRightCorner<3, 1>();
      if (std::abs(p.x()) > half_length || std::abs(p.z()) > half_width) continue;
      if (owner[b] < 0 || ranks_above(box, a, tracks[owner[b]], owner[b])) owner[b] = static_cast<int>(a);
    }
  }
  return owner;
}

}  // namespace twistslam::objects
