#pragma once
// Plane fitting: RANSAC on 3-point samples, then a least-squares (SVD) refit on the inliers,
// as the paper does for the road cluster ("SVD in a RANSAC loop").
#include <cstdint>
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::geometry {

struct PlaneFitOptions {
  double inlier_threshold = 0.05;  // m, point-to-plane distance counted as inlier
  int iterations = 200;            // RANSAC samples
  std::uint64_t seed = 0;          // deterministic sampling
  // > 0: samples are drawn from, and scored on, an evenly strided subset of at most this many
  // points (a LiDAR ground holds tens of thousands); the refits use every point. 0: all
  int max_scored_points = 0;
};

struct PlaneFit {
  Vec4 plane = Vec4::Zero();  // (n, d) with |n| = 1, n.X + d = 0, sign chosen so that d >= 0
  std::vector<std::uint8_t> inliers;  // one flag per input point
  int num_inliers = 0;
  double rms = 0;  // m, RMS distance of the inliers to the refined plane
};

// Least-squares plane through points (centroid + smallest singular vector). Needs >= 3 points.
Vec4 fit_plane_svd(const Points3& points);

// Throws std::invalid_argument for fewer than 3 points, non-finite points or options.
PlaneFit fit_plane_ransac(const Points3& points, const PlaneFitOptions& options = {});

}  // namespace twistslam::geometry
