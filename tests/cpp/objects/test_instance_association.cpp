// associate_instances: one-to-one greedy by shared matched points, then mask overlap for the
// clusters left without an instance; background ids (<= 0) never match.
#include <gtest/gtest.h>

#include <vector>

#include "objects/instance_association.hpp"

namespace twistslam::objects {
namespace {

ClusterInstanceEvidence shared(std::vector<std::pair<int, int>> votes) {
  ClusterInstanceEvidence e;
  for (auto [id, n] : votes) e.shared.add(id, n);
  return e;
}

void add_projected(ClusterInstanceEvidence* e, int num_projected,
                   std::vector<std::pair<int, int>> votes) {
  e->num_projected = num_projected;
  for (auto [id, n] : votes) e->projected.add(id, n);
}

InstanceAssociationOptions defaults() { return {}; }

TEST(InstanceAssociation, EmptyInput) {
  EXPECT_TRUE(associate_instances({}, defaults()).empty());
}

TEST(InstanceAssociation, SharedPointsPickTheInstanceWithMostMatches) {
  const auto out = associate_instances({shared({{3, 6}, {4, 20}, {0, 50}})}, defaults());
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], 4);
}

TEST(InstanceAssociation, SharedPointsThresholdIsInclusive) {
  InstanceAssociationOptions o;
  o.min_shared_points = 5;
  EXPECT_EQ(associate_instances({shared({{3, 5}})}, o)[0], 3);
  EXPECT_EQ(associate_instances({shared({{3, 4}})}, o)[0], -1);
  o.min_shared_points = 4;
  EXPECT_EQ(associate_instances({shared({{3, 4}})}, o)[0], 3);
}

TEST(InstanceAssociation, BackgroundIdsNeverMatch) {
  ClusterInstanceEvidence e = shared({{0, 100}, {-1, 100}});
  add_projected(&e, 10, {{0, 10}, {-2, 10}});
  EXPECT_EQ(associate_instances({e}, defaults())[0], -1);
}

TEST(InstanceAssociation, NoEvidenceGivesMinusOne) {
  const auto out = associate_instances({ClusterInstanceEvidence{}, shared({{2, 9}})}, defaults());
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], -1);
  EXPECT_EQ(out[1], 2);
}

TEST(InstanceAssociation, CompetingClustersMoreEvidenceWinsLoserGetsNone) {
  // both want instance 5; cluster 1 has more shared points
  const auto out = associate_instances({shared({{5, 8}}), shared({{5, 12}})}, defaults());
  EXPECT_EQ(out[0], -1);
  EXPECT_EQ(out[1], 5);
}

TEST(InstanceAssociation, CompetingClustersLoserFallsBackToNextCandidate) {
  const auto out =
      associate_instances({shared({{5, 8}, {6, 6}}), shared({{5, 12}})}, defaults());
  EXPECT_EQ(out[0], 6);
  EXPECT_EQ(out[1], 5);
}

TEST(InstanceAssociation, GreedyIsOneToOneAcrossManyClusters) {
  // cluster 0: 5 (10), 6 (9); cluster 1: 5 (11); cluster 2: 6 (20)
  const auto out = associate_instances(
      {shared({{5, 10}, {6, 9}}), shared({{5, 11}}), shared({{6, 20}})}, defaults());
  EXPECT_EQ(out[0], -1);  // both its candidates went to stronger clusters
  EXPECT_EQ(out[1], 5);
  EXPECT_EQ(out[2], 6);
}

TEST(InstanceAssociation, MaskOverlapFallbackForClustersWithoutSharedPoints) {
  ClusterInstanceEvidence e;
  add_projected(&e, 20, {{4, 12}, {0, 8}});  // 60 % inside instance 4
  EXPECT_EQ(associate_instances({e}, defaults())[0], 4);
  ClusterInstanceEvidence weak;
  add_projected(&weak, 20, {{4, 9}, {0, 11}});  // 45 % < 50 %
  EXPECT_EQ(associate_instances({weak}, defaults())[0], -1);
  ClusterInstanceEvidence exact;
  add_projected(&exact, 20, {{4, 10}});  // exactly 50 %: inclusive
  EXPECT_EQ(associate_instances({exact}, defaults())[0], 4);
}

TEST(InstanceAssociation, OverlapRelativeToAllProjectedPoints) {
  // 6 of 20 projected points inside: the votes alone would be 100 % of the voting points
  ClusterInstanceEvidence e;
  add_projected(&e, 20, {{4, 6}});
  EXPECT_EQ(associate_instances({e}, defaults())[0], -1);
  ClusterInstanceEvidence none;  // votes without any projected point: no overlap
  none.projected.add(4, 5);
  EXPECT_EQ(associate_instances({none}, defaults())[0], -1);
}

TEST(InstanceAssociation, SharedPointsTakePrecedenceOverOverlap) {
  // cluster 0 overlaps instance 3 fully but cluster 1 shares points with it: 1 gets 3, and
  // cluster 0 falls back to the instance it overlaps next.
  ClusterInstanceEvidence a;
  add_projected(&a, 10, {{3, 10}});
  ClusterInstanceEvidence b = shared({{3, 5}});
  auto out = associate_instances({a, b}, defaults());
  EXPECT_EQ(out[0], -1);
  EXPECT_EQ(out[1], 3);
  ClusterInstanceEvidence a2;
  add_projected(&a2, 10, {{3, 10}, {8, 6}});  // overlap counted per instance (can sum > 1)
  out = associate_instances({a2, b}, defaults());
  EXPECT_EQ(out[0], 8);
  EXPECT_EQ(out[1], 3);
}

TEST(InstanceAssociation, ClusterMatchedByPointsIsNotReassignedByOverlap) {
  ClusterInstanceEvidence e = shared({{2, 7}});
  add_projected(&e, 10, {{9, 10}});
  const auto out = associate_instances({e}, defaults());
  EXPECT_EQ(out[0], 2);
}

TEST(InstanceAssociation, OverlapCompetitionMoreOverlapWins) {
  ClusterInstanceEvidence a, b;
  add_projected(&a, 10, {{6, 6}});
  add_projected(&b, 10, {{6, 9}});
  const auto out = associate_instances({a, b}, defaults());
  EXPECT_EQ(out[0], -1);
  EXPECT_EQ(out[1], 6);
}

}  // namespace
}  // namespace twistslam::objects
