#pragma once
// The LiDAR's highest beam, fitted to the scan: where it runs, an object's highest return
// is where the field of view ends, not the object's top. A pole or a tree trunk near the
// sensor is cut flat there (1.9-2.2 m above the road at 6-12 m) and would pass the person
// height test; a person's head lies below it: 0.17 m and more on 7 simulated sequences,
// 0.26 m and more for real KITTI's labelled pedestrians and cyclists (docs/detection.md,
// "Posts cut by the top beam").
//
// The beam is a cone about the sensor's axis: in the camera frame c its height is
// up = a + b r + c x + d z (r the horizontal range; b = tan of its elevation; c, d the small
// tilt between sensor and camera; a the sensor's height over the camera centre and its
// emitters' offsets). The fit takes the highest return of each (range, azimuth) bin, the
// upper envelope of the scan: where the beam hits something (facades, trees, poles) the
// envelope is the beam, elsewhere it is lower, and nowhere above it. So the beam is the cone
// (RANSAC over the bins) with the most bins on it and almost none above it, refined by least
// squares on its bins.
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

struct TopBeam {
  bool valid = false;  // false: too few envelope bins on a cone (an open field, a short scan)
  double a = 0, b = 0, c = 0, d = 0;  // up = a + b r + c x + d z (m)
  int num_bins = 0;                   // envelope bins on the fitted cone
  double rms_m = 0;                   // their residual

  // m, the beam's height (up, camera frame) at the point (x, z)
  double up_at(double x, double z) const;
};

// The top beam of the selected returns (x right, z forward, up in the camera frame).
TopBeam fit_top_beam(const std::vector<ScenePoint>& points);

// Whether the cluster's highest return lies on the beam, within margin_m of it: the object
// continues above what the sensor sees. False without a valid beam.
bool cut_by_top_beam(const std::vector<int>& members, const std::vector<ScenePoint>& points,
                     const TopBeam& beam, double margin_m);

}  // namespace twistslam::detection
