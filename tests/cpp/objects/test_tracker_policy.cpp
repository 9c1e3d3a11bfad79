// The tracker's range and gap policies on scripted scenes: the range-corrected score (births
// of far cars whose raw score is low, the track confidence), the backcast of far-born tracks
// (where it starts, where it stops) and the interpolation of a re-detected track's gap.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "geometry/se3.hpp"
#include "objects/tracker.hpp"
#include "scenes.hpp"

using namespace twistslam;
using namespace twistslam::objects;
using scenes::Car;
using scenes::detect;
using scenes::kI;
using scenes::position;

namespace {

// A car driving towards the camera along its optical axis (yaw pi/2: length along z) at
// 1 m/frame, at z = z0 in frame 0.
Car oncoming(double z0, double x = 0) {
  Car car;
  car.p0 = Vec3(x, 0.9, z0);
  car.yaw0 = M_PI / 2;
  car.v = 1.0;
  return car;
}

}  // namespace

TEST(TrackerPolicy, RangeCorrectedScoreBringsFarCarsWithLowScores) {
  // 60 m away, the detector's raw score 0.5 is below birth_score 1: with the raw score the car
  // is never tracked; corrected, 0.5 + 0.15 * (60 - 35) = 4.25 starts and confirms it.
  for (const double slope : {0.0, 0.15}) {
    SCOPED_TRACE(testing::Message() << "slope " << slope);
    TrackerOptions o = scenes::options();
    o.birth_score = o.high_score = 1.0;
    o.range_score_slope = slope;
    o.range_score_start = 35;
    Tracker tracker(o);
    Car car;
    car.p0 = Vec3(0, 0.9, 60);
    car.v = 0.5;  // crossing at 60 m: the range stays 60 m (within 0.1 m)
    for (int f = 0; f < 8; ++f) tracker.step(f, kI, {detect(car.pose(f), 0.5)});
    const auto& tracks = tracker.tracks();
    if (slope == 0) {
      EXPECT_TRUE(tracks.empty());
      continue;
    }
    ASSERT_EQ(tracks.size(), 1u);
    const ObjectTrack& t = tracks[0];
    EXPECT_TRUE(t.ever_confirmed());
    EXPECT_EQ(t.hits, 8);
    EXPECT_NEAR(t.mean_score(), 0.5, 1e-12);  // the detector's own scores are kept
    for (const auto& fr : t.frames) {
      EXPECT_NEAR(fr.range, position(car.pose(fr.frame)).norm(), 1e-9);
      EXPECT_NEAR(fr.confidence, range_corrected_score(0.5, fr.range, o), 1e-12);
    }
    EXPECT_NEAR(t.confidence(), 0.5 + 0.15 * (60.0 - 35.0), 0.02);
  }
}

TEST(TrackerPolicy, RangeCorrectedScoreLeavesNearDetectionsAlone) {
  TrackerOptions o = scenes::options();
  o.range_score_slope = 0.15;
  o.range_score_start = 35;
  EXPECT_DOUBLE_EQ(range_corrected_score(2.0, 20.0, o), 2.0);
  EXPECT_DOUBLE_EQ(range_corrected_score(2.0, 35.0, o), 2.0);
  EXPECT_DOUBLE_EQ(range_corrected_score(2.0, 55.0, o), 5.0);
  EXPECT_DOUBLE_EQ(range_corrected_score(-1.0, 45.0, o), 0.5);
}

