#pragma once
// The uncertainty of a motion registered by GICP, as the e_reg term weighs it (paper eq. 9,
// W_reg): GICP's information H (Gauss-Newton J^T W J) of its left update delta of
// T_target_source = M_w^-1, world twist [v; w]. M_w moves by eps = -Ad_M delta, so
// Cov(eps) = Ad_M H^-1 Ad_M^T; restricted to the object's link (Pi), its translation seen at
// the object's centre (v - [c]x w) and its rotation. A far car's sparse scan is far less
// certain than a near car's dense one: one fixed W_reg cannot weigh both. A scan of one face
// is also far less certain along the face than across it: a car seen from behind pins its
// step along its length to ~1 cm and leaves the sideways step to ~10 cm.
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

// How the information's covariance becomes e_reg's: at the object's centre, the translation's
// standard deviations times scale_translation and the rotation's times scale_rotation (the
// errors measured against the information's), then each direction the link allows raised to
// at least the min_sigma (m/frame, rad/frame).
struct MotionCovarianceOptions {
  double scale_translation = 1.0;
  double scale_rotation = 1.0;
  double min_sigma_translation = 0.0;  // m/frame
  double min_sigma_rotation = 0.0;     // rad/frame
};

// The full covariance of eps (M_w -> exp(eps) M_w, world twist [v; w] at the world origin),
// restricted to the link (zero across it), scaled and floored as the options say: e_reg weighs
// each direction by what GICP saw along it instead of by the worst one.
Mat6 registered_motion_covariance(const Mat6& information, const Mat4& M_w, const Mat6& Pi,
                                  const Vec3& centre_w, const MotionCovarianceOptions& options);

}  // namespace twistslam::objects
