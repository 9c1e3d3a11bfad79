// A track's size (objects/object_track.hpp, update_size): the per-dimension median of its
// boxes, the length from the boxes that measured it when some did, and the boxes whose length
// is the detector's prior moved along their open end to that length (their seen face stays);
// boxes that are their points' extent take an upper quantile and keep their near end.
#include <gtest/gtest.h>

#include <vector>

#include "objects/object_track.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

// a detected row of a car heading along w's x axis, its box centre at x_centre
TrackFrame box_row(int frame, double x_centre, double length, int open_end) {
  TrackFrame f;
  f.frame = frame;
  f.detection_index = 0;
  f.T_w_o_detected.topRightCorner<3, 1>() = Vec3(x_centre, 0, 20);
  f.detected_size = Vec3(length, 1.7, 1.5);
  f.open_end_w = open_end * Vec3::UnitX();
  return f;
}

}  // namespace

TEST(TrackSize, MeasuredLengthsGiveTheLengthAndMovePriorBoxesFromTheirSeenFace) {
  // a 4.8 m car centred at x = 10: three rear-only boxes (seen face at x = 7.6, the prior's
  // 4.0 m laid towards +x) and two L-shaped boxes measuring 4.75 and 4.85 m
  const double prior = 4.0, rear_face = 7.6;
  ObjectTrack track;
  for (int k = 0; k < 3; ++k) track.frames.push_back(box_row(k, rear_face + 0.5 * prior, prior, +1));
  track.frames.push_back(box_row(3, 10.0, 4.75, 0));
  track.frames.push_back(box_row(4, 10.0, 4.85, 0));
  track.update_size();
  EXPECT_NEAR(track.size[0], 4.8, 1e-9);  // not the median of all five (4.0)
  for (const TrackFrame& f : track.frames)
    EXPECT_NEAR(f.T_w_o_detected(0, 3), 10.0, 1e-9) << "frame " << f.frame;
  // a second update moves nothing further (the shift is absolute, not added twice)
  track.update_size();
  EXPECT_NEAR(track.frames[0].T_w_o_detected(0, 3), 10.0, 1e-9);
}

TEST(TrackSize, OnlyPriorBoxesKeepThePriorAndTheirCentres) {
  // a car seen only from behind: nothing measured its length, nothing moves; an open end
  // towards -x (the car faces the sensor) moves the other way once a length is known
  ObjectTrack track;
  track.frames.push_back(box_row(0, 5.0, 4.0, -1));
  track.frames.push_back(box_row(1, 5.1, 4.0, -1));
  track.update_size();
  EXPECT_NEAR(track.size[0], 4.0, 1e-9);
  EXPECT_NEAR(track.frames[0].T_w_o_detected(0, 3), 5.0, 1e-9);
  track.frames.push_back(box_row(2, 5.0, 3.6, 0));  // a short car: the prior was 0.4 m too long
  track.update_size();
  EXPECT_NEAR(track.size[0], 3.6, 1e-9);
  EXPECT_NEAR(track.frames[0].T_w_o_detected(0, 3), 5.2, 1e-9);  // towards the seen face (+x)
  EXPECT_NEAR(track.size[1], 1.7, 1e-9);  // width and height from every box
}

TEST(TrackSize, PointExtentsGiveAnUpperQuantileAndKeepTheirNearEnd) {
  // a car heading along +x, seen from -x: its boxes are the extents of its points, their near
  // (rear) face at x = 7.7 measured, their far end short by what the side's returns missed
  const double rear_face = 7.7;
  const std::vector<double> lengths{4.1, 4.55, 4.3, 4.6, 4.5};
  ObjectTrack track;
  for (size_t k = 0; k < lengths.size(); ++k) {
    TrackFrame f = box_row(static_cast<int>(k), rear_face + 0.5 * lengths[k], lengths[k], 0);
    f.far_end_w = Vec3::UnitX();
    track.frames.push_back(f);
  }
  track.update_size(0.5);  // the paper's median
  EXPECT_NEAR(track.size[0], 4.5, 1e-9);
  track.update_size(0.9);  // sorted 4.1 4.3 4.5 4.55 4.6: 0.9 lies at 3.6 -> 4.55 + 0.6 x 0.05
  EXPECT_NEAR(track.size[0], 4.58, 1e-9);
  for (const TrackFrame& f : track.frames)  // every box now spans 7.7 .. 12.28
    EXPECT_NEAR(f.T_w_o_detected(0, 3), rear_face + 0.5 * 4.58, 1e-9) << "frame " << f.frame;
  EXPECT_NEAR(track.size[1], 1.7, 1e-9);  // width and height: the median still
}

TEST(TrackSize, EstimatedLengthsAmongPointExtentsKeepTheMedian) {
  // a detector's estimate is no lower bound: with one among the measured boxes, the median
  ObjectTrack track;
  track.frames.push_back(box_row(0, 10.0, 4.0, 0));
  track.frames.push_back(box_row(1, 10.0, 4.4, 0));
  track.frames.push_back(box_row(2, 10.0, 4.8, 0));
  track.frames[0].far_end_w = track.frames[1].far_end_w = Vec3::UnitX();
  track.update_size(0.9);
  EXPECT_NEAR(track.size[0], 4.4, 1e-9);
  EXPECT_NEAR(track.frames[2].T_w_o_detected(0, 3), 10.0, 1e-9);  // an estimate does not move
  EXPECT_NEAR(track.frames[0].T_w_o_detected(0, 3), 10.2, 1e-9);  // a point extent grows forward
}
