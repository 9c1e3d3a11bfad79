// Levelling a turn a cluster made up (objects/track_turn.hpp): rows spinning faster than a car
// turns take the last row's heading and keep their path; a car's real turn is left alone.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>
#include <vector>

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

namespace {
// Reported rows at the given positions, the frame turned yaw_deg[r] about the road's normal.
ObjectTrack rows_at(const std::vector<Vec3>& positions, const std::vector<double>& yaw_deg) {
  ObjectTrack track;
  track.link = geometry::LinkType::kPlanar;
  track.Pi = geometry::projector_planar(kUp);
  for (size_t r = 0; r < positions.size(); ++r) {
    TrackFrame row;
    row.frame = 33 + static_cast<int>(r);
    row.reported = true;
    row.T_w_o = geometry::make_pose(geometry::so3_exp(kUp * (yaw_deg[r] * M_PI / 180.0)), positions[r]);
    track.frames.push_back(row);
  }
  for (size_t r = 0; r + 1 < positions.size(); ++r)
    track.frames[r].xi = track.Pi * geometry::twist_between(track.frames[r].T_w_o, track.frames[r + 1].T_w_o);
  return track;
}

// urban s23's car 17: 65 rows crossing at 0.2 m a frame (13 m) at 45 m with its far stereo's
// depth jitter (+-0.4 m), its frame turning -0.8 deg a frame (-51 deg) with the bearing
ObjectTrack side_on_spinning_car(double deg_per_frame) {
  std::vector<Vec3> p;
  std::vector<double> yaw;
  for (int r = 0; r < 65; ++r) {
    p.emplace_back(3.0 - 0.2 * r, 1.2, 45.0 + 0.4 * std::sin(0.7 * r));
    yaw.push_back(-27.0 + deg_per_frame * r);
  }
  return rows_at(p, yaw);
}
}  // namespace

TEST(TrackTurn, AFrameTurningOffAStraightPathTakesOneRotation) {
  ObjectTrack track = side_on_spinning_car(-0.8);
  const ObjectTrack before = track;
  ASSERT_TRUE(level_turn_off_its_path(&track, kUp, 5.0, 15.0, 20.0));
  const Mat3 R_mid = before.frames[32].T_w_o.topLeftCorner<3, 3>();  // the middle reported row
  for (size_t r = 0; r < track.frames.size(); ++r) {
    EXPECT_LT(angle_deg(track.frames[r].T_w_o.topLeftCorner<3, 3>(), R_mid), 1e-9) << "row " << r;
    EXPECT_LT((track.frames[r].T_w_o.topRightCorner<3, 1>() - before.frames[r].T_w_o.topRightCorner<3, 1>()).norm(), 1e-12);
  }
  for (size_t r = 0; r + 1 < track.frames.size(); ++r) {  // eq. 2 links the levelled rows
    const Mat4 next = geometry::se3_exp(track.frames[r].xi) * track.frames[r].T_w_o;
    EXPECT_LT((next - track.frames[r + 1].T_w_o).norm(), 1e-9) << "row " << r;
  }
  // its predicted (unreported) rows take the rotation too, and do not count for the path
  ObjectTrack with_gap = side_on_spinning_car(-0.8);
  for (int r = 40; r < 45; ++r) {
    with_gap.frames[r].reported = false;
    with_gap.frames[r].T_w_o(0, 3) += 30.0;  // a prediction gone far: no path of the car's
  }
  ASSERT_TRUE(level_turn_off_its_path(&with_gap, kUp, 5.0, 15.0, 20.0));
  const Mat3 R_mid_reported = before.frames[30].T_w_o.topLeftCorner<3, 3>();  // 30 of 60 reported
  EXPECT_LT(angle_deg(with_gap.frames[42].T_w_o.topLeftCorner<3, 3>(), R_mid_reported), 1e-9);
}

TEST(TrackTurn, ATurnItsPathMadeASmallSpinOrTooShortAPathIsLeftAlone) {
  // a right-angle turn on a 10 m circle: the path turns with the frame (p = c + R(a) (r, 0, 0))
  std::vector<Vec3> p;
  std::vector<double> yaw;
  for (int r = 0; r <= 30; ++r) {
    const double a = 0.5 * M_PI * r / 30;
    p.push_back(Vec3(-6.0, 1.2, 30.0) + geometry::so3_exp(kUp * a) * Vec3(10.0, 0, 0));
    yaw.push_back(a * 180.0 / M_PI);
  }
  const ObjectTrack turn = rows_at(p, yaw);
  // a spin the path did not make, but 15 deg: under the excess
  const ObjectTrack small = side_on_spinning_car(-15.0 / 64);
  // the spinning car over 45 rows: 8.8 m of path, its 5 m chords overlap
  ObjectTrack short_path = side_on_spinning_car(-0.8);
  short_path.frames.resize(45);
  // a bend of 12 deg between two straight stretches, the frame turning with it
  std::vector<Vec3> bend_p;
  std::vector<double> bend_yaw;
  const Vec3 before_bend(-0.5, 0, 0), after_bend = geometry::so3_exp(kUp * (12.0 * M_PI / 180.0)) * before_bend;
  Vec3 at(8.0, 1.2, 25.0);
  for (int r = 0; r < 60; ++r) {
    bend_p.push_back(at);
    bend_yaw.push_back(r < 30 ? 0.0 : 12.0);
    at += r < 30 ? before_bend : after_bend;
  }
  const ObjectTrack bend = rows_at(bend_p, bend_yaw);
  for (const ObjectTrack& track0 : {turn, small, short_path, bend}) {
    ObjectTrack track = track0;
    EXPECT_FALSE(level_turn_off_its_path(&track, kUp, 5.0, 15.0, 20.0));
    for (size_t r = 0; r < track.frames.size(); ++r) EXPECT_EQ(track.frames[r].T_w_o, track0.frames[r].T_w_o);
  }
  // the spinning car with the rule off, or no normal: untouched
  for (const auto& [chord, excess, up] : {std::tuple{0.0, 20.0, kUp}, std::tuple{5.0, 0.0, kUp},
                                          std::tuple{5.0, 20.0, Vec3(Vec3::Zero())}}) {
    ObjectTrack track = side_on_spinning_car(-0.8);
    EXPECT_FALSE(level_turn_off_its_path(&track, up, chord, 15.0, excess));
  }
}