TEST(TrackerPolicy, FarBornTrackIsBackcastAlongItsMotion) {
  // The car drives towards the camera from 70 m; the detector sees it from frame 10 (60 m).
  const Car car = oncoming(70);
  for (const int backcast : {0, 4, 20}) {
    SCOPED_TRACE(testing::Message() << "backcast_frames " << backcast);
    TrackerOptions o = scenes::options();
    o.backcast_frames = backcast;
    o.backcast_min_range = 45;
    Tracker tracker(o);
    for (int f = 0; f < 25; ++f) {
      std::vector<Detection> dets;
      if (f >= 10) dets.push_back(detect(car.pose(f)));
      tracker.step(f, kI, dets);
    }
    const auto& tracks = tracker.tracks();
    ASSERT_EQ(tracks.size(), 1u);
    const ObjectTrack& t = tracks[0];
    EXPECT_EQ(t.first_frame(), 10);  // the track itself starts at its first detection
    // backcast: min(backcast_frames, frames since the first frame stepped), oldest first
    const int expected = std::min(backcast, 10);
    ASSERT_EQ(static_cast<int>(t.backcast.size()), expected);
    for (int k = 0; k < expected; ++k) {
      const TrackFrame& b = t.backcast[k];
      EXPECT_EQ(b.frame, 10 - expected + k);
      EXPECT_TRUE(b.reported);
      EXPECT_FALSE(b.detected);
      // constant velocity backwards: on the car's true path
      EXPECT_LT((position(b.T_w_o) - position(car.pose(b.frame))).norm(), 0.05) << b.frame;
      EXPECT_NEAR(scenes::wrap_angle(scenes::yaw_of(b.T_w_o) - M_PI / 2), 0, 1e-6);
    }
  }
}

