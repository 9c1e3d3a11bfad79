// Association costs of every metric, metric names, and the heading alignment helpers
// (turned_around, heading_flipped).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/box_overlap.hpp"
#include "geometry/se3.hpp"
#include "objects/association.hpp"
#include "scenes.hpp"

using namespace twistslam;
using namespace twistslam::objects;
using scenes::make_box;

namespace {

Eigen::MatrixXd cost_1x1(const geometry::Box3D& a, const geometry::Box3D& b, AssociationMetric m,
                         int class_a = 0, int class_b = 0) {
  return association_cost({a}, {class_a}, {b}, {class_b}, m);
}

const AssociationMetric kAll[] = {AssociationMetric::kGiou3d, AssociationMetric::kIouBev,
                                  AssociationMetric::kCentreDistance};

}  // namespace

TEST(Association, IdenticalBoxesCostNothing) {
  const auto a = make_box(2, 1, 15, 4, 1.6, 1.5, 0.3);
  for (auto m : kAll) EXPECT_NEAR(cost_1x1(a, a, m)(0, 0), 0.0, 1e-9) << to_string(m);
}

TEST(Association, Giou3dOfFarBoxesApproachesTwo) {
  const auto a = make_box(0, 1, 10, 4, 1.6, 1.5, 0.0);
  const auto near = make_box(6, 1, 10, 4, 1.6, 1.5, 0.0);
  const auto far = make_box(500, 1, 600, 4, 1.6, 1.5, 1.0);
  const double c_near = cost_1x1(a, near, AssociationMetric::kGiou3d)(0, 0);
  const double c_far = cost_1x1(a, far, AssociationMetric::kGiou3d)(0, 0);
  EXPECT_GT(c_near, 1.0);  // disjoint: GIoU < 0
  EXPECT_LT(c_near, c_far);
  EXPECT_GT(c_far, 1.99);
  EXPECT_LE(c_far, 2.0);
}

TEST(Association, IouBevAndCentreDistanceValues) {
  const auto a = make_box(0, 1, 10, 4, 2, 1.5, 0.0);
  const auto half = make_box(2, 1, 10, 4, 2, 1.5, 0.0);  // half overlap along the length
  EXPECT_NEAR(cost_1x1(a, half, AssociationMetric::kIouBev)(0, 0), 1.0 - 4.0 / 12.0, 1e-9);
  const auto apart = make_box(10, 1, 10, 4, 2, 1.5, 0.0);
  EXPECT_TRUE(std::isinf(cost_1x1(a, apart, AssociationMetric::kIouBev)(0, 0)));  // no overlap: never
  // IoU in bird view ignores the height: a box above the other still costs 0.
  const auto above = make_box(0, -5, 10, 4, 2, 1.5, 0.0);
  EXPECT_NEAR(cost_1x1(a, above, AssociationMetric::kIouBev)(0, 0), 0.0, 1e-12);
  EXPECT_GT(cost_1x1(a, above, AssociationMetric::kGiou3d)(0, 0), 1.0);
  const auto moved = make_box(3, -1, 14, 1, 1, 1, 2.0);
  EXPECT_NEAR(cost_1x1(a, moved, AssociationMetric::kCentreDistance)(0, 0),
              std::sqrt(9.0 + 4.0 + 16.0), 1e-12);
}

TEST(Association, DifferentClassesAreForbidden) {
  const auto a = make_box(0, 1, 10, 4, 2, 1.5, 0.0);
  for (auto m : kAll) {
    const double c = cost_1x1(a, a, m, 0, 1)(0, 0);
    EXPECT_TRUE(std::isinf(c) && c > 0) << to_string(m) << ": " << c;
  }
}

TEST(Association, MatrixIsTracksByDetections) {
  const std::vector<geometry::Box3D> tracks = {make_box(0, 1, 10, 4, 2, 1.5, 0), make_box(5, 1, 10, 4, 2, 1.5, 0)};
  const std::vector<geometry::Box3D> dets = {make_box(5, 1, 10, 4, 2, 1.5, 0), make_box(0, 1, 10, 4, 2, 1.5, 0),
                                             make_box(0, 1, 10, 4, 2, 1.5, 0)};
  const auto c = association_cost(tracks, {0, 0}, dets, {0, 0, 2}, AssociationMetric::kCentreDistance);
  ASSERT_EQ(c.rows(), 2);
  ASSERT_EQ(c.cols(), 3);
  EXPECT_NEAR(c(0, 0), 5.0, 1e-12);
  EXPECT_NEAR(c(0, 1), 0.0, 1e-12);
  EXPECT_NEAR(c(1, 0), 0.0, 1e-12);
  EXPECT_TRUE(std::isinf(c(0, 2)) && std::isinf(c(1, 2)));
  const auto empty = association_cost({}, {}, dets, {0, 0, 0}, AssociationMetric::kGiou3d);
  EXPECT_EQ(empty.rows(), 0);
  EXPECT_EQ(empty.cols(), 3);
  EXPECT_EQ(association_cost(tracks, {0, 0}, {}, {}, AssociationMetric::kIouBev).cols(), 0);
}

