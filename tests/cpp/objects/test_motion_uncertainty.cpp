// The registered motion's sigmas for e_reg (objects/motion_uncertainty.hpp): they are the
// inverse information's standard deviations, a rotation's uncertainty reaches the centre's
// translation through its lever arm, and the planar link leaves out roll and pitch that GICP
// could not see.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "objects/motion_uncertainty.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

Mat6 diagonal_information(double sigma_t, const Vec3& sigma_w) {
  Vec6 d;
  d << Vec3::Constant(1 / (sigma_t * sigma_t)), sigma_w.cwiseInverse().cwiseAbs2();
  return d.asDiagonal();
}

}  // namespace

TEST(MotionUncertainty, SigmasAreTheInverseInformationsStandardDeviations) {
  const Mat6 H = diagonal_information(0.02, Vec3::Constant(0.004));
  const MotionSigmas s = registered_motion_sigmas(H, Mat4::Identity(), Mat6::Identity(), Vec3::Zero());
  EXPECT_NEAR(s.translation_m, 0.02, 1e-6);
  EXPECT_NEAR(s.rotation_rad, 0.004, 1e-8);
}

TEST(MotionUncertainty, RotationReachesTheCentreThroughItsLeverArm) {
  // twists are at the world origin; a car 40 m away moves by 40 m x its rotation's sigma more
  const Mat6 H = diagonal_information(0.01, Vec3::Constant(0.001));
  const MotionSigmas near = registered_motion_sigmas(H, Mat4::Identity(), Mat6::Identity(), Vec3::Zero());
  const MotionSigmas far = registered_motion_sigmas(H, Mat4::Identity(), Mat6::Identity(), Vec3(0, 0, 40));
  EXPECT_NEAR(far.translation_m, std::hypot(0.01, 0.04), 1e-4);
  EXPECT_NEAR(far.rotation_rad, near.rotation_rad, 1e-9);
}

TEST(MotionUncertainty, ThePlanarLinkLeavesOutWhatGicpCouldNotSee) {
  // a flat, sparse scan: roll and pitch nearly unseen (huge variance), yaw well seen
  const Mat6 H = diagonal_information(0.02, Vec3(10.0, 0.003, 10.0));
  const Mat6 free = Mat6::Identity();
  const Mat6 planar = geometry::projector_planar(Vec3(0, -1, 0));  // y down: up is -y
  const MotionSigmas s_free = registered_motion_sigmas(H, Mat4::Identity(), free, Vec3::Zero());
  const MotionSigmas s_planar = registered_motion_sigmas(H, Mat4::Identity(), planar, Vec3::Zero());
  EXPECT_GT(s_free.rotation_rad, 5.0);
  EXPECT_NEAR(s_planar.rotation_rad, 0.003, 1e-6);
  // a singular information (a direction never seen) is a huge sigma, not a NaN
  Mat6 singular = H;
  singular(4, 4) = 0;
  const MotionSigmas s = registered_motion_sigmas(singular, Mat4::Identity(), free, Vec3::Zero());
  EXPECT_TRUE(std::isfinite(s.rotation_rad));
  EXPECT_GT(s.rotation_rad, 1.0);
}
