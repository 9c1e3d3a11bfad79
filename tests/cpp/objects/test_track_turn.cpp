// Levelling a turn a cluster made up (objects/track_turn.hpp): rows spinning faster than a car
// turns take the last row's heading and keep their path; a car's real turn is left alone.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "objects/track_turn.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {
const Vec3 kUp(0, -1, 0);  // camera-style world: y down

// A planar track from frame 12 on: `rows` rows driving 1.5 m/frame towards the camera (-z) and
// turning yaw_deg_per_frame about the road's normal, with eq. 2's twists between them.
ObjectTrack turning_track(int rows, double yaw_deg_per_frame) {
  ObjectTrack track;
  track.link = geometry::LinkType::kPlanar;
  track.Pi = geometry::projector_planar(kUp);
  for (int r = 0; r < rows; ++r) {
    TrackFrame row;
    row.frame = 12 + r;
    const Mat3 R = geometry::so3_exp(kUp * (0.3 + yaw_deg_per_frame * M_PI / 180.0 * r));
    row.T_w_o = geometry::make_pose(R, Vec3(4.0, 1.2, 47.0 - 1.5 * r));
    track.frames.push_back(row);
  }
  for (int r = 0; r + 1 < rows; ++r)
    track.frames[r].xi = track.Pi * geometry::twist_between(track.frames[r].T_w_o, track.frames[r + 1].T_w_o);
  return track;
}

double angle_deg(const Mat3& a, const Mat3& b) {
  return geometry::so3_log(a * b.transpose()).norm() * 180.0 / M_PI;
}
}  // namespace

TEST(TrackTurn, MeanTurnPerFrameCountsEveryStep) {
  EXPECT_NEAR(mean_turn_deg_per_frame(turning_track(5, 11.0)), 11.0, 1e-9);
  EXPECT_NEAR(mean_turn_deg_per_frame(turning_track(5, -2.0)), 2.0, 1e-9);
  EXPECT_EQ(mean_turn_deg_per_frame(turning_track(1, 11.0)), 0.0);  // one row: no turn
  ObjectTrack gap = turning_track(3, 6.0);
  gap.frames[2].frame += 2;  // the last step spans three frames
  EXPECT_NEAR(mean_turn_deg_per_frame(gap), 12.0 / 4.0, 1e-9);
}

TEST(TrackTurn, ASpinNoCarMakesTakesTheLastRowsHeadingAndKeepsItsPath) {
  ObjectTrack track = turning_track(5, 11.0);  // urban s0's far oncoming car 11, frames 12-16
  const ObjectTrack before = track;
  ASSERT_TRUE(level_made_up_turn(&track, 5.0));
  const Mat3 R_last = before.last().T_w_o.topLeftCorner<3, 3>();
  for (size_t r = 0; r < track.frames.size(); ++r) {
    const TrackFrame& row = track.frames[r];
    EXPECT_LT(angle_deg(row.T_w_o.topLeftCorner<3, 3>(), R_last), 1e-9) << "row " << r;
    EXPECT_LT((row.T_w_o.topRightCorner<3, 1>() - before.frames[r].T_w_o.topRightCorner<3, 1>()).norm(), 1e-12);
  }
  // the twists link the levelled rows (eq. 2) and turn no more
  for (size_t r = 0; r + 1 < track.frames.size(); ++r) {
    const Mat4 next = geometry::se3_exp(track.frames[r].xi) * track.frames[r].T_w_o;
    EXPECT_LT((next - track.frames[r + 1].T_w_o).norm(), 1e-9) << "row " << r;
    EXPECT_LT(track.frames[r].xi.tail<3>().norm(), 1e-12);
    EXPECT_NEAR(track.frames[r].xi.head<3>().norm(), 1.5, 1e-9);
  }
  EXPECT_EQ(mean_turn_deg_per_frame(track), 0.0);
}

TEST(TrackTurn, ACarsTurnAndTheSwitchedOffRuleLeaveTheRowsAlone) {
  for (const auto& [rate, max_deg] : {std::pair{3.3, 5.0}, std::pair{11.0, 0.0}}) {
    ObjectTrack track = turning_track(8, rate);
    const ObjectTrack before = track;
    EXPECT_FALSE(level_made_up_turn(&track, max_deg)) << rate << " deg/frame, max " << max_deg;
    for (size_t r = 0; r < track.frames.size(); ++r) {
      EXPECT_EQ(track.frames[r].T_w_o, before.frames[r].T_w_o);
      EXPECT_EQ(track.frames[r].xi, before.frames[r].xi);
    }
  }
}

