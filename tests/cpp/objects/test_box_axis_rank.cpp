// How well a box knows a car's length axis (objects/box_axis_rank.hpp): a measured length
// ranks 2, a prior length laid along a face seen across the line of sight 1, one laid along
// the line of sight (away from a face seen end-on) 0; a track takes its best box's rank.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "objects/box_axis_rank.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

// A box at `centre` (camera at the origin, looking along z) whose length axis is turned by
// `yaw` about y from the camera's x axis.
Mat4 box_at(const Vec3& centre, double yaw) {
  return geometry::make_pose(geometry::so3_exp(Vec3(0, yaw, 0)), centre);
}

TrackFrame row_with_box(const Mat4& T_w_box, bool prior_length) {
  TrackFrame row;
  row.detection_index = 0;
  row.T_w_o_detected = T_w_box;
  row.T_c_w = Mat4::Identity();
  row.open_end_w = prior_length ? Vec3(T_w_box.block<3, 1>(0, 0)) : Vec3::Zero();
  return row;
}

}  // namespace

TEST(BoxAxisRank, MeasuredAcrossAndAlongTheLineOfSight) {
  const Mat4 camera = Mat4::Identity();
  const Vec3 ahead(2, 0, 40);  // 3 deg right of the camera's axis
  EXPECT_EQ(axis_rank(false, box_at(ahead, M_PI / 2), camera, 60), 2);  // measured: any axis
  EXPECT_EQ(axis_rank(true, box_at(ahead, 0.0), camera, 60), 1);        // across the sight
  EXPECT_EQ(axis_rank(true, box_at(ahead, M_PI / 2), camera, 60), 0);   // along it
  // 45 deg off the sight: a side only for a threshold below 45 deg
  EXPECT_EQ(axis_rank(true, box_at(Vec3(0, 0, 40), M_PI / 4), camera, 60), 0);
  EXPECT_EQ(axis_rank(true, box_at(Vec3(0, 0, 40), M_PI / 4), camera, 40), 1);
}

TEST(BoxAxisRank, ATrackTakesItsBestBoxAndNoBoxIsMinusOne) {
  ObjectTrack track;
  track.frames.push_back(TrackFrame{});  // no box
  EXPECT_EQ(track_axis_rank(track, 60), -1);
  track.frames.push_back(row_with_box(box_at(Vec3(2, 0, 40), M_PI / 2), true));
  EXPECT_EQ(track_axis_rank(track, 60), 0);
  track.frames.push_back(row_with_box(box_at(Vec3(2, 0, 38), 0.0), true));
  EXPECT_EQ(track_axis_rank(track, 60), 1);
  track.frames.push_back(row_with_box(box_at(Vec3(2, 0, 36), M_PI / 2), true));
  EXPECT_EQ(track_axis_rank(track, 60), 1);
}
