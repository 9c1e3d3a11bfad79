// LabelVotes: per-label vote counts, the majority label (first reached on ties), totals.
#include <gtest/gtest.h>

#include "objects/label_votes.hpp"

namespace twistslam::objects {
namespace {

TEST(LabelVotes, EmptyReturnsNoneAndZeroCounts) {
  LabelVotes v;
  EXPECT_EQ(v.best(), -1);
  EXPECT_EQ(v.best(42), 42);
  EXPECT_EQ(v.total(), 0);
  EXPECT_EQ(v.count(3), 0);
  EXPECT_TRUE(v.votes().empty());
}

TEST(LabelVotes, AccumulatesPerLabel) {
  LabelVotes v;
  v.add(26);
  v.add(7, 3);
  v.add(26, 4);
  v.add(0);
  EXPECT_EQ(v.count(26), 5);
  EXPECT_EQ(v.count(7), 3);
  EXPECT_EQ(v.count(0), 1);
  EXPECT_EQ(v.count(99), 0);
  EXPECT_EQ(v.total(), 9);
  ASSERT_EQ(v.votes().size(), 3u);  // one entry per distinct label, in first-seen order
  EXPECT_EQ(v.votes()[0].first, 26);
  EXPECT_EQ(v.votes()[1].first, 7);
  EXPECT_EQ(v.votes()[2].first, 0);
  EXPECT_EQ(v.best(), 26);
  EXPECT_EQ(v.best(-5), 26);  // `none` only without votes
}

TEST(LabelVotes, MajorityFollowsLaterVotes) {
  LabelVotes v;
  v.add(1, 2);
  v.add(2, 1);
  EXPECT_EQ(v.best(), 1);
  v.add(2, 2);
  EXPECT_EQ(v.best(), 2);
  EXPECT_EQ(v.total(), 5);
}

TEST(LabelVotes, TiesGoToTheLabelReachedFirst) {
  LabelVotes a;
  a.add(5, 2);
  a.add(9, 2);
  EXPECT_EQ(a.best(), 5);
  LabelVotes b;
  b.add(9, 2);
  b.add(5, 2);
  EXPECT_EQ(b.best(), 9);
  // the first-seen label wins even when the other reached the tie count by more steps
  LabelVotes c;
  c.add(4);
  c.add(8);
  c.add(8);
  c.add(4);
  EXPECT_EQ(c.best(), 4);
}

TEST(LabelVotes, NegativeAndZeroLabelsAreOrdinaryLabels) {
  LabelVotes v;
  v.add(-1, 3);
  v.add(0, 2);
  EXPECT_EQ(v.best(77), -1);
  EXPECT_EQ(v.count(-1), 3);
  EXPECT_EQ(v.count(0), 2);
}

}  // namespace
}  // namespace twistslam::objects
