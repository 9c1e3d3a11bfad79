#include "objects/duplicate_tracks.hpp"

#include <cmath>

#include "geometry/se3.hpp"

namespace twistslam::objects {

std::vector<char> duplicate_tracks(const std::vector<TrackFootprint>& tracks, double margin_m) {
  std::vector<char> duplicate(tracks.size(), 0);
  if (!(margin_m >= 0)) return duplicate;
  for (size_t a = 0; a < tracks.size(); ++a) {
    const TrackFootprint& box = tracks[a];
    if (!box.canonical || !(box.size.minCoeff() > 0)) continue;
    const Mat4 T_o_w = geometry::se3_inverse(box.T_w_o);
    // box axes: x length, y down, z width
    const double half_length = box.size.x() / 2 + margin_m, half_width = box.size.y() / 2 + margin_m;
    for (size_t b = 0; b < tracks.size(); ++b) {
      const TrackFootprint& other = tracks[b];
      if (b == a || other.class_id != box.class_id) continue;
      if (other.boxes > box.boxes || (other.boxes == box.boxes && b < a)) continue;
      const Vec3 p = T_o_w.topLeftCorner<3, 3>() * other.T_w_o.topRightCorner<3, 1>() +
                     T_o_w.topRightCorner<3, 1>();
      if (std::abs(p.x()) <= half_length && std::abs(p.z()) <= half_width) duplicate[b] = 1;
    }
  }
  return duplicate;
}

}  // namespace twistslam::objects
