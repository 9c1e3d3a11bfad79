// The tracker's motion estimates: the sliding-window smoothing of noisy detections of a car
// on a circle (with missed frames), and tracking in a moving world frame (T_w_c varies).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
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

constexpr double kDeg = M_PI / 180;


struct Errors {
  double raw_position = 0, raw_yaw = 0;      // RMS of the detections (detected frames)
  double track_position = 0, track_yaw = 0;  // RMS of the track poses (same frames)
  double gap_position = 0;                   // worst error in the missed frames
  int reported = 0;
  std::vector<bool> gap_reported;
};

// A car at 1 m/frame turning 0.05 rad/frame (a 20 m radius circle), 60 frames, detections
// with sigma_t (m, each axis) / sigma_yaw noise, none in frames 30, 31, 32.
Errors run_circle(TrackerOptions o, unsigned seed, double sigma_t = 0.2, double sigma_yaw = 2 * kDeg) {
  Car car;
  car.p0 = Vec3(-5, 0.9, 25);
  car.yaw0 = 0.3;
  car.omega = 0.05;
  const std::set<int> gap = {30, 31, 32};
  Tracker tracker(o);
  std::mt19937 rng(seed);
  std::vector<Detection> detections(60);
  for (int f = 0; f < 60; ++f) {
    std::vector<Detection> dets;
    if (!gap.count(f)) dets.push_back(detections[f] = scenes::detect_noisy(car.pose(f), sigma_t, sigma_yaw, rng));
    tracker.step(f, kI, dets);
  }
  Errors e;
  const auto& tracks = tracker.tracks();
  EXPECT_EQ(tracks.size(), 1u);
  if (tracks.size() != 1u) return e;
  const ObjectTrack& t = tracks[0];
  EXPECT_EQ(t.frames.size(), 60u);
  EXPECT_EQ(t.hits, 57);
  int n = 0;
  for (const auto& fr : t.frames) {
    const Mat4 truth = car.pose(fr.frame);
    e.reported += fr.reported;
    if (gap.count(fr.frame)) {
      EXPECT_FALSE(fr.detected);
      e.gap_position = std::max(e.gap_position, (position(fr.T_w_o) - position(truth)).norm());
      e.gap_reported.push_back(fr.reported);
      continue;
    }
    const auto& d = detections[fr.frame].box;
    e.raw_position += (d.center - position(truth)).squaredNorm();
    e.raw_yaw += std::pow(scenes::wrap_angle(d.yaw - scenes::yaw_of(truth)), 2);
    e.track_position += (position(fr.T_w_o) - position(truth)).squaredNorm();
    e.track_yaw += std::pow(scenes::wrap_angle(scenes::yaw_of(fr.T_w_o) - scenes::yaw_of(truth)), 2);
    ++n;
  }
  for (double* v : {&e.raw_position, &e.raw_yaw, &e.track_position, &e.track_yaw}) *v = std::sqrt(*v / n);
  return e;
}

}  // namespace

TEST(TrackerMotion, WindowSmoothingBeatsTheRawDetectionsOnACircle) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    TrackerOptions o = scenes::options();
    o.optimize = true;
    o.max_misses = 3;  // survives the 3 missed frames
    o.max_reported_gap = 3;
    const Errors e = run_circle(o, seed);
    EXPECT_LT(e.track_position, 0.7 * e.raw_position)
        << "track " << e.track_position << " m, detections " << e.raw_position << " m";
    EXPECT_LT(e.track_yaw, e.raw_yaw) << "track " << e.track_yaw / kDeg << " deg, detections "
                                      << e.raw_yaw / kDeg << " deg";
    EXPECT_LT(e.gap_position, 0.6);  // the predictions over the gap follow the circle
    EXPECT_EQ(e.reported, 60);
    EXPECT_EQ(e.gap_reported, std::vector<bool>(3, true));
  }
}

TEST(TrackerMotion, GapLongerThanMaxReportedGapIsNotReported) {
  TrackerOptions o = scenes::options();
  o.max_misses = 3;
  o.max_reported_gap = 2;  // < the 3 missed frames
  const Errors e = run_circle(o, 1);
  EXPECT_EQ(e.reported, 57);
  EXPECT_EQ(e.gap_reported, std::vector<bool>(3, false));
}

// Without the window the twist comes from the last two raw detections: with 0.2 m noise its
// prediction over the gap is too poor to associate (a new track is born), hence less noise.
TEST(TrackerMotion, WithoutOptimisationTheTrackFollowsTheDetections) {
  TrackerOptions o = scenes::options();
  o.optimize = false;
  o.max_misses = 3;
  const Errors e = run_circle(o, 1, 0.05, 0.5 * kDeg);
  EXPECT_NEAR(e.track_position, e.raw_position, 1e-9);
  EXPECT_NEAR(e.track_yaw, e.raw_yaw, 1e-9);
  EXPECT_LT(e.gap_position, 1.0);  // still predicted with the last twist
}