TEST(Association, GiouCostRanksDisjointBoxesByDistance) {
  const auto a = make_box(0, 1, 10, 4, 1.6, 1.5, 0.0);
  double previous = -1;
  for (double dx = 0; dx <= 20; dx += 0.5) {
    const double c = cost_1x1(a, make_box(dx, 1, 10, 4, 1.6, 1.5, 0.0), AssociationMetric::kGiou3d)(0, 0);
    EXPECT_GT(c, previous - 1e-12) << dx;
    EXPECT_GE(c, 0.0);
    EXPECT_LE(c, 2.0);
    previous = c;
  }
}

TEST(Association, MetricNamesRoundTrip) {
  for (auto m : kAll) EXPECT_EQ(association_metric_from_string(to_string(m)), m);
  EXPECT_STREQ(to_string(AssociationMetric::kGiou3d), "giou_3d");
  EXPECT_STREQ(to_string(AssociationMetric::kIouBev), "iou_bev");
  EXPECT_STREQ(to_string(AssociationMetric::kCentreDistance), "centre_distance");
}

TEST(Association, UnknownMetricThrowsNamingTheValidOnes) {
  for (const std::string bad : {"", "giou", "GIOU_3D", "center_distance", "iou_3d "}) {
    try {
      association_metric_from_string(bad);
      ADD_FAILURE() << "no exception for '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("giou_3d"), std::string::npos) << what;
      EXPECT_NE(what.find("iou_bev"), std::string::npos) << what;
      EXPECT_NE(what.find("centre_distance"), std::string::npos) << what;
    }
  }
}

TEST(Association, TurnedAroundIsTheSameBoxWithYawPlusPi) {
  const Mat4 T = scenes::pose_yaw(0.7, Vec3(3, 1, 12));
  const Mat4 U = turned_around(T);
  EXPECT_TRUE(geometry::is_rigid_transform(U, 1e-12));
  EXPECT_LT((U.block<3, 1>(0, 3) - T.block<3, 1>(0, 3)).norm(), 1e-15);  // same centre
  EXPECT_LT((U.block<3, 1>(0, 1) - T.block<3, 1>(0, 1)).norm(), 1e-15);  // same vertical axis
  EXPECT_LT((U - scenes::pose_yaw(0.7 + M_PI, Vec3(3, 1, 12))).norm(), 1e-12);
  EXPECT_LT((turned_around(U) - T).norm(), 1e-15);
  // A tilted (non-upright) pose turns about its own y axis: T * rot_y(pi).
  const Mat4 tilted = geometry::se3_exp((Vec6() << 1, 2, 3, 0.3, -0.2, 0.5).finished());
  const Mat4 expected = tilted * geometry::make_pose(scenes::rot_y(M_PI), Vec3::Zero());
  EXPECT_LT((turned_around(tilted) - expected).norm(), 1e-12);
  // The turned box covers the same volume.
  const auto box = make_box(3, 1, 12, 4, 1.6, 1.5, 0.7);
  auto turned = box;
  turned.yaw = scenes::yaw_of(U);
  EXPECT_NEAR(geometry::iou_3d(box, turned), 1.0, 1e-9);
}

TEST(Association, HeadingFlippedBeyondNinetyDegrees) {
  const Vec3 p(1, 1, 20);
  const Mat4 ref = scenes::pose_yaw(0.4, p);
  const double deg = M_PI / 180;
  for (double d : {0.0, 10 * deg, -45 * deg, 80 * deg, -89 * deg}) {
    EXPECT_FALSE(heading_flipped(scenes::pose_yaw(0.4 + d, p), ref)) << d / deg;
    EXPECT_FALSE(heading_flipped(ref, scenes::pose_yaw(0.4 + d, p))) << d / deg;
  }
  for (double d : {M_PI, 91 * deg, -100 * deg, 170 * deg, -179 * deg}) {
    EXPECT_TRUE(heading_flipped(scenes::pose_yaw(0.4 + d, p), ref)) << d / deg;
    EXPECT_TRUE(heading_flipped(ref, scenes::pose_yaw(0.4 + d, p))) << d / deg;
  }
  // The translation plays no part; a turned-around pose is always flipped.
  EXPECT_FALSE(heading_flipped(scenes::pose_yaw(0.4, Vec3(50, 0, -3)), ref));
  EXPECT_TRUE(heading_flipped(turned_around(ref), ref));
  EXPECT_FALSE(heading_flipped(turned_around(turned_around(ref)), ref));
}

TEST(Association, QuarterTurnedBeyondFortyFiveDegreesModuloPi) {
  const Vec3 p(1, 1, 20);
  const Mat4 ref = scenes::pose_yaw(0.4, p);
  const double deg = M_PI / 180;
  for (double d : {0.0, 30 * deg, -44 * deg, M_PI, 150 * deg, -170 * deg})
    EXPECT_FALSE(quarter_turned(scenes::pose_yaw(0.4 + d, p), ref)) << d / deg;
  for (double d : {90 * deg, -90 * deg, 46 * deg, -60 * deg, 120 * deg, -134 * deg})
    EXPECT_TRUE(quarter_turned(scenes::pose_yaw(0.4 + d, p), ref)) << d / deg;
  // The translation plays no part; a turned-around box is not quarter-turned.
  EXPECT_FALSE(quarter_turned(scenes::pose_yaw(0.4, Vec3(50, 0, -3)), ref));
  EXPECT_FALSE(quarter_turned(turned_around(ref), ref));
}
