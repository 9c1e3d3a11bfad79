// The mean offset between an object frame and its boxes (objects/box_offset.hpp): noisy
// samples of one offset average to it (near boxes weigh more), a box turned by pi and a far
// outlier are left out, and no usable sample gives no offset.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "objects/box_offset.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

Mat4 offset_pose(double yaw, const Vec3& t) {
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = geometry::so3_exp(Vec3(0, yaw, 0));
  T.topRightCorner<3, 1>() = t;
  return T;
}

double yaw_of(const Mat4& T) { return geometry::so3_log(T.topLeftCorner<3, 3>()).y(); }

}  // namespace

TEST(BoxOffset, NoisySamplesAverageToTheTrueOffsetNearBoxesWeighMore) {
  std::mt19937 rng(3);
  std::normal_distribution<double> unit(0, 1);
  const Vec3 t_true(0.15, -0.02, -0.3);
  const double yaw_true = 0.03;
  std::vector<BoxOffsetSample> samples;
  for (int k = 0; k < 60; ++k) {
    const double range = 5 + k;  // 5-65 m: noise in proportion
    const double sigma = 0.012 * range;
    samples.push_back({offset_pose(yaw_true + 0.004 * range * unit(rng),
                                   t_true + sigma * Vec3(unit(rng), 0.2 * unit(rng), unit(rng))),
                       1.0 / (range * range)});
  }
  const BoxOffset mean = mean_box_offset(samples);
  ASSERT_TRUE(mean.valid);
  EXPECT_LT((mean.T_o_box.topRightCorner<3, 1>() - t_true).norm(), 0.04);
  EXPECT_NEAR(yaw_of(mean.T_o_box), yaw_true, 0.012);
  EXPECT_TRUE(geometry::is_rigid_transform(mean.T_o_box, 1e-9));
  // weighting by range beats the plain mean, which the far boxes' scatter dominates
  std::vector<BoxOffsetSample> equal = samples;
  for (auto& s : equal) s.weight = 1;
  const BoxOffset unweighted = mean_box_offset(equal);
  EXPECT_LT((mean.T_o_box.topRightCorner<3, 1>() - t_true).norm(),
            (unweighted.T_o_box.topRightCorner<3, 1>() - t_true).norm());
}

TEST(BoxOffset, TurnedBoxesAndFarOutliersAreLeftOut) {
  std::vector<BoxOffsetSample> samples;
  for (int k = 0; k < 10; ++k) samples.push_back({offset_pose(0.02, Vec3(0.1, 0, 0)), 1.0});
  samples.push_back({offset_pose(M_PI - 0.01, Vec3(0.1, 0, 0)), 5.0});  // heading the other way
  samples.push_back({offset_pose(0.02, Vec3(3.0, 0, 0)), 2.0});          // a wrong association
  const BoxOffset mean = mean_box_offset(samples);
  ASSERT_TRUE(mean.valid);
  EXPECT_EQ(mean.inliers, 10);
  EXPECT_NEAR(mean.T_o_box(0, 3), 0.1, 1e-9);
  EXPECT_NEAR(yaw_of(mean.T_o_box), 0.02, 1e-9);
}

TEST(BoxOffset, NoUsableSampleGivesNoOffset) {
  EXPECT_FALSE(mean_box_offset({}).valid);
  Mat4 nan_pose = Mat4::Identity();
  nan_pose(0, 3) = NAN;
  EXPECT_FALSE(mean_box_offset({{nan_pose, 1.0}, {Mat4::Identity(), 0.0},
                                {Mat4::Identity(), NAN}}).valid);
}
