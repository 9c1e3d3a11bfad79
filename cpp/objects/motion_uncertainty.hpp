#pragma once
// The uncertainty of a motion registered by GICP, as the e_reg term weighs it (paper eq. 9,
// W_reg): GICP's information H (Gauss-Newton J^T W J) of its left update delta of
// T_target_source = M_w^-1, world twist [v; w]. M_w moves by eps = -Ad_M delta, so
// Cov(eps) = Ad_M H^-1 Ad_M^T; restricted to the object's link (Pi), its translation seen at
// the object's centre (v - [c]x w) and its rotation. A far car's sparse scan is far less
// certain than a near car's dense one: one fixed W_reg cannot weigh both.
#include "geometry/types.hpp"

namespace twistslam::objects {

struct MotionSigmas {
  double translation_m = 0;  // the largest standard deviation of the centre's motion
  double rotation_rad = 0;   // the largest standard deviation of the rotation in the link
};

// Marginal standard deviations of M_w from GICP's information (a direction GICP never saw,
// e.g. along a flat scan, gets a huge sigma, never a NaN).
MotionSigmas registered_motion_sigmas(const Mat6& information, const Mat4& M_w, const Mat6& Pi,
                                      const Vec3& centre_w);

}  // namespace twistslam::objects
