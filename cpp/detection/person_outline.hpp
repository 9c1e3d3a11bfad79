#pragma once
// Whether a person-sized cluster has a person's outline or a post's: a person's head is
// narrower than their shoulders, a pole or a tree trunk is as wide at its top as lower down
// (and a tall one is cut flat by the LiDAR's highest beam, so it passes the person height
// test at 5-12 m). The widths are the visible ones, across the line of sight: the azimuth
// span of a height band's returns times their median range.
//
// Measured (docs/detection.md, "Posts read as people"): head / shoulder width of real KITTI's
// labelled pedestrians 0.29-0.72, of the tree trunk 0001 passes at 4-11 m 0.96-1.00; on 15
// simulated sequences people median 0.40, trunks and poles 1.00 (p5 0.83-0.86).
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

struct PersonOutline {
  double head_width_m = 0;      // the returns within head_band_m of the top (0: fewer than 2)
  double shoulder_width_m = 0;  // those shoulder_band_m below the top (0: fewer than 2)
};

// m below the cluster's top: the head band [0, 0.2] and the shoulder band [0.35, 0.6] (an
// adult's head is ~0.23 m tall; the shoulders and chest span the next ~0.4 m).
inline constexpr double kHeadBandM = 0.2;
inline constexpr double kShoulderBandFromM = 0.35, kShoulderBandToM = 0.6;

// Of the returns pts[members] (x, up, z), with `top_up` the highest one's up.
PersonOutline person_outline(const std::vector<int>& members, const std::vector<ScenePoint>& pts,
                             float top_up);

}  // namespace twistslam::detection
