// Half-occluded keypoints (features/right_occlusion.hpp): instance images and matches built by
// hand with known disparities, so the hidden strip left of a nearer object's left edge is known
// exactly: a point at column u with disparity d is hidden by an object whose left edge is at a
// with disparity D when a - u < D - d.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "features/right_occlusion.hpp"

using namespace twistslam::features;

namespace {

constexpr float kBaselineFx = 389.0f;  // KITTI's fx b (px m): depth = kBaselineFx / disparity

struct Scene {
  cv::Mat instances = cv::Mat(60, 400, CV_32SC1, cv::Scalar(0));
  Keypoints left;
  StereoMatches matches;
  std::vector<int> all;

  void fill(int id, int first_column, int end_column) {
    instances(cv::Range(10, 50), cv::Range(first_column, end_column)).setTo(id);
  }
  int add(float x, float y, float disparity) {
    cv::KeyPoint k;
    k.pt = {x, y};
    left.keypoints.push_back(k);
    matches.u_right.push_back(disparity > 0 ? x - disparity : -1.0f);
    matches.depth.push_back(disparity > 0 ? kBaselineFx / disparity : -1.0f);
    all.push_back(static_cast<int>(left.size()) - 1);
    return all.back();
  }
  // n matched keypoints spread over [first_column, end_column) at one disparity
  void add_many(int n, int first_column, int end_column, float disparity) {
    for (int j = 0; j < n; ++j)
      add(first_column + (end_column - first_column - 1) * (j + 0.5f) / n, 20.0f + j % 20, disparity);
  }
  bool has_depth(int i) const { return matches.depth[i] > 0; }
};

// A far car (id 1, columns 100-199, six matches at 10 px) left of a nearer one (id 2, columns
// 200-299, `near_matches` matches at 30 px), which hides the 20 px left of its edge.
Scene far_beside_near(int near_matches) {
  Scene s;
  s.fill(1, 100, 200);
  s.fill(2, 200, 300);
  s.add_many(6, 110, 150, 10.0f);
  s.add_many(near_matches, 210, 290, 30.0f);
  return s;
}

}  // namespace

TEST(RightOcclusion, DropsExactlyTheStripLeftOfANearerObject) {
  Scene s;
  s.fill(1, 100, 200);  // far car: disparity 10 px (38.9 m)
  s.fill(2, 200, 300);  // nearer car to its right: 30 px (13 m), hides 20 px of the far one
  s.fill(4, 350, 390);  // a still nearer car farther right: the walks reach 39.5 px
  s.add_many(6, 110, 150, 10.0f);
  s.add_many(6, 210, 290, 30.0f);
  s.add_many(6, 352, 388, 50.0f);
  const int deep = s.add(195.0f, 30.0f, 10.0f);     // 5 px from the edge: hidden
  const int inner = s.add(181.0f, 30.0f, 10.0f);    // 19 px: hidden (20 > 19 + 0.5)
  const int margin = s.add(180.3f, 30.0f, 10.0f);   // 19.7 px: within the margin, kept
  const int border = s.add(179.6f, 30.0f, 10.0f);   // 20.4 px: kept
  const int outside = s.add(170.0f, 30.0f, 10.0f);  // 30 px: the right camera sees it
  const int no_depth = s.add(196.0f, 31.0f, -1.0f);
  const RightOcclusionReport r = drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, &s.matches);
  EXPECT_EQ(r.num_instances, 3);
  EXPECT_EQ(r.num_dropped, 2);
  EXPECT_FALSE(s.has_depth(deep));
  EXPECT_FALSE(s.has_depth(inner));
  EXPECT_TRUE(s.has_depth(margin));
  EXPECT_TRUE(s.has_depth(border));
  EXPECT_TRUE(s.has_depth(outside));
  EXPECT_EQ(s.matches.u_right[deep], -1.0f);
  EXPECT_EQ(s.matches.depth[no_depth], -1.0f);
  for (int i = 0; i < 18; ++i) EXPECT_TRUE(s.has_depth(i)) << i;  // the instances' own points
}

TEST(RightOcclusion, ANearerObjectToTheLeftOrAFartherOneHidesNothing) {
  Scene s;
  s.fill(2, 50, 150);   // nearer car to the far one's left: the right camera sees past its right side
  s.fill(1, 150, 250);  // far car
  s.fill(3, 250, 300);  // a farther car to the far one's right
  s.add_many(6, 60, 140, 30.0f);
  s.add_many(6, 160, 240, 10.0f);
  s.add_many(6, 255, 295, 5.0f);
  const int beside_nearer = s.add(152.0f, 30.0f, 10.0f);
  const int beside_farther = s.add(248.0f, 30.0f, 10.0f);
  const RightOcclusionReport r = drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, &s.matches);
  EXPECT_EQ(r.num_instances, 3);
  EXPECT_EQ(r.num_dropped, 0);
  EXPECT_TRUE(s.has_depth(beside_nearer));
  EXPECT_TRUE(s.has_depth(beside_farther));
}

