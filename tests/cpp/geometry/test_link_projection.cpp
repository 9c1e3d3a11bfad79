#include <gtest/gtest.h>

#include <stdexcept>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"

using namespace twistslam;
using namespace twistslam::geometry;

TEST(LinkProjection, PlanarKeepsInPlaneTranslationAndYaw) {
  const Vec3 n = Vec3(0.05, -1.0, 0.02).normalized();  // a slightly tilted road, y down
  const Mat6 Pi = projector_planar(n * 3.0);            // any scale of the normal
  EXPECT_LT((Pi * Pi - Pi).cwiseAbs().maxCoeff(), 1e-12);  // idempotent
  EXPECT_LT((Pi - Pi.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(projector_dof(Pi), 3);
  Vec6 xi;
  xi << 1.0, 2.0, 3.0, 0.1, 0.2, 0.3;
  const Vec6 p = Pi * xi;
  EXPECT_NEAR(p.head<3>().dot(n), 0.0, 1e-12);              // no motion off the plane
  EXPECT_NEAR(p.tail<3>().cross(n).norm(), 0.0, 1e-12);     // rotation only about n
  // Moving with the projected twist keeps a point on the plane at its height.
  const Vec3 on_plane = Vec3(2.0, 0.0, 5.0);
  const Mat4 T = se3_exp(p);
  const Vec3 moved = T.topLeftCorner<3, 3>() * on_plane + T.topRightCorner<3, 1>();
  EXPECT_NEAR((moved - on_plane).dot(n), 0.0, 1e-9);
}

TEST(LinkProjection, FreeIsIdentityAndBadNormalThrows) {
  EXPECT_EQ(projector_dof(projector_free()), 6);
  EXPECT_THROW(projector_planar(Vec3::Zero()), std::invalid_argument);
  EXPECT_THROW(projector_planar(Vec3(NAN, 0, 1)), std::invalid_argument);
}