namespace {
// `rows` rows of a car driving `step_m` a frame along a circle of `radius_m` (its heading the
// circle's tangent: a real turn), starting at (4, 1.2, 20) heading -z.
ObjectTrack circling_track(int rows, double radius_m, double step_m) {
  ObjectTrack track;
  track.link = geometry::LinkType::kPlanar;
  track.Pi = geometry::projector_planar(kUp);
  const Vec3 centre(4.0 - radius_m, 1.2, 20.0);
  for (int r = 0; r < rows; ++r) {
    const double angle = step_m * r / radius_m;  // rad turned so far
    TrackFrame row;
    row.frame = 30 + r;
    row.T_w_o = geometry::make_pose(geometry::so3_exp(kUp * angle),
                                    centre + Vec3(radius_m * std::cos(angle), 0, -radius_m * std::sin(angle)));
    track.frames.push_back(row);
  }
  for (int r = 0; r + 1 < rows; ++r)
    track.frames[r].xi = track.Pi * geometry::twist_between(track.frames[r].T_w_o, track.frames[r + 1].T_w_o);
  return track;
}
}  // namespace

TEST(TrackTurn, ASlowCarsSpinIsBoundedByItsTravel) {
  // urban s23's car 17: 0.1 m a frame straight ahead while its frame spins 1.5 deg a frame
  ObjectTrack track = turning_track(12, 1.5);
  for (size_t r = 0; r < track.frames.size(); ++r) track.frames[r].T_w_o(2, 3) = 47.0 - 0.1 * r;
  const ObjectTrack before = track;
  EXPECT_EQ(bound_turn_by_travel(&track, 5.0), 11);
  const double max_deg = 0.1 / 5.0 * 180.0 / M_PI;  // 1.15 deg a frame
  for (size_t r = 1; r < track.frames.size(); ++r) {
    const Mat3 R = track.frames[r].T_w_o.topLeftCorner<3, 3>();
    EXPECT_NEAR(angle_deg(R, track.frames[r - 1].T_w_o.topLeftCorner<3, 3>()), max_deg, 1e-6) << "row " << r;
    // the same way round, about the road's normal
    EXPECT_GT(geometry::so3_log(R * track.frames[r - 1].T_w_o.topLeftCorner<3, 3>().transpose()).dot(kUp), 0);
    EXPECT_LT((track.frames[r].T_w_o.topRightCorner<3, 1>() - before.frames[r].T_w_o.topRightCorner<3, 1>()).norm(), 1e-12);
  }
  EXPECT_EQ(track.frames[0].T_w_o, before.frames[0].T_w_o);
  for (size_t r = 0; r + 1 < track.frames.size(); ++r) {  // eq. 2 links the bounded rows
    const Mat4 next = geometry::se3_exp(track.frames[r].xi) * track.frames[r].T_w_o;
    EXPECT_LT((next - track.frames[r + 1].T_w_o).norm(), 1e-9) << "row " << r;
  }
}

TEST(TrackTurn, AStoppedCarKeepsItsHeading) {
  ObjectTrack track = turning_track(6, 2.0);
  for (TrackFrame& row : track.frames) row.T_w_o(2, 3) = 30.0;  // no travel
  EXPECT_EQ(bound_turn_by_travel(&track, 5.0), 5);
  for (const TrackFrame& row : track.frames)
    EXPECT_LT(angle_deg(row.T_w_o.topLeftCorner<3, 3>(), track.frames[0].T_w_o.topLeftCorner<3, 3>()), 1e-9);
}

TEST(TrackTurn, ACarTurningOnItsRadiusOrTheSwitchedOffBoundLeaveTheRowsAlone) {
  // 1 m a frame on a 6 m circle (9.5 deg a frame), bound 5 m; and a spin with the bound off
  for (const auto& [track0, radius] : {std::pair{circling_track(10, 6.0, 1.0), 5.0},
                                       std::pair{turning_track(6, 11.0), 0.0}}) {
    ObjectTrack track = track0;
    EXPECT_EQ(bound_turn_by_travel(&track, radius), 0);
    for (size_t r = 0; r < track.frames.size(); ++r) {
      EXPECT_EQ(track.frames[r].T_w_o, track0.frames[r].T_w_o);
      EXPECT_EQ(track.frames[r].xi, track0.frames[r].xi);
    }
  }
}
