#pragma once
// The local bundle adjustment after a keyframe insertion: the static half of paper eq. 9 over
// the new keyframe's covisible window of its map segment.
#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "tracking/level_weights.hpp"
#include "tracking/options.hpp"

namespace twistslam::tracking {

// Frees keyframe_id and its options.window - 1 most covisible keyframes of the same segment,
// holds up to options.max_fixed others sharing their points (and gauge_keyframe, the
// segment's first) fixed, and refines poses and the points seen by >= 2 keyframes of the
// problem. Outlier observations are erased from the map, points left without any with them.
// Returns false, changing nothing, when the window is the keyframe alone.
bool local_bundle_adjustment(map::Map& map, int keyframe_id, int gauge_keyframe,
                             const geometry::StereoCamera& camera, const LocalBAOptions& options,
                             const LevelWeights& weights);

}  // namespace twistslam::tracking
