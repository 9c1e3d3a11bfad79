#pragma once
// Back in time from a new track's first box: the boxes of the frames before it that no track
// took and that line up with it, nearest first under a constant velocity. A car whose cluster
// could not start yet (too few stereo points: far, dark, or queued behind a nearer car) was
// already boxed by the detector; those boxes place it in the frames it was not tracked in.
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::objects {

struct BoxChainOptions {
  // the first step back has no velocity yet: the box must lie this close to the first one
  // (m; a car at 100 km/h moves 2.8 m a frame at 10 Hz)
  double first_gate_m = 3.0;
  // later steps: this close to the constant-velocity prediction (m)
  double gate_m = 1.0;
  // the nearest box must be this much nearer than the next one (m), or the chain stops
  double ambiguity_m = 1.0;
};

// start: the first box's centre (frame F). earlier[s]: the centres of the candidate boxes of
// frame F - 1 - s. Returns, per step back, the index of the chosen box in earlier[s], up to
// the first step with none (so the frames are consecutive).
std::vector<int> box_chain(const Vec3& start, const std::vector<std::vector<Vec3>>& earlier,
                           const BoxChainOptions& options = {});

}  // namespace twistslam::objects
