// Duplicate tracks on one car (objects/duplicate_tracks.hpp): a track inside another's box
// footprint with fewer boxes is the duplicate, whichever of the two it is; cars side by side,
// another class, a track without a box frame and a negative margin hide nothing.
#include <gtest/gtest.h>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "objects/duplicate_tracks.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

constexpr int kCar = 26;

TrackFootprint car_at(const Vec3& centre, double yaw, int boxes, bool canonical = true, int class_id = kCar) {
  TrackFootprint t;
  t.T_w_o = geometry::make_pose(geometry::so3_exp(Vec3(0, yaw, 0)), centre);
  t.size = Vec3(4.5, 1.8, 1.5);
  t.canonical = canonical;
  t.class_id = class_id;
  t.boxes = boxes;
  return t;
}

}  // namespace

TEST(DuplicateTracks, TheTrackWithFewerBoxesInsideTheOthersFootprintIsTheDuplicate) {
  // a car heading along x (yaw 0.3); a second track 1.8 m ahead of its centre on its axis:
  // inside its 4.5 m length, 1.8 m off the centre (a z-offset that large would be outside)
  const Vec3 centre(2, 1.5, 30);
  const Vec3 along = geometry::so3_exp(Vec3(0, 0.3, 0)) * Vec3(1.8, 0, 0);
  const TrackFootprint car = car_at(centre, 0.3, 20);
  const TrackFootprint second = car_at(centre + along, 2.9, 2);  // its frame turned by ~150 deg
  EXPECT_EQ(duplicate_owners({car, second}, 0.3), (std::vector<int>{-1, 0}));
  // the same two, the second with more boxes: the first is the duplicate
  EXPECT_EQ(duplicate_owners({car_at(centre, 0.3, 2), car_at(centre + along, 2.9, 20)}, 0.3),
            (std::vector<int>{1, -1}));
  // equal boxes: the earlier one in the list stays
  EXPECT_EQ(duplicate_owners({car_at(centre, 0.3, 5), car_at(centre + along, 0.3, 5)}, 0.3),
            (std::vector<int>{-1, 0}));
  // a cluster track (no box frame) on the car is a duplicate too, but never hides the car
  EXPECT_EQ(duplicate_owners({car, car_at(centre + along, 0.0, 0, false)}, 0.3), (std::vector<int>{-1, 0}));
}

TEST(DuplicateTracks, CarsSideBySideAnotherClassOrANegativeMarginHideNothing) {
  const Vec3 centre(2, 1.5, 30);
  const Vec3 beside = geometry::so3_exp(Vec3(0, 0.3, 0)) * Vec3(0, 0, 2.0);  // parked next to it
  EXPECT_EQ(duplicate_owners({car_at(centre, 0.3, 20), car_at(centre + beside, 0.3, 3)}, 0.3),
            (std::vector<int>{-1, -1}));
  EXPECT_EQ(duplicate_owners({car_at(centre, 0.3, 20), car_at(centre, 0.3, 3, true, 24)}, 0.3),
            (std::vector<int>{-1, -1}));
  EXPECT_EQ(duplicate_owners({car_at(centre, 0.3, 20), car_at(centre, 0.3, 3)}, -1.0),
            (std::vector<int>{-1, -1}));
  // two cluster tracks without box frames: nothing to compare against
  EXPECT_EQ(duplicate_owners({car_at(centre, 0, 0, false), car_at(centre, 0, 0, false)}, 0.3),
            (std::vector<int>{-1, -1}));
}

TEST(DuplicateTracks, OfSeveralOwnersTheHighestRankedHoldsTheDuplicate) {
  const Vec3 centre(2, 1.5, 30);
  const Vec3 along = geometry::so3_exp(Vec3(0, 0.3, 0)) * Vec3(0.4, 0, 0);
  // three tracks on one car: 30, 20 and 10 boxes; both others are the first one's duplicates
  const std::vector<int> owner = duplicate_owners(
      {car_at(centre + along, 0.3, 20), car_at(centre - along, 0.3, 10), car_at(centre, 0.3, 30)}, 0.3);
  EXPECT_EQ(owner, (std::vector<int>{2, 2, -1}));
}

// A far car the classical detector read end-on in most frames (its prior length laid along the
// line of sight: axis rank 0) and from the side in a few (rank 1) got a track per axis: the
// one whose boxes know the axis better is the car, however many boxes the other has.
TEST(DuplicateTracks, BoxesThatKnowTheAxisBetterOutrankMoreBoxes) {
  const Vec3 centre(11, 1.5, 40);
  TrackFootprint end_on = car_at(centre, M_PI / 2, 12);  // length along the line of sight
  end_on.axis_rank = 0;
  TrackFootprint side = car_at(centre + Vec3(0.3, 0, -1.0), 0.0, 4);  // across it
  side.axis_rank = 1;
  EXPECT_EQ(duplicate_owners({end_on, side}, 0.3), (std::vector<int>{1, -1}));
  // equal ranks: the box count decides as before
  side.axis_rank = 0;
  EXPECT_EQ(duplicate_owners({end_on, side}, 0.3), (std::vector<int>{-1, 0}));
}
