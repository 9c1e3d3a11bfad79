#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "geometry/stereo_camera.hpp"

using namespace twistslam;
using namespace twistslam::geometry;

namespace {
// P2 / P3 of KITTI tracking sequence 0001 (training/calib/0001.txt).
Mat34 kitti_p2() {
  Mat34 P;
  P << 721.5377, 0, 609.5593, 44.85728, 0, 721.5377, 172.854, 0.2163791, 0, 0, 1, 0.002745884;
  return P;
}
Mat34 kitti_p3() {
  Mat34 P;
  P << 721.5377, 0, 609.5593, -339.5242, 0, 721.5377, 172.854, 2.199936, 0, 0, 1, 0.002729905;
  return P;
}
}  // namespace

TEST(StereoCamera, KittiBaselineAndOffsets) {
  const auto cam = StereoCamera::from_kitti(kitti_p2(), kitti_p3(), 1242, 375);
  EXPECT_NEAR(cam.baseline, (44.85728 + 339.5242) / 721.5377, 2e-5);  // ~0.533 m
  EXPECT_NEAR(cam.t_left.x(), 0.0596, 1e-3);  // camera 2 sits ~6 cm from the reference
}

TEST(StereoCamera, ProjectionMatchesP2IncludingFourthColumn) {
  const auto cam = StereoCamera::from_kitti(kitti_p2(), kitti_p3(), 1242, 375);
  const Vec3 X(2.0, 1.0, 15.0);
  const Vec3 p = kitti_p2() * X.homogeneous();
  EXPECT_LT((cam.project(X) - p.hnormalized()).norm(), 1e-9);
  const Vec3 q = kitti_p3() * X.homogeneous();
  EXPECT_LT((cam.project_right(X) - q.hnormalized()).norm(), 1e-9);
}

TEST(StereoCamera, TriangulateInvertsProjection) {
  const auto cam = StereoCamera::from_kitti(kitti_p2(), kitti_p3(), 1242, 375);
  for (const Vec3& X : {Vec3(2.0, 1.0, 15.0), Vec3(-8.0, -2.0, 40.0), Vec3(0.5, 1.6, 4.0)}) {
    const Vec2 l = cam.project(X), r = cam.project_right(X);
    const Vec3 back = cam.triangulate(l, l.x() - r.x());
    // The two cameras' z offsets differ by 16 um, which bounds the error.
    EXPECT_LT((back - X).norm(), 1e-4 * X.z()) << X.transpose();
    EXPECT_LT((cam.backproject(l, X.z() + cam.t_left.z()) - X).norm(), 1e-9);
  }
  EXPECT_TRUE(std::isnan(cam.triangulate(Vec2(100, 100), 0.0).x()));
}

TEST(StereoCamera, RejectsUnrectifiedPair) {
  Mat34 P3 = kitti_p3();
  P3(0, 0) += 5.0;
  EXPECT_THROW(StereoCamera::from_kitti(kitti_p2(), P3, 1242, 375), std::invalid_argument);
  EXPECT_THROW(StereoCamera::from_kitti(kitti_p3(), kitti_p2(), 1242, 375), std::invalid_argument);
}

TEST(StereoCamera, DisparityOffsetMovesTheRightPrincipalPoint) {
  const auto cam = StereoCamera::from_kitti(kitti_p2(), kitti_p3(), 1242, 375, 0.6);
  EXPECT_DOUBLE_EQ(cam.disparity_offset, 0.6);
  const auto plain = StereoCamera::from_kitti(kitti_p2(), kitti_p3(), 1242, 375);
  const Vec3 X(-3.0, 1.2, 25.0);
  // the right image sees every point 0.6 px further right, the left image is unchanged
  EXPECT_NEAR(cam.project_right(X).x() - plain.project_right(X).x(), 0.6, 1e-12);
  EXPECT_LT((cam.project(X) - plain.project(X)).norm(), 1e-12);
  // triangulation from the measured (shortened) disparity recovers the point
  const Vec2 l = cam.project(X), r = cam.project_right(X);
  EXPECT_LT((cam.triangulate(l, l.x() - r.x()) - X).norm(), 1e-4 * X.z());
  EXPECT_NEAR(cam.depth_from_disparity(-0.6), -1.0, 0);  // no depth at d + offset <= 0
  EXPECT_THROW(StereoCamera::from_kitti(kitti_p2(), kitti_p3(), 1242, 375, 20.0),
               std::invalid_argument);
  EXPECT_THROW(StereoCamera::from_kitti(kitti_p2(), kitti_p3(), 1242, 375, std::nan("")),
               std::invalid_argument);
}
