// The tracker's input contract: out-of-order frames, non-finite or empty boxes, non-rigid
// camera poses and bad options throw std::invalid_argument and leave the state untouched;
// skipped frames are predicted; empty detection lists are fine.
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <vector>

#include "objects/tracker.hpp"
#include "scenes.hpp"

using namespace twistslam;
using namespace twistslam::objects;
using scenes::Car;
using scenes::detect;
using scenes::kI;
using scenes::position;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();


}  // namespace

TEST(TrackerInput, EmptyDetectionListsAreFine) {
  Tracker tracker(scenes::options());
  for (int f = 0; f < 5; ++f) EXPECT_NO_THROW(tracker.step(f, kI, {}));
  EXPECT_TRUE(tracker.tracks().empty());
  EXPECT_EQ(tracker.num_live(), 0);
  EXPECT_EQ(tracker.last_frame(), 4);
}

TEST(TrackerInput, FramesMustIncrease) {
  Tracker tracker(scenes::options());
  const Car car;
  EXPECT_THROW(tracker.step(-1, kI, {}), std::invalid_argument);
  tracker.step(5, kI, {detect(car.pose(5))});  // the first frame need not be 0
  EXPECT_THROW(tracker.step(5, kI, {detect(car.pose(5))}), std::invalid_argument);
  EXPECT_THROW(tracker.step(4, kI, {}), std::invalid_argument);
  EXPECT_EQ(tracker.last_frame(), 5);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_EQ(tracker.tracks()[0].frames.size(), 1u);  // the failed calls changed nothing
  EXPECT_EQ(tracker.tracks()[0].hits, 1);
  EXPECT_NO_THROW(tracker.step(6, kI, {detect(car.pose(6))}));
  EXPECT_EQ(tracker.tracks()[0].hits, 2);
}

TEST(TrackerInput, BadBoxesThrowAndChangeNothing) {
  Tracker tracker(scenes::options());
  const Car car;
  tracker.step(0, kI, {detect(car.pose(0))});
  std::vector<Detection> bad;
  for (int k = 0; k < 9; ++k) bad.push_back(detect(car.pose(1)));
  bad[0].box.center.x() = kNaN;
  bad[1].box.center.z() = kInf;
  bad[2].box.yaw = kNaN;
  bad[3].box.length = 0;
  bad[4].box.width = -1.6;
  bad[5].box.height = kNaN;
  bad[6].score = kNaN;
  bad[7].box.length = kInf;
  bad[8].box.height = 0;
  for (size_t k = 0; k < bad.size(); ++k) {
    // the bad one after a good one: nothing is half-processed
    EXPECT_THROW(tracker.step(1, kI, {detect(car.pose(1)), bad[k]}), std::invalid_argument) << k;
  }
  EXPECT_EQ(tracker.last_frame(), 0);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_EQ(tracker.tracks()[0].frames.size(), 1u);
  tracker.step(1, kI, {detect(car.pose(1))});
  EXPECT_EQ(tracker.tracks()[0].hits, 2);
}

TEST(TrackerInput, NonRigidCameraPosesThrow) {
  Tracker tracker(scenes::options());
  const Car car;
  Mat4 scaled = kI;
  scaled.topLeftCorner<3, 3>() *= 2.0;
  Mat4 sheared = kI;
  sheared(0, 1) = 0.3;
  Mat4 reflected = kI;
  reflected(0, 0) = -1;
  Mat4 bottom = kI;
  bottom(3, 0) = 0.5;
  Mat4 nan_t = kI;
  nan_t(1, 3) = kNaN;
  Mat4 inf_t = kI;
  inf_t(2, 3) = kInf;
  for (const Mat4& T : {scaled, sheared, reflected, bottom, nan_t, inf_t, Mat4(Mat4::Zero())}) {
    EXPECT_THROW(tracker.step(0, T, {detect(car.pose(0))}), std::invalid_argument) << T;
  }
  EXPECT_TRUE(tracker.tracks().empty());
  EXPECT_EQ(tracker.last_frame(), -1);
  EXPECT_NO_THROW(tracker.step(0, scenes::pose_yaw(0.3, Vec3(1, 2, 3)), {detect(car.pose(0))}));
}

TEST(TrackerInput, BadOptionsThrow) {
  EXPECT_NO_THROW(Tracker{TrackerOptions{}});  // the library's defaults are valid
  EXPECT_NO_THROW(Tracker{scenes::options()});
  TrackerOptions o = scenes::options();
  o.window = 1;
  EXPECT_THROW(Tracker{o}, std::invalid_argument);
  o = TrackerOptions{};
  o.birth_hits = 0;
  EXPECT_THROW(Tracker{o}, std::invalid_argument);
  o = TrackerOptions{};
  o.ground_normal = Vec3::Zero();
  EXPECT_THROW(Tracker{o}, std::invalid_argument);
  o.ground_normal = Vec3(kNaN, 1, 0);
  EXPECT_THROW(Tracker{o}, std::invalid_argument);
}

TEST(TrackerInput, SkippedFramesArePredicted) {
  for (const bool optimize : {true, false}) {
    SCOPED_TRACE(optimize ? "optimize" : "no optimisation");
    TrackerOptions o = scenes::options();
    o.optimize = optimize;
    Tracker tracker(o);
    Car car;
    car.omega = 0.03;
    for (int f = 0; f < 5; ++f) tracker.step(f, kI, {detect(car.pose(f))});
    tracker.step(7, kI, {detect(car.pose(7))});  // frames 5 and 6 skipped: 2 misses, survives
    const auto& tracks = tracker.tracks();
    ASSERT_EQ(tracks.size(), 1u);
    const ObjectTrack& t = tracks[0];
    ASSERT_EQ(t.frames.size(), 8u);
    EXPECT_EQ(t.state, TrackState::kConfirmed);
    EXPECT_EQ(t.hits, 6);
    for (int f = 0; f < 8; ++f) {
      ASSERT_NE(t.at(f), nullptr);
      EXPECT_EQ(t.at(f)->frame, f);
      EXPECT_EQ(t.at(f)->detected, f != 5 && f != 6);
      EXPECT_TRUE(t.at(f)->reported) << f;
      EXPECT_LT((position(t.at(f)->T_w_o) - position(car.pose(f))).norm(), 0.1) << f;
    }
    // Skipping more than max_misses frames kills it; the next detection starts a new track.
    tracker.step(20, kI, {detect(car.pose(20))});
    const auto& after = tracker.tracks();
    ASSERT_EQ(after.size(), 2u);
    EXPECT_EQ(after[0].state, TrackState::kDead);
    EXPECT_EQ(after[0].frames.size(), 8u);
    EXPECT_EQ(after[1].first_frame(), 20);
    EXPECT_NE(after[1].id, after[0].id);
  }
}

TEST(TrackerInput, ClassesNeverMix) {
  Tracker tracker(scenes::options());
  const Car car;
  for (int f = 0; f < 6; ++f) {
    Detection d = detect(car.pose(f));
    d.class_id = f % 2;  // the same box, alternately labelled car and van
    tracker.step(f, kI, {d});
  }
  for (const auto& t : tracker.tracks()) {
    for (const auto& fr : t.frames) {
      if (fr.detected) {
        EXPECT_EQ(fr.frame % 2, t.class_id);
      }
    }
    EXPECT_FALSE(t.ever_confirmed());
  }
}
