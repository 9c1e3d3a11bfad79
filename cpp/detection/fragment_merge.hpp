#pragma once
// Far cars split in two by the clustering: a car seen end-on beyond ~20 m (an oncoming car's
// front, a lead car's rear) has its bumper hit by one or two rings, the next ring passes over
// the hood (trunk) and lands on the windshield (rear window) a hood's length behind. That gap
// is wider than cluster_gap_m, so the bumper's returns form a cluster of their own (dropped
// when small, no car when not), and the car's box is laid with the prior length from the
// windshield: 1-1.4 m off along the car (simulated urban s8's oncoming car 11 at 35-50 m,
// every second frame).
// A fragment (a cluster at least fragment_min_range_m away whose returns span at most
// fragment_max_height_extent_m in height) joins the cluster whose returns lie behind most of
// its own on the same bearings, at most fragment_merge_gap_m farther, when that cluster's top
// is fragment_min_rise_m higher: the body behind a bumper. Fragments beside a cluster, in
// front of nothing or near the sensor stay as they are; clusters left with fewer than
// min_cluster_points returns are dropped, as before.
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

// `clusters`: every connected component (lists of positions in `points`). On return, those
// with at least min_cluster_points returns after the fragments joined the clusters behind them.
void merge_face_fragments(const std::vector<ScenePoint>& points,
                          std::vector<std::vector<int>>* clusters, const DetectorOptions& options);

}  // namespace twistslam::detection
