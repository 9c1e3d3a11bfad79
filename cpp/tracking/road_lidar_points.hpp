#pragma once
// LiDAR returns of the road cluster (paper sec. "Injecting LiDAR scans": LiDAR points of the
// road class, projected into the segmentation, join the road cluster for plane fitting).
// A return joins when it projects in front of the left camera onto a road pixel whose whole
// (2 border_px + 1)^2 neighbourhood is road: our class images carry no per-pixel score, and
// the mask boundary is where a label is least trustworthy (road masks bleed onto curbs and
// car bottoms, and the LiDAR sees past an object's edge from another viewpoint than the
// camera). The returns kept are spread over the scan by taking at most one per block of
// consecutive candidates, so a 120k-point scan costs one pass of projections plus at most
// about max_points window tests.
#include <opencv2/core/mat.hpp>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::tracking {

struct RoadLidarSelection {
  int road_class_id = 7;     // class id of the road in the label image
  double max_depth_m = 25;   // m along the left optical axis; farther returns are skipped
  int border_px = 3;         // px; every pixel within this Chebyshev distance must be road
  int max_points = 300;      // returns kept per call (the road plane's reservoir holds 5000)
};

struct RoadLidarPoints {
  Points3 points_c;         // kept returns, rectified reference camera frame c
  int num_non_finite = 0;   // scan rows with a NaN / Inf coordinate
  int num_candidates = 0;   // in front, in depth range, on a road pixel (window not tested)
  int num_near_border = 0;  // window tests failed (another class within border_px)
};

// Road returns of `points_c` (N x 3, frame c; empty is fine) in the label image `labels`
// (CV_32SC1 class ids of the left image of `camera`). Empty labels give no points.
// Throws std::invalid_argument for labels of another type, or negative border / max_points,
// or a non-positive max depth.
RoadLidarPoints select_road_lidar_points(const Points3& points_c,
                                         const geometry::StereoCamera& camera,
                                         const cv::Mat& labels,
                                         const RoadLidarSelection& selection);

}  // namespace twistslam::tracking
