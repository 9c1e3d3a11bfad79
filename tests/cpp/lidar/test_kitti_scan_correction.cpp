// KITTI vertical-angle correction against rotations computed by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "lidar/kitti_scan_correction.hpp"

using namespace twistslam;
using namespace twistslam::lidar;

namespace {
const double kA = kKittiVerticalAngleOffsetDeg * M_PI / 180.0;
}

TEST(KittiScanCorrection, RotatesEveryPointUpByTheOffset) {
  Points3 p(4, 3);
  p << 10, 0, 0,   // straight ahead: axis (p x z) = (0, -10, 0) -> -y
      0, 5, -1,    // to the left, below: axis (5, 0, 0) -> +x
      0, 0, 7,     // on the z axis: no horizontal direction, unchanged
      NAN, 1, 1;   // non-finite: unchanged
  const Points3 q = correct_kitti_scan(p);
  const double c = std::cos(kA), s = std::sin(kA);
  // Rodrigues with k perpendicular to p: q = p cos + (k x p) sin.
  EXPECT_NEAR((q.row(0) - Eigen::RowVector3d(10 * c, 0, 10 * s)).norm(), 0, 1e-12);
  // k = (1, 0, 0), k x p = (0, 1, 5) for p = (0, 5, -1).
  EXPECT_NEAR((q.row(1) - Eigen::RowVector3d(0, 5 * c + s, -c + 5 * s)).norm(), 0, 1e-12);
  EXPECT_EQ(q.row(2), p.row(2));
  EXPECT_TRUE(std::isnan(q(3, 0)));
}

TEST(KittiScanCorrection, KeepsRangeAndAzimuthAndRaisesElevation) {
  Points3 p(1, 3);
  p << -12.3, 4.5, -1.7;
  const Points3 q = correct_kitti_scan(p, 1.0);
  EXPECT_NEAR(q.row(0).norm(), p.row(0).norm(), 1e-12);
  EXPECT_NEAR(std::atan2(q(0, 1), q(0, 0)), std::atan2(p(0, 1), p(0, 0)), 1e-12);
  auto elevation = [](const Eigen::RowVector3d& x) { return std::atan2(x.z(), x.head<2>().norm()); };
  EXPECT_NEAR(elevation(q.row(0)) - elevation(p.row(0)), M_PI / 180.0, 1e-12);
  EXPECT_THROW(correct_kitti_scan(p, NAN), std::invalid_argument);
}
