// The registered motion's sigmas for e_reg (objects/motion_uncertainty.hpp): they are the
// inverse information's standard deviations, a rotation's uncertainty reaches the centre's
// translation through its lever arm, and the planar link leaves out roll and pitch that GICP
// could not see; the full covariance keeps each direction's own uncertainty, scaled and floored.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Eigenvalues>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
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

namespace {

// GICP's information of a car seen only from behind, 30 m ahead along z: its rear face pins
// the step along z (the car's length) to 5 mm, leaves the step along x (sideways) to 8 cm,
// the yaw to 0.2 deg; roll, pitch and height are what the planar link drops anyway.
Mat6 rear_face_information() {
  Vec6 sigma;
  sigma << 0.08, 0.05, 0.005, 0.02, 0.0035, 0.02;
  return sigma.cwiseInverse().cwiseAbs2().asDiagonal();
}

double variance_along(const Mat6& C_w, const Vec3& centre_w, const Vec6& direction_at_centre) {
  Mat6 A = Mat6::Identity();  // world-origin twist -> the twist seen at the centre
  A.topRightCorner<3, 3>() = -geometry::hat(centre_w);
  return direction_at_centre.dot(A * C_w * A.transpose() * direction_at_centre);
}

Vec6 unit(int k) { return Vec6::Unit(k); }

}  // namespace

TEST(MotionUncertainty, TheCovarianceKeepsWhatEachDirectionSaw) {
  // information about the car's centre: the twist at the origin is moved there first
  const Vec3 c(0, 0, 30);
  Mat6 to_centre = Mat6::Identity();  // [v; w] at the origin -> [v - c x w; w]
  to_centre.topRightCorner<3, 3>() = -geometry::hat(c);
  const Mat6 H = to_centre.transpose() * rear_face_information() * to_centre;
  const Mat6 Pi = geometry::projector_planar(Vec3(0, -1, 0));
  const Mat6 C = registered_motion_covariance(H, Mat4::Identity(), Pi, c, MotionCovarianceOptions());
  // along the length and sideways, as GICP saw them (the largest sigma would give both 8 cm)
  EXPECT_NEAR(std::sqrt(variance_along(C, c, unit(2))), 0.005, 1e-5);
  EXPECT_NEAR(std::sqrt(variance_along(C, c, unit(0))), 0.08, 1e-4);
  EXPECT_NEAR(std::sqrt(variance_along(C, c, unit(4))), 0.0035, 1e-6);
  // the largest of them is the sigma registered_motion_sigmas gives
  const MotionSigmas s = registered_motion_sigmas(H, Mat4::Identity(), Pi, c);
  EXPECT_NEAR(s.translation_m, 0.08, 1e-4);
  // across the link: nothing (height, roll, pitch)
  for (int k : {1, 3, 5}) EXPECT_NEAR(variance_along(C, c, unit(k)), 0.0, 1e-12) << k;
}

TEST(MotionUncertainty, ScalesAndFloorsActOnEachDirection) {
  const Vec3 c = Vec3::Zero();
  const Mat6 Pi = geometry::projector_planar(Vec3(0, -1, 0));
  MotionCovarianceOptions o;
  o.scale_translation = 0.5;
  o.scale_rotation = 2.0;
  o.min_sigma_translation = 0.01;
  o.min_sigma_rotation = 0.001;
  const Mat6 C = registered_motion_covariance(rear_face_information(), Mat4::Identity(), Pi, c, o);
  EXPECT_NEAR(std::sqrt(C(0, 0)), 0.04, 1e-5);    // 8 cm x 0.5
  EXPECT_NEAR(std::sqrt(C(2, 2)), 0.01, 1e-6);    // 5 mm x 0.5 = 2.5 mm, raised to the floor
  EXPECT_NEAR(std::sqrt(C(4, 4)), 0.007, 1e-6);   // 0.0035 x 2
  EXPECT_NEAR(C(1, 1), 0.0, 1e-12);               // the floor leaves the link's null alone
  EXPECT_NEAR(C(3, 3), 0.0, 1e-12);
  // positive semi-definite and symmetric
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(C);
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-15);
  EXPECT_LT((C - C.transpose()).norm(), 1e-15);
}
