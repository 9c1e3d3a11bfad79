#pragma once
// Is a box empty space? A LiDAR return inside a box is a surface there; a return whose ray
// crosses the box and ends beyond it saw through it. A car stands where its returns are, and
// rays pass through where no car is: a track placed metres off its car (a cluster whose
// points lie at the wrong depth) has a see-through box. A car hidden behind another has
// neither (its rays end before it): no verdict.
#include "geometry/types.hpp"

namespace twistslam::objects {

struct BoxRayCounts {
  int inside = 0;   // returns inside the box
  int through = 0;  // returns beyond the box whose ray from the sensor crosses it
};

// Counts over scan_c (N, 3; camera frame, non-finite rows skipped) for the box at T_c_o of
// size (length, width, height) (x length, y down, z width; origin at its centre), shrunk by
// shrink_m on every side for the crossing test (the rays start at sensor_c, an approximation
// of the LiDAR's origin: the shrink absorbs that offset) and as it is for the inside count.
BoxRayCounts count_box_rays(const Points3& scan_c, const Mat4& T_c_o, const Vec3& size_lwh,
                            const Vec3& sensor_c, double shrink_m);

// The returns of scan_c that count_box_rays may count (inside or through) for a box of that
// size whose centre lies within reach_m of T_c_o's: enough to take the test again after the
// box moved by up to reach_m (a track's pose refined later), without the whole scan.
Points3 returns_near_box_rays(const Points3& scan_c, const Mat4& T_c_o, const Vec3& size_lwh,
                              const Vec3& sensor_c, double reach_m);

}  // namespace twistslam::objects
