#pragma once
// The local bundle adjustment after a keyframe insertion: paper eq. 9 over the new keyframe's
// covisible window of its map segment, e_stat from the map and, when given, e_dyna and the
// link from the moving objects.
//
// Three steps, so that the solve can run beside tracking (LocalMapper, local_ba.asynchronous):
// prepare copies what the BA needs out of the map (and the objects) into a LocalBAJob; solve
// touches nothing but the job; apply writes the result back. local_bundle_adjustment runs
// the three in a row.
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "optim/bundle_adjustment.hpp"
#include "tracking/level_weights.hpp"
#include "tracking/object_bundle_terms.hpp"
#include "tracking/options.hpp"

namespace twistslam::tracking {

struct LocalBAJob {
  int keyframe_id = -1;                            // the inserted keyframe
  int frame_index = -1;                            // its frame
  optim::BAProblem problem;                        // a copy: the map may be read meanwhile
  std::vector<std::pair<int, int>> keyframe_slots;  // (keyframe id, slot in problem.keyframes)
  std::vector<int> window;                          // the free keyframes' ids
  std::vector<int> point_ids;                       // map id of each problem point
  std::vector<std::pair<int, int>> obs_link;        // (point id, keyframe id) per observation
  ObjectBundleTerms* objects = nullptr;             // takes the object half of the result
  optim::BundleAdjustmentReport report;             // solve's output
  double solve_ms = 0;                              // wall time of solve
};

// Frees keyframe_id and its options.window - 1 most covisible keyframes of the same segment,
// holds up to options.max_fixed others sharing their points (and gauge_keyframe, the
// segment's first) fixed, and takes the points seen by >= 2 keyframes of the problem.
// objects (nullable) adds the moving objects seen from the problem's keyframes. Returns
// false, filling nothing, when the window is the keyframe alone.
bool prepare_local_ba(const map::Map& map, int keyframe_id, int gauge_keyframe,
                      const LocalBAOptions& options, const LevelWeights& weights,
                      ObjectBundleTerms* objects, LocalBAJob* job);
// Solves the job's problem in place (any thread: it reads nothing else).
void solve_local_ba(const geometry::StereoCamera& camera, const LocalBAOptions& options, LocalBAJob* job);
// Writes the refined free poses and points into the map (those erased meanwhile are
// skipped), erases the outlier observations and the points left without any, updates the
// window's covisibility, and gives the objects their result.
void apply_local_ba(const LocalBAJob& job, map::Map& map);

// prepare + solve + apply. Returns false, changing nothing, when the window is the keyframe alone.
bool local_bundle_adjustment(map::Map& map, int keyframe_id, int gauge_keyframe,
                             const geometry::StereoCamera& camera, const LocalBAOptions& options,
                             const LevelWeights& weights, ObjectBundleTerms* objects = nullptr);

}  // namespace twistslam::tracking
