#include <gtest/gtest.h>

#include "map/map.hpp"

using namespace twistslam;
using namespace twistslam::map;

namespace {
KeyFrame make_keyframe(int num_keypoints) {
  KeyFrame kf;
  kf.keypoints.uv.assign(num_keypoints, Vec2(10, 10));
  kf.keypoints.octave.assign(num_keypoints, 0);
  kf.keypoints.u_right.assign(num_keypoints, -1);
  kf.keypoints.depth.assign(num_keypoints, -1);
  kf.keypoints.descriptors.assign(num_keypoints, Descriptor{});
  kf.keypoints.label.assign(num_keypoints, -1);
  return kf;
}
}  // namespace

TEST(Map, ObservationsAreLinkedBothWays) {
  Map m;
  const int a = m.add_keyframe(make_keyframe(5)).id;
  const int b = m.add_keyframe(make_keyframe(5)).id;
  const int p = m.add_point(Vec3(1, 2, 3), Descriptor{}, a).id;
  m.add_observation(p, a, 2);
  m.add_observation(p, b, 4);
  EXPECT_EQ(m.keyframe(a).point_ids[2], p);
  EXPECT_EQ(m.point(p).observations.size(), 2u);
  // Re-linking the point to another keypoint of the same keyframe frees the old one.
  m.add_observation(p, b, 1);
  EXPECT_EQ(m.keyframe(b).point_ids[4], -1);
  EXPECT_EQ(m.keyframe(b).point_ids[1], p);
  m.erase_observation(p, a);
  EXPECT_EQ(m.keyframe(a).point_ids[2], -1);
  m.erase_point(p);
  EXPECT_FALSE(m.has_point(p));
  EXPECT_EQ(m.keyframe(b).point_ids[1], -1);
}

TEST(Map, CovisibilityCountsSharedPointsAndRanks) {
  Map m;
  const int a = m.add_keyframe(make_keyframe(10)).id;
  const int b = m.add_keyframe(make_keyframe(10)).id;
  const int c = m.add_keyframe(make_keyframe(10)).id;
  for (int i = 0; i < 6; ++i) {
    const int p = m.add_point(Vec3::Zero(), Descriptor{}, a).id;
    m.add_observation(p, a, i);
    m.add_observation(p, b, i);
    if (i < 2) m.add_observation(p, c, i);
  }
  m.update_covisibility(a);
  EXPECT_EQ(m.keyframe(a).covisibility.at(b), 6);
  EXPECT_EQ(m.keyframe(b).covisibility.at(a), 6);
  EXPECT_EQ(m.keyframe(a).covisibility.at(c), 2);
  EXPECT_EQ(m.covisible_keyframes(a, 5), (std::vector<int>{b, c}));
  EXPECT_EQ(m.covisible_keyframes(a, 5, 3), (std::vector<int>{b}));
  EXPECT_EQ(m.keyframe(a).num_tracked_points(), 6);
}

TEST(Map, DescriptorIsTheMostCentralObservation) {
  Map m;
  Descriptor zero{}, one{}, far{};
  one[0] = 1;
  far.fill(0xFF);
  std::vector<int> kfs;
  for (const Descriptor& d : {zero, one, far}) {
    KeyFrame kf = make_keyframe(1);
    kf.keypoints.descriptors[0] = d;
    kfs.push_back(m.add_keyframe(kf).id);
  }
  const int p = m.add_point(Vec3::Zero(), far, kfs[0]).id;
  for (int kf : kfs) m.add_observation(p, kf, 0);
  m.update_descriptor(p);
  EXPECT_LE(hamming(m.point(p).descriptor, zero), 1);
  EXPECT_EQ(hamming(zero, far), 256);
}
