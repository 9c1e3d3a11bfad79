// Camera-only rows of small objects (people) are reported only within
// small_object_report_max_depth_m (tracking/object_report_range.cpp); cars at the same range,
// and people nearer, are reported in every tracked frame.
#include <gtest/gtest.h>

#include <algorithm>

#include "tracker_scene.hpp"

namespace {

constexpr int kPerson = 24;

int count_reported(const objects::ObjectTrack& t) {
  return static_cast<int>(
      std::count_if(t.frames.begin(), t.frames.end(), [](const auto& r) { return r.reported; }));
}

struct ReportRange : TrackerScene {
  // A cluster of `label` walking towards the camera from `depth` for 6 frames; the tracker.
  tracking::ObjectTracker run(double depth, int label, const tracking::ObjectTrackingOptions& options) {
    Car walker = make_car(rng, Vec3(-2.0, 0.9, depth), Vec3(0.0, 0.0, -0.15), 0.0, 80);
    walker.label = label;
    auto tracker = make_tracker(options);
    std::vector<tracking::ObjectTrackingReport> reports;
    run_car(tracker, walker, background, 6, true, &reports);
    return tracker;
  }
};

TEST_F(ReportRange, FarPeopleAreTrackedButNotReported) {
  const tracking::ObjectTrackingOptions options;
  ASSERT_TRUE(std::count(options.small_object_class_ids.begin(), options.small_object_class_ids.end(),
                         kPerson));
  ASSERT_GT(options.small_object_report_max_depth_m, 30.0);
  ASSERT_LT(options.small_object_report_max_depth_m, 38.0);
  for (double depth : {25.0, 40.0}) {
    const auto tracker = run(depth, kPerson, options);
    ASSERT_EQ(tracker.tracks().size(), 1u) << depth << " m";
    const objects::ObjectTrack& track = tracker.tracks()[0];
    EXPECT_EQ(track.class_id, kPerson);
    ASSERT_EQ(track.frames.size(), 6u);
    EXPECT_GE(track.hits, 5) << depth << " m";  // tracked either way
    EXPECT_EQ(count_reported(track), depth < 35 ? 6 : 0) << depth << " m";
  }
  // a car at 40 m is reported
  const auto car = run(40.0, kCar, options);
  ASSERT_EQ(car.tracks().size(), 1u);
  EXPECT_EQ(count_reported(car.tracks()[0]), 6);
  // no small classes: the far person is reported too
  tracking::ObjectTrackingOptions none = options;
  none.small_object_class_ids.clear();
  EXPECT_EQ(count_reported(run(40.0, kPerson, none).tracks()[0]), 6);
}

}  // namespace
