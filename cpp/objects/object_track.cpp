#include "objects/object_track.hpp"

#include <algorithm>

namespace twistslam::objects {

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

void ObjectTrack::update_size() {
  // a partly seen car's box has the prior's length (KITTI's cars: 3.4-5.2 m): where other
  // frames measured the length, only those give it
  bool any_measured = false;
  for (const auto& f : frames) any_measured |= f.has_detection() && f.open_end_w.isZero();
  std::vector<double> dim;
  for (int d = 0; d < 3; ++d) {
    dim.clear();
    for (const auto& f : frames) {
      if (f.has_detection() && (d != 0 || !any_measured || f.open_end_w.isZero()))
        dim.push_back(f.detected_size[d]);
    }
    if (dim.empty()) continue;
    // the median, as the paper fuses sizes: robust to a few truncated / merged detections
    const size_t mid = dim.size() / 2;
    std::nth_element(dim.begin(), dim.begin() + mid, dim.end());
    double median = dim[mid];
    if (dim.size() % 2 == 0) {
      median = 0.5 * (median + *std::max_element(dim.begin(), dim.begin() + mid));
    }
    size[d] = median;
  }
  // the seen face stays, the prior's end moves to the track's length: the centre moves by
  // half the difference (a rear-only box of a 4.8 m car was 0.4 m too near with the 4.0 prior)
  for (auto& f : frames) {
    if (!f.has_detection() || f.open_end_w.isZero()) continue;
    const double shift = 0.5 * (size[0] - f.detected_size[0]);
    f.T_w_o_detected.topRightCorner<3, 1>() += (shift - f.open_shift_m) * f.open_end_w;
    f.open_shift_m = shift;
  }
}

}  // namespace twistslam::objects
