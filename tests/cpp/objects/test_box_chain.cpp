// Boxes back in time from a new track's first box (objects/box_chain.hpp): a car's earlier
// boxes line up under a constant velocity, another car's do not, a gap or an ambiguity stops
// the chain.
#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "objects/box_chain.hpp"

using namespace twistslam;
using namespace twistslam::objects;

TEST(BoxChain, FollowsTheCarsEarlierBoxesAndSkipsOtherCars) {
  // the car drives 1.2 m a frame along x; each earlier frame also has a car 4 m to its side
  const Vec3 start(10, 1.6, 30), v(1.2, 0, 0);
  std::vector<std::vector<Vec3>> earlier;
  for (int s = 1; s <= 5; ++s)
    earlier.push_back({start + Vec3(0, 0, 4) - v * s, start - v * s + Vec3(0.1 * (s % 2), 0, -0.1)});
  const std::vector<int> chain = box_chain(start, earlier);
  ASSERT_EQ(chain.size(), 5u);
  for (int i : chain) EXPECT_EQ(i, 1);
}

TEST(BoxChain, AGapOrAnAmbiguityEndsTheChain) {
  const Vec3 start(0, 1.6, 20), v(0, 0, -0.8);
  // frame F-3 has no box near the prediction: the chain keeps F-1 and F-2 only
  std::vector<std::vector<Vec3>> earlier{{start - v}, {start - v * 2}, {Vec3(5, 1.6, 30)}, {start - v * 4}};
  EXPECT_EQ(box_chain(start, earlier).size(), 2u);
  // two boxes equally near the first step back: no guess
  std::vector<std::vector<Vec3>> twins{{start + Vec3(1, 0, 0), start + Vec3(-1, 0, 0)}};
  EXPECT_TRUE(box_chain(start, twins).empty());
  // a box beyond the first gate, a NaN centre, nothing at all
  EXPECT_TRUE(box_chain(start, {{start + Vec3(4, 0, 0)}}).empty());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(box_chain(start, {{Vec3(nan, 0, 0)}}).empty());
  EXPECT_TRUE(box_chain(start, {}).empty());
}