TEST(RightOcclusion, AFartherObjectBetweenDoesNotShieldTheNearerEdge) {
  Scene s;
  s.fill(1, 100, 190);  // far car, 10 px
  s.fill(3, 190, 196);  // a sliver of a still farther car, 8 px
  s.fill(2, 196, 300);  // the nearer car, 30 px
  s.add_many(6, 110, 150, 10.0f);
  s.add_many(6, 190, 196, 8.0f);
  s.add_many(6, 210, 290, 30.0f);
  const int hidden = s.add(185.0f, 30.0f, 10.0f);  // 11 px from the nearer edge, 5 from the sliver
  const RightOcclusionReport r = drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, &s.matches);
  EXPECT_FALSE(s.has_depth(hidden));
  // the sliver itself lies in the nearer car's hidden strip too (196 - 190.4 < 30 - 8)
  for (int i = 6; i < 12; ++i) EXPECT_FALSE(s.has_depth(i)) << i;
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(s.has_depth(i)) << i;
  EXPECT_EQ(r.num_dropped, 7);
}

TEST(RightOcclusion, AnInstanceWithTooFewMatchesJudgesNothing) {
  Scene s = far_beside_near(4);  // four matches: below min_keypoints 5
  const int near_edge = s.add(195.0f, 30.0f, 10.0f);
  RightOcclusionReport r = drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, &s.matches);
  EXPECT_EQ(r.num_instances, 1);
  EXPECT_EQ(r.num_dropped, 0);
  EXPECT_TRUE(s.has_depth(near_edge));
  r = drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 4, &s.matches);
  EXPECT_EQ(r.num_dropped, 1);
  EXPECT_FALSE(s.has_depth(near_edge));
}

TEST(RightOcclusion, TheMedianDisparityIgnoresAFewWrongMatches) {
  Scene s = far_beside_near(5);
  s.add_many(2, 210, 290, 3.0f);  // two matches far too far on the nearer car
  const int hidden = s.add(185.0f, 30.0f, 10.0f);
  const RightOcclusionReport r = drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, &s.matches);
  EXPECT_FALSE(s.has_depth(hidden));
  EXPECT_EQ(r.num_dropped, 1);
}

TEST(RightOcclusion, OnlyTheKeypointsOfWhichAreJudgedAndCounted) {
  Scene s = far_beside_near(6);
  const int hidden = s.add(195.0f, 30.0f, 10.0f);
  std::vector<int> which(s.all.begin(), s.all.end() - 1);  // all but the hidden one
  RightOcclusionReport r = drop_matches_occluded_in_right(s.left, which, s.instances, 0.5f, 5, &s.matches);
  EXPECT_EQ(r.num_dropped, 0);
  EXPECT_TRUE(s.has_depth(hidden));
  which.resize(6);  // the far car's own points only: the nearer car has no disparity then
  which.push_back(hidden);
  r = drop_matches_occluded_in_right(s.left, which, s.instances, 0.5f, 5, &s.matches);
  EXPECT_EQ(r.num_instances, 1);
  EXPECT_EQ(r.num_dropped, 0);
}

TEST(RightOcclusion, BadInputIsRefused) {
  Scene s;
  s.fill(1, 100, 200);
  s.add_many(6, 110, 150, 10.0f);
  EXPECT_THROW(drop_matches_occluded_in_right(s.left, s.all, cv::Mat(), 0.5f, 5, &s.matches), std::invalid_argument);
  cv::Mat as_float;
  s.instances.convertTo(as_float, CV_32F);
  EXPECT_THROW(drop_matches_occluded_in_right(s.left, s.all, as_float, 0.5f, 5, &s.matches), std::invalid_argument);
  EXPECT_THROW(drop_matches_occluded_in_right(s.left, s.all, s.instances, -1.0f, 5, &s.matches), std::invalid_argument);
  EXPECT_THROW(drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 0, &s.matches), std::invalid_argument);
  EXPECT_THROW(drop_matches_occluded_in_right(s.left, {0, 6}, s.instances, 0.5f, 5, &s.matches), std::invalid_argument);
  EXPECT_THROW(drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, nullptr), std::invalid_argument);
  StereoMatches short_matches = s.matches;
  short_matches.depth.pop_back();
  EXPECT_THROW(drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, &short_matches), std::invalid_argument);
  // keypoints off the image are skipped, not read out of bounds
  s.add(-5.0f, 30.0f, 10.0f);
  s.add(1000.0f, 30.0f, 10.0f);
  s.add(150.0f, 400.0f, 10.0f);
  EXPECT_NO_THROW(drop_matches_occluded_in_right(s.left, s.all, s.instances, 0.5f, 5, &s.matches));
}