// The same world scene seen from a moving camera (rotating about its y axis, so boxes stay
// upright, and moving forward with a bumpy height) gives the same world tracks as feeding the
// world-frame detections with T_w_c = I.
TEST(TrackerMotion, MovingCameraGivesTheSameWorldTracks) {
  Car a, b;
  a.p0 = Vec3(-6, 1.0, 15);
  a.omega = 0.02;
  b.p0 = Vec3(8, 1.0, 40);
  b.yaw0 = 2.5;
  b.v = 0.6;
  const auto T_w_c = [](int f) {
    return scenes::pose_yaw(0.015 * f, Vec3(0.3 * f, 0.05 * std::sin(0.7 * f), 0.8 * f));
  };
  Tracker in_world(scenes::options()), in_camera(scenes::options());
  std::mt19937 rng(5);
  for (int f = 0; f < 30; ++f) {
    std::vector<Detection> world, camera;
    world.push_back(scenes::detect_noisy(a.pose(f), 0.1, 1 * kDeg, rng));
    if (f != 12 && f != 13) world.push_back(scenes::detect_noisy(b.pose(f), 0.1, 1 * kDeg, rng));
    const Mat4 T_c_w = geometry::se3_inverse(T_w_c(f));
    for (const auto& d : world) camera.push_back(detect(T_c_w * d.box.pose(), d.score));
    in_world.step(f, kI, world);
    in_camera.step(f, T_w_c(f), camera);
  }
  const auto& tw = in_world.tracks();
  const auto& tc = in_camera.tracks();
  ASSERT_EQ(tw.size(), 2u);
  ASSERT_EQ(tc.size(), tw.size());
  for (size_t k = 0; k < tw.size(); ++k) {
    EXPECT_EQ(tc[k].id, tw[k].id);
    EXPECT_EQ(tc[k].state, tw[k].state);
    EXPECT_EQ(tc[k].hits, tw[k].hits);
    ASSERT_EQ(tc[k].frames.size(), tw[k].frames.size());
    for (size_t i = 0; i < tw[k].frames.size(); ++i) {
      const auto& fw = tw[k].frames[i];
      const auto& fc = tc[k].frames[i];
      EXPECT_EQ(fc.frame, fw.frame);
      EXPECT_EQ(fc.detected, fw.detected);
      EXPECT_EQ(fc.reported, fw.reported);
      EXPECT_LT((position(fc.T_w_o) - position(fw.T_w_o)).norm(), 1e-4) << "track " << k << " frame " << fw.frame;
      EXPECT_LT((fc.T_w_o.topLeftCorner<3, 3>() - fw.T_w_o.topLeftCorner<3, 3>()).norm(), 1e-4)
          << "track " << k << " frame " << fw.frame;
      EXPECT_LT((fc.T_w_o_detected - fw.T_w_o_detected).norm(), 1e-9);
    }
  }
  // And the world tracks are the world trajectories, not the camera-frame ones: car A is
  // detection 0 of every frame.
  const int k = scenes::track_with_detection(tc, 0, 0);
  ASSERT_GE(k, 0);
  for (int f = 0; f < 30; ++f) {
    ASSERT_NE(tc[k].at(f), nullptr) << f;
    EXPECT_LT((position(tc[k].at(f)->T_w_o) - position(a.pose(f))).norm(), 0.3) << f;
  }
}

// The link restricts the motion the tracker estimates and predicts: a box sinking 0.2 m per
// frame while driving forward keeps its height under the planar link, not under the free one.
TEST(TrackerMotion, PlanarLinkKeepsPredictionsOnTheGround) {
  for (const bool planar : {true, false}) {
    SCOPED_TRACE(planar ? "planar" : "free");
    TrackerOptions o = scenes::options();
    o.optimize = false;  // the twists of the raw detections, projected on the link
    Tracker tracker(o);
    for (int f = 0; f < 5; ++f) {
      Detection d = detect(scenes::pose_yaw(0.0, Vec3(f, 0.9 + 0.2 * f, 20)));
      d.planar = planar;
      tracker.step(f, kI, {d});
    }
    tracker.step(5, kI, {});
    ASSERT_EQ(tracker.tracks().size(), 1u);
    const ObjectTrack& t = tracker.tracks()[0];
    EXPECT_EQ(t.link, planar ? geometry::LinkType::kPlanar : geometry::LinkType::kFree);
    const Vec3 predicted = position(t.at(5)->T_w_o);
    EXPECT_NEAR(predicted.x(), 5.0, 1e-6);
    EXPECT_NEAR(predicted.y(), planar ? 0.9 + 0.2 * 4 : 0.9 + 0.2 * 5, 1e-6);
    EXPECT_NEAR(t.at(4)->xi[1], planar ? 0.0 : 0.2, 1e-9);
  }
}