TEST(TrackerPolicy, BackcastStopsNearerThanItsMinimumRange) {
  // A car driving away from the camera, first detected at 50 m in frame 10: backwards it
  // comes nearer, and the backcast keeps the frames where it is still >= 45 m away (45-49 m,
  // frames 5-9), not the 8 asked for.
  Car car;
  car.p0 = Vec3(0, 0.9, 40);
  car.yaw0 = -M_PI / 2;  // forward = +z
  TrackerOptions o = scenes::options();
  o.backcast_frames = 8;
  o.backcast_min_range = 45;
  Tracker tracker(o);
  for (int f = 0; f < 20; ++f) {
    std::vector<Detection> dets;
    if (f >= 10) dets.push_back(detect(car.pose(f)));
    tracker.step(f, kI, dets);
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  const auto& backcast = tracker.tracks()[0].backcast;
  ASSERT_EQ(backcast.size(), 5u);
  EXPECT_EQ(backcast.front().frame, 5);
  for (const auto& b : backcast) EXPECT_GE(position(b.T_w_o).norm(), 45.0) << b.frame;
}

TEST(TrackerPolicy, BackcastRangeIsFromEachFramesCamera) {
  // The oncoming car tracked in the world frame from a camera that backs away from it at
  // 3 m/frame (at z = 30 - 3 f): first detected 60 m away in frame 10, but backwards in time
  // the camera was nearer: 58, 56, ..., 46 m in frames 9 ... 3, 44 m in frame 2. The backcast
  // keeps frames 3-9 (a range from the world origin would keep all 8).
  const Car car = oncoming(70);
  TrackerOptions o = scenes::options();
  o.backcast_frames = 8;
  o.backcast_min_range = 45;
  Tracker tracker(o);
  for (int f = 0; f < 20; ++f) {
    const Mat4 T_w_c = scenes::pose_yaw(0, Vec3(0, 0, 30.0 - 3.0 * f));
    std::vector<Detection> dets;
    if (f >= 10) dets.push_back(detect(geometry::se3_inverse(T_w_c) * car.pose(f)));
    tracker.step(f, T_w_c, dets);
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  const auto& backcast = tracker.tracks()[0].backcast;
  ASSERT_EQ(backcast.size(), 7u);
  EXPECT_EQ(backcast.front().frame, 3);
  for (const auto& b : backcast)  // world poses on the car's path
    EXPECT_LT((position(b.T_w_o) - position(car.pose(b.frame))).norm(), 0.05) << b.frame;
}

TEST(TrackerPolicy, NearBornTrackIsNotBackcast) {
  // The same car first detected at 40 m (< backcast_min_range): it came into view (or out of
  // an occlusion) there, nothing is reported before.
  const Car car = oncoming(50);
  TrackerOptions o = scenes::options();
  o.backcast_frames = 8;
  o.backcast_min_range = 45;
  Tracker tracker(o);
  for (int f = 0; f < 20; ++f) {
    std::vector<Detection> dets;
    if (f >= 10) dets.push_back(detect(car.pose(f)));
    tracker.step(f, kI, dets);
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_TRUE(tracker.tracks()[0].backcast.empty());
}

TEST(TrackerPolicy, UnconfirmedTracksAreNotBackcast) {
  TrackerOptions o = scenes::options();
  o.backcast_frames = 8;
  o.birth_hits = 3;
  Tracker tracker(o);
  const Car car = oncoming(70);
  for (int f = 0; f < 12; ++f) {
    std::vector<Detection> dets;
    if (f >= 10) dets.push_back(detect(car.pose(f)));  // 2 hits < birth_hits
    tracker.step(f, kI, dets);
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_FALSE(tracker.tracks()[0].ever_confirmed());
  EXPECT_TRUE(tracker.tracks()[0].backcast.empty());
}

TEST(TrackerPolicy, BackcastStopsAtAnotherTracksBox) {
  // A parked car at z = 68 m is tracked from frame 0; the oncoming car, first detected at
  // 60 m in frame 10, would be backcast through z = 61 ... 68 (frames 9 ... 2): its boxes
  // (4 m long along z) touch the parked one's from z = 64 on, so the backcast keeps frames
  // 6-9 only (z 61-64) and never reports two boxes on one object.
  const Car car = oncoming(70);
  Car parked;
  parked.p0 = Vec3(0, 0.9, 68);
  parked.yaw0 = M_PI / 2;
  parked.v = 0;
  TrackerOptions o = scenes::options();
  o.backcast_frames = 8;
  o.backcast_min_range = 45;
  Tracker tracker(o);
  for (int f = 0; f < 20; ++f) {
    std::vector<Detection> dets = {detect(parked.pose(f))};
    if (f >= 10) dets.push_back(detect(car.pose(f)));
    tracker.step(f, kI, dets);
  }
  const auto& tracks = tracker.tracks();
  ASSERT_EQ(tracks.size(), 2u);
  const int k = scenes::track_with_detection(tracks, 15, 1);
  ASSERT_EQ(k, 1);
  const ObjectTrack& t = tracks[k];
  ASSERT_EQ(t.backcast.size(), 4u);
  EXPECT_EQ(t.backcast.front().frame, 6);
  EXPECT_EQ(t.backcast.back().frame, 9);
  EXPECT_TRUE(tracks[0].backcast.empty());  // the parked car was there from the first frame
  // without the parked car the same track is backcast the full 8 frames
  Tracker alone(o);
  for (int f = 0; f < 20; ++f) alone.step(f, kI, f >= 10 ? std::vector<Detection>{detect(car.pose(f))} : std::vector<Detection>{});
  ASSERT_EQ(alone.tracks().size(), 1u);
  EXPECT_EQ(alone.tracks()[0].backcast.size(), 8u);
}

TEST(TrackerPolicy, BackcastIsRecomputedNotAccumulated) {
  // tracks() may be called after any step: the backcast is the output policy's, rebuilt each
  // time from the current track (never stacked, never fed to the window).
  TrackerOptions o = scenes::options();
  o.backcast_frames = 5;
  Tracker tracker(o);
  const Car car = oncoming(70);
  for (int f = 0; f < 20; ++f) {
    std::vector<Detection> dets;
    if (f >= 10) dets.push_back(detect(car.pose(f)));
    tracker.step(f, kI, dets);
    const auto& tracks = tracker.tracks();
    if (f >= 10) {  // born at 10, confirmed at its third detection (birth_hits 3)
      ASSERT_EQ(tracks.size(), 1u);
      EXPECT_EQ(tracks[0].backcast.size(), f >= 12 ? 5u : 0u) << f;
      EXPECT_EQ(tracks[0].first_frame(), 10) << f;
    }
  }
}

TEST(TrackerPolicy, GapIsInterpolatedBetweenItsDetections) {
  // A car at 1 m/frame slows to 0.8 m/frame during 8 missed frames (10-17): the forward
  // prediction overshoots by up to 1.6 m; the interpolation between the last estimate and the
  // re-detection lies on the true path. Without the window nothing else moves the gap poses.
  const auto truth = [](int f) {
    const double x = f <= 9 ? f : 9 + 0.8 * (f - 9);
    return scenes::pose_yaw(0, Vec3(x, 0.9, 20));
  };
  for (const bool interpolate : {false, true}) {
    SCOPED_TRACE(testing::Message() << "interpolate " << interpolate);
    TrackerOptions o = scenes::options();
    o.optimize = false;
    o.interpolate_gaps = interpolate;
    o.max_misses = 10;
    o.max_reported_gap = 10;
    Tracker tracker(o);
    for (int f = 0; f < 25; ++f) {
      std::vector<Detection> dets;
      if (f < 10 || f >= 18) dets.push_back(detect(truth(f)));
      tracker.step(f, kI, dets);
    }
    const auto& tracks = tracker.tracks();
    ASSERT_EQ(tracks.size(), 1u);  // the re-detection is associated (1.8 m along the length)
    double worst = 0;
    for (int f = 10; f < 18; ++f) {
      const TrackFrame* fr = tracks[0].at(f);
      ASSERT_NE(fr, nullptr);
      EXPECT_FALSE(fr->detected);
      EXPECT_TRUE(fr->reported);
      worst = std::max(worst, (position(fr->T_w_o) - position(truth(f))).norm());
    }
    if (interpolate) {
      EXPECT_LT(worst, 1e-6);
    } else {
      EXPECT_GT(worst, 1.0);
    }
  }
}

TEST(TrackerPolicy, PredictedTurnDecaysThroughMissedFrames) {
  // A car on a 20 m circle (1 m/frame, 0.05 rad/frame) detected in frames 0-9, then lost: the
  // first missed frame is predicted with the full twist; after it the turn rate is multiplied
  // by miss_turn_decay per frame while the speed is kept.
  Car car;
  car.p0 = Vec3(-5, 0.9, 25);
  car.omega = 0.05;
  for (const double decay : {1.0, 0.5, 0.0}) {
    SCOPED_TRACE(testing::Message() << "miss_turn_decay " << decay);
    TrackerOptions o = scenes::options();
    o.miss_turn_decay = decay;
    o.max_misses = 10;
    Tracker tracker(o);
    for (int f = 0; f < 16; ++f) tracker.step(f, kI, f < 10 ? std::vector<Detection>{detect(car.pose(f))} : std::vector<Detection>{});
    ASSERT_EQ(tracker.tracks().size(), 1u);
    const ObjectTrack& t = tracker.tracks()[0];
    ASSERT_EQ(t.last().frame, 15);
    double expected_turn = 0, rate = 0.05;
    for (int f = 10; f <= 15; ++f) {
      const Mat4& a = t.at(f - 1)->T_w_o;
      const Mat4& b = t.at(f)->T_w_o;
      const double turn = scenes::wrap_angle(scenes::yaw_of(b) - scenes::yaw_of(a));
      EXPECT_NEAR(turn, rate, 0.004) << f;
      EXPECT_NEAR((position(b) - position(a)).norm(), 1.0, 0.02) << f;  // speed kept
      expected_turn += turn;
      rate *= decay;  // the next frame's rate
    }
    if (decay == 0.0) EXPECT_NEAR(expected_turn, 0.05, 0.005);
    if (decay == 1.0) EXPECT_NEAR(expected_turn, 0.30, 0.02);
  }
}

TEST(TrackerPolicy, NegativeBackcastFramesThrow) {
  TrackerOptions o = scenes::options();
  o.backcast_frames = -1;
  EXPECT_THROW(Tracker{o}, std::invalid_argument);
  o = scenes::options();
  o.range_score_slope = std::nan("");
  EXPECT_THROW(Tracker{o}, std::invalid_argument);
  o = scenes::options();
  o.miss_turn_decay = 1.5;
  EXPECT_THROW(Tracker{o}, std::invalid_argument);
}
