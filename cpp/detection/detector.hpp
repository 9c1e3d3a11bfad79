#pragma once
// The classical LiDAR 3D detector (docs/detection.md): region of interest -> road removal
// (ground_removal) -> bird's-eye-view clustering (euclidean_clustering) -> L-shape fit
// (box_fitting) -> class, car-size prior and score (classify). No learned weights; the
// default detection source of twistslam without a 3DSSD checkpoint.
#include <vector>

#include "detection/classify.hpp"
#include "detection/detector_options.hpp"
#include "detection/top_beam.hpp"
#include "geometry/types.hpp"

namespace twistslam::detection {

struct DetectorTimings {  // ms of wall time per stage of the last call
  double select_ms = 0, ground_ms = 0, cluster_ms = 0, fit_ms = 0;
};

struct DetectorResult {
  std::vector<Detection> detections;  // sorted by decreasing score
  int num_non_finite = 0;             // input rows with NaN / Inf (dropped)
  int num_selected = 0;               // returns in the region of interest
  int num_obstacle = 0;               // of those, above the road and below the height cap
  int num_clusters = 0;               // clusters with at least min_cluster_points returns
  TopBeam top_beam;                   // the LiDAR's top beam as fitted (person_top_beam_margin_m > 0)
  DetectorTimings timings;
};

// Boxes of the road users in a scan. points_c: (N, 3) in the rectified camera frame (N may
// be 0; NaN / Inf rows are skipped and counted). Throws std::invalid_argument on invalid
// options (see validate).
DetectorResult detect(const Eigen::Ref<const Points3>& points_c, const DetectorOptions& options = {});

}  // namespace twistslam::detection
