#include "objects/object_track.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::objects {
namespace {

// The q quantile of values (0 <= q <= 1), interpolated between order statistics as numpy's
// default: q = 0.5 is the median (the mean of the middle two of an even count).
double quantile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  const double at = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(at));
  const size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (at - static_cast<double>(below)) * (values[above] - values[below]);
}

}  // namespace

const char* to_string(TrackState state) {
  switch (state) {
    case TrackState::kTentative: return "tentative";
    case TrackState::kConfirmed: return "confirmed";
    case TrackState::kLost: return "lost";
    case TrackState::kDead: return "dead";
  }
  return "unknown";
}

const TrackFrame* ObjectTrack::at(int frame) const {
  if (frames.empty()) return nullptr;
  const int k = frame - frames.front().frame;  // frames are consecutive
  if (k < 0 || k >= static_cast<int>(frames.size())) return nullptr;
  return &frames[k];
}

int ObjectTrack::first_linked_row(double max_depth_m, int min_rows) const {
  for (int r = static_cast<int>(frames.size()) - 1; r >= std::max(1, min_rows); --r)
    if (frames[r].reborn && (frames[r].T_c_w * frames[r].T_w_o)(2, 3) < max_depth_m) return r;
  return 0;
}

double ObjectTrack::mean_score() const {
  double sum = 0;
  int n = 0;
  for (const auto& f : frames) {
    if (f.has_detection()) sum += f.score, ++n;
  }
  return n ? sum / n : 0.0;
}

double ObjectTrack::confidence() const {
  double sum = 0;
  int n = 0;
  for (const auto& f : frames) {
    if (f.has_detection()) sum += f.confidence, ++n;
  }
  return n ? sum / n : 0.0;
}

void ObjectTrack::update_size(double bound_quantile) {
  // a partly seen car's box has the prior's length (KITTI's cars: 3.4-5.2 m): where other
  // frames measured the length, only those give it
  bool any_measured = false, all_bounds = true;
  for (const auto& f : frames) {
    if (!f.has_detection() || !f.open_end_w.isZero()) continue;
    any_measured = true;
    all_bounds &= !f.far_end_w.isZero();
  }
  std::vector<double> dim;
  for (int d = 0; d < 3; ++d) {
    dim.clear();
    for (const auto& f : frames) {
      if (f.has_detection() && (d != 0 || !any_measured || f.open_end_w.isZero()))
        dim.push_back(f.detected_size[d]);
    }
    if (dim.empty()) continue;
    // the median, as the paper fuses sizes: robust to a few truncated / merged detections;
    // a point extent's length only ever falls short of the car's (the far end of its side
    // returns few points): an upper quantile of those
    const bool bounds = d == 0 && any_measured && all_bounds;
    size[d] = quantile(dim, bounds ? bound_quantile : 0.5);
  }
  // the seen face stays, the prior's (or the thinned-out) end moves to the track's length: the
  // centre moves by half the difference (a rear-only box of a 4.8 m car was 0.4 m too near
  // with the 4.0 prior)
  for (auto& f : frames) {
    if (!f.has_detection()) continue;
    const Vec3& end_w = f.open_end_w.isZero() ? f.far_end_w : f.open_end_w;
    if (end_w.isZero()) continue;
    const double shift = 0.5 * (size[0] - f.detected_size[0]);
    f.T_w_o_detected.topRightCorner<3, 1>() += (shift - f.open_shift_m) * end_w;
    f.open_shift_m = shift;
  }
}

}  // namespace twistslam::objects
