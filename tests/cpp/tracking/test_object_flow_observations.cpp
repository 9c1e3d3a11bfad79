// Flow observations (tracking/object_flow_observations.cpp): a cluster whose keypoints are
// never found again (new descriptors every frame, as a far car's small corners) is tracked by
// the flow-predicted pixels of its points when flow_observations_below_matches is on and it
// lies beyond flow_observations_min_depth_m (the default: every cluster beyond 20 m), or
// nearer with fewer matches than flow_observations_near_below_matches (the default: fewer
// than the twist LM needs), and re-seeded frame after frame otherwise.
#include <gtest/gtest.h>

#include <iostream>

#include "tracker_scene.hpp"

namespace {

struct FlowObservations : TrackerScene {
  // A car crossing at 30 m whose keypoints take new descriptors every frame; with the flow.
  Car car = make_car(rng, Vec3(-3.0, 0.9, 30.0), Vec3(0.4, 0.0, -0.1), 0.0, 80);
  static constexpr int kFrames = 8;

  objects::ObjectTrack run(const tracking::ObjectTrackingOptions& options, bool with_flow = true) {
    auto tracker = make_tracker(options);
    std::mt19937 descriptor_rng(5);
    Car changing = car;
    for (int i = 0; i < kFrames; ++i) {
      for (auto& d : changing.descriptors) d = random_descriptor(descriptor_rng);
      SceneFrame f(i);
      f.add_car(changing, i, instance_id(i));
      f.add_background(background);
      tracker.track(f.finish(), f.instances, with_flow && i > 0 ? f.flow : cv::Mat(), kUp);
    }
    EXPECT_EQ(tracker.tracks().size(), 1u);
    return tracker.tracks().empty() ? objects::ObjectTrack{} : tracker.tracks()[0];
  }
};

TEST_F(FlowObservations, AClusterWithoutRepeatableKeypointsIsTrackedByItsFlow) {
  tracking::ObjectTrackingOptions off;
  off.flow_observations_below_matches = 0;
  off.flow_observations_near_below_matches = 0;
  // the premise: no keypoint is found again, so every frame fails and re-seeds
  const objects::ObjectTrack reseeded = run(off);
  EXPECT_LE(reseeded.hits, 1);

  tracking::ObjectTrackingOptions on = off;
  on.flow_observations_below_matches = 10;
  on.flow_observations_min_depth_m = 0.0;
  const objects::ObjectTrack tracked = run(on);
  ASSERT_EQ(tracked.frames.size(), static_cast<size_t>(kFrames));
  EXPECT_GE(tracked.hits, kFrames - 1);  // every frame after the first
  for (size_t r = 1; r < tracked.frames.size(); ++r) EXPECT_TRUE(tracked.frames[r].detected) << r;
  // mono observations at exact flow fix the crossing motion
  expect_motion(tracked, car, 0);
  const Vec3 moved = tracked.last().T_w_o.topRightCorner<3, 1>() - tracked.frames[0].T_w_o.topRightCorner<3, 1>();
  const Vec3 truth = car.pose(kFrames - 1).topRightCorner<3, 1>() - car.pose(0).topRightCorner<3, 1>();
  std::cout << "[ flow observations ] path " << moved.transpose() << " m (truth " << truth.transpose() << ")\n";
  EXPECT_LT((moved - truth).norm(), 0.05);

  // no flow, no flow observations: re-seeded as before
  EXPECT_LE(run(on, false).hits, 1);
  // nearer than flow_observations_min_depth_m (the car at ~30 m): none either
  tracking::ObjectTrackingOptions far_only = on;
  far_only.flow_observations_min_depth_m = 40.0;
  EXPECT_LE(run(far_only).hits, 1);
  far_only.flow_observations_min_depth_m = 25.0;
  EXPECT_GE(run(far_only).hits, kFrames - 1);
  // ... unless it has fewer keypoint matches than flow_observations_near_below_matches (here
  // none: every descriptor is new)
  tracking::ObjectTrackingOptions starved = far_only;
  starved.flow_observations_min_depth_m = 40.0;
  starved.flow_observations_near_below_matches = 1;
  EXPECT_GE(run(starved).hits, kFrames - 1);
  // the defaults: on for every cluster beyond 20 m, so this car at 30 m is tracked (no stereo
  // pair here: mono observations at the flow's pixels), and for nearer ones short of the
  // twist LM's inliers
  const tracking::ObjectTrackingOptions defaults;
  EXPECT_GT(defaults.flow_observations_below_matches, 0);
  EXPECT_GE(run(defaults).hits, kFrames - 1);
  EXPECT_EQ(defaults.flow_observations_near_below_matches, defaults.min_inliers);
  tracking::ObjectTrackingOptions near_defaults;
  near_defaults.flow_observations_min_depth_m = 40.0;
  EXPECT_GE(run(near_defaults).hits, kFrames - 1);
}

}  // namespace
