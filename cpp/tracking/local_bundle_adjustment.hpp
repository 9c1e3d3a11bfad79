#pragma once
// The local bundle adjustment after a keyframe insertion: paper eq. 9 over the new keyframe's
// covisible window of its map segment, e_stat from the map and, when given, e_dyna and the
// link from the moving objects.
#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "tracking/level_weights.hpp"
#include "tracking/object_bundle_terms.hpp"
#include "tracking/options.hpp"

namespace twistslam::tracking {

// Frees keyframe_id and its options.window - 1 most covisible keyframes of the same segment,
// holds up to options.max_fixed others sharing their points (and gauge_keyframe, the
// segment's first) fixed, and refines poses and the points seen by >= 2 keyframes of the
// problem. Outlier observations are erased from the map, points left without any with them.
// objects (nullable) adds the moving objects seen from the problem's keyframes and takes
// their refined poses and points back. Returns false, changing nothing, when the window is
// the keyframe alone.
bool local_bundle_adjustment(map::Map& map, int keyframe_id, int gauge_keyframe,
                             const geometry::StereoCamera& camera, const LocalBAOptions& options,
                             const LevelWeights& weights, ObjectBundleTerms* objects = nullptr);

}  // namespace twistslam::tracking
