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
  std::vector<double> dim;
  for (int d = 0; d < 3; ++d) {
    dim.clear();
    for (const auto& f : frames) {
      if (f.has_detection()) dim.push_back(f.detected_size[d]);
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
}

}  // namespace twistslam::objects
