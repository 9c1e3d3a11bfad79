#include "objects/box_travel.hpp"

#include <algorithm>

namespace twistslam::objects {
namespace {

struct Line {
  bool valid = false;
  Vec3 origin = Vec3::Zero();    // position at frame f0
  Vec3 velocity = Vec3::Zero();  // per frame
  double f0 = 0;
};

// Least-squares p(f) = origin + velocity (f - f0) over the centres with use[i].
Line fit_line(const std::vector<BoxCentre>& c, const std::vector<char>& use) {
  Line line;
  double n = 0, mean_f = 0;
  Vec3 mean_p = Vec3::Zero();
  for (size_t i = 0; i < c.size(); ++i)
    if (use[i]) n += 1, mean_f += c[i].frame, mean_p += c[i].centre_w;
  if (n < 2) return line;
  mean_f /= n;
  mean_p /= n;
  double sff = 0;
  Vec3 sfp = Vec3::Zero();
  for (size_t i = 0; i < c.size(); ++i) {
    if (!use[i]) continue;
    const double df = c[i].frame - mean_f;
    sff += df * df;
    sfp += df * (c[i].centre_w - mean_p);
  }
  if (!(sff > 0)) return line;  // every centre at one frame
  line.valid = true;
  line.f0 = mean_f;
  line.origin = mean_p;
  line.velocity = sfp / sff;
  return line;
}

}  // namespace

BoxTravel box_travel(const std::vector<BoxCentre>& centres, const BoxTravelOptions& options) {
  BoxTravel out;
  std::vector<char> use(centres.size(), 1);
  for (size_t i = 0; i < centres.size(); ++i) use[i] = centres[i].centre_w.allFinite();
  const Line first = fit_line(centres, use);
  if (!first.valid) return out;
  for (size_t i = 0; i < centres.size(); ++i) {
    if (!use[i]) continue;
    const Vec3 on_line = first.origin + first.velocity * (centres[i].frame - first.f0);
    use[i] = (centres[i].centre_w - on_line).norm() <= options.outlier_m;
  }
  const Line second = fit_line(centres, use);
  if (!second.valid) return out;
  int lo = 0, hi = 0;
  bool any = false;
  for (size_t i = 0; i < centres.size(); ++i) {
    if (!use[i]) continue;
    lo = any ? std::min(lo, centres[i].frame) : centres[i].frame;
    hi = any ? std::max(hi, centres[i].frame) : centres[i].frame;
    any = true;
    ++out.inliers;
  }
  out.valid = true;
  out.velocity_w = second.velocity;
  out.distance_m = second.velocity.norm() * (hi - lo);
  return out;
}

}  // namespace twistslam::objects
