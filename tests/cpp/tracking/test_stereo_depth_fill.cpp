// Depths for a vehicle mask's keypoints without stereo (tracking/stereo_depth_fill.hpp): each
// takes its nearest stereo keypoint's depth; too few or too far stereo depths give none.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "tracking/stereo_depth_fill.hpp"

using namespace twistslam;
using tracking::nearest_stereo_depths;
using tracking::StereoDepthFillOptions;

namespace {

TEST(StereoDepthFill, EachMonoKeypointTakesItsNearestStereoDepth) {
  // a car seen at an angle: its rear (left, 15 m) and its side (right, 16-18 m)
  const std::vector<Vec2> stereo_uv{{100, 50}, {110, 60}, {200, 55}, {260, 52}};
  const std::vector<double> stereo_depth{15.0, 15.2, 16.5, 18.0};
  const std::vector<Vec2> mono_uv{{104, 55}, {195, 70}, {270, 40}, {150, 58}};
  const auto depth = nearest_stereo_depths(stereo_uv, stereo_depth, mono_uv, {});
  ASSERT_EQ(depth.size(), 4u);
  EXPECT_DOUBLE_EQ(depth[0], 15.0);
  EXPECT_DOUBLE_EQ(depth[1], 16.5);
  EXPECT_DOUBLE_EQ(depth[2], 18.0);
  EXPECT_DOUBLE_EQ(depth[3], 15.2);  // 40.0 px from (110, 60), 50.1 px from (200, 55)
}

TEST(StereoDepthFill, TooFewOrTooFarStereoDepthsGiveNone) {
  const std::vector<Vec2> mono_uv{{10, 10}};
  const std::vector<Vec2> two_uv{{0, 0}, {20, 20}};
  // two depths: under the 3 the default asks for
  EXPECT_TRUE(nearest_stereo_depths(two_uv, {12.0, 12.5}, mono_uv, {}).empty());
  StereoDepthFillOptions two;
  two.min_stereo_points = 2;
  EXPECT_EQ(nearest_stereo_depths(two_uv, {12.0, 12.5}, mono_uv, two).size(), 1u);
  // a far car: its median depth (40 m) beyond the 30 m limit
  const std::vector<Vec2> three_uv{{0, 0}, {20, 20}, {30, 5}};
  EXPECT_TRUE(nearest_stereo_depths(three_uv, {39.0, 40.0, 42.0}, mono_uv, {}).empty());
  EXPECT_EQ(nearest_stereo_depths(three_uv, {19.0, 20.0, 22.0}, mono_uv, {}).size(), 1u);
  // no keypoint to fill: nothing to return, whatever the stereo points
  EXPECT_TRUE(nearest_stereo_depths(three_uv, {19.0, 20.0, 22.0}, {}, {}).empty());
}

TEST(StereoDepthFill, StereoDepthsOnATinyShareOfTheKeypointsFillNothing) {
  // 3 stereo depths on a mask of 33 keypoints (9 %): the stereo failed over most of the car
  const std::vector<Vec2> stereo_uv{{0, 0}, {20, 0}, {40, 0}};
  const std::vector<double> stereo_depth{8.0, 8.5, 9.0};
  std::vector<Vec2> many, some;
  for (int i = 0; i < 30; ++i) many.emplace_back(2.0 * i, 10.0);
  for (int i = 0; i < 10; ++i) some.emplace_back(4.0 * i, 10.0);
  EXPECT_TRUE(nearest_stereo_depths(stereo_uv, stereo_depth, many, {}).empty());
  EXPECT_EQ(nearest_stereo_depths(stereo_uv, stereo_depth, some, {}).size(), 10u);  // 23 %
  StereoDepthFillOptions any_share;
  any_share.min_stereo_share = 0.0;
  EXPECT_EQ(nearest_stereo_depths(stereo_uv, stereo_depth, many, any_share).size(), 30u);
}

TEST(StereoDepthFill, NonFiniteEntriesAreSkippedAndSizesChecked) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Vec2> stereo_uv{{0, 0}, {10, 0}, {20, 0}, {30, 0}, {nan, 0}};
  // the NaN and negative depths do not count: 2 valid depths are too few
  EXPECT_TRUE(nearest_stereo_depths(stereo_uv, {10.0, nan, -1.0, 11.0, 12.0}, {{1, 1}}, {}).empty());
  // with a third valid one they fill; the keypoint nearest to the NaN-depth one takes the
  // next valid neighbour's depth, a NaN pixel position gets NaN
  const auto depth =
      nearest_stereo_depths(stereo_uv, {10.0, nan, 10.5, 11.0, 12.0}, {{11, 0}, {nan, 3}}, {});
  ASSERT_EQ(depth.size(), 2u);
  EXPECT_TRUE(depth[0] == 10.0 || depth[0] == 10.5);
  EXPECT_TRUE(std::isnan(depth[1]));
  EXPECT_THROW(nearest_stereo_depths(stereo_uv, {10.0, 11.0}, {{1, 1}}, {}), std::invalid_argument);
}

}  // namespace
