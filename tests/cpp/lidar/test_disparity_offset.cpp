// Disparity offset: recovers a known offset under noise and gross mismatches, skips pairs
// without a LiDAR depth, follows the minimum-sample rule, refuses inconsistent input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "lidar/disparity_offset.hpp"

using namespace twistslam::lidar;

namespace {
constexpr double kFxB = 721.5377 * 0.5372;  // px m, KITTI colour pair
}

TEST(DisparityOffset, RecoversAKnownOffsetDespiteOutliers) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> range(5.0, 60.0);
  std::normal_distribution<double> noise(0.0, 0.2);
  std::vector<double> d, z;
  for (int i = 0; i < 400; ++i) {
    z.push_back(range(rng));
    d.push_back(kFxB / z.back() - 0.6 + noise(rng));  // stereo disparity 0.6 px too small
  }
  for (int i = 0; i < 40; ++i) {  // mismatches: 10 % wildly wrong
    z.push_back(range(rng));
    d.push_back(kFxB / z.back() + 15.0);
  }
  z.push_back(NAN);  // keypoints without LiDAR depth
  d.push_back(10.0);
  const DisparityOffset off = estimate_disparity_offset(d, z, kFxB);
  ASSERT_TRUE(off.valid);
  EXPECT_EQ(off.num_samples, 400);  // the 40 mismatches and the NaN are left out
  EXPECT_NEAR(off.offset_px, 0.6, 0.03);
  EXPECT_NEAR(off.mad_px, 0.2 * 0.6745, 0.03);  // MAD of a normal = 0.6745 sigma
}

TEST(DisparityOffset, ExactMedianOfFewSamples) {
  DisparityOffsetOptions opt;
  opt.min_samples = 4;
  // residuals fx b / z - d = 0.1, 0.2, 0.4, 1.0 -> median 0.3, |r - 0.3| = .2 .1 .1 .7 -> MAD .15
  const std::vector<double> z = {10, 20, 30, 40};
  std::vector<double> d;
  const double r[] = {0.1, 0.2, 0.4, 1.0};
  for (int i = 0; i < 4; ++i) d.push_back(kFxB / z[i] - r[i]);
  const DisparityOffset off = estimate_disparity_offset(d, z, kFxB, opt);
  ASSERT_TRUE(off.valid);
  EXPECT_NEAR(off.offset_px, 0.3, 1e-9);
  EXPECT_NEAR(off.mad_px, 0.15, 1e-9);
}

TEST(DisparityOffset, TooFewSamplesIsInvalidWithZeroOffset) {
  const std::vector<double> z(10, 20.0), d(10, kFxB / 20.0 - 0.5);
  const DisparityOffset off = estimate_disparity_offset(d, z, kFxB);  // min_samples = 30
  EXPECT_FALSE(off.valid);
  EXPECT_EQ(off.num_samples, 10);
  EXPECT_EQ(off.offset_px, 0.0);
  EXPECT_FALSE(estimate_disparity_offset({}, {}, kFxB).valid);
}

TEST(DisparityOffset, RefusesInconsistentInput) {
  EXPECT_THROW(estimate_disparity_offset({1.0}, {}, kFxB), std::invalid_argument);
  EXPECT_THROW(estimate_disparity_offset({1.0}, {2.0}, NAN), std::invalid_argument);
  EXPECT_THROW(estimate_disparity_offset({1.0}, {2.0}, -1.0), std::invalid_argument);
  DisparityOffsetOptions bad;
  bad.min_samples = 0;
  EXPECT_THROW(estimate_disparity_offset({1.0}, {2.0}, kFxB, bad), std::invalid_argument);
}
