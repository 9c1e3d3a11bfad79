// Local mapping on synthetic stereo frames: keypoints are exact projections of known 3D
// points (no images), so each check isolates the component: a segment's first keyframe turns
// its usable stereo keypoints into map points, the keyframe decision follows the temporal rule
// (and skips it while the camera stands still),
// and a second keyframe matched to the first is bundle-adjusted against it (the first holds the
// gauge), the BA pulling a perturbed pose back and reporting that it ran and its time.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/kitti_camera.hpp"
#include "features/orb.hpp"
#include "geometry/se3.hpp"
#include "tracking/local_mapper.hpp"

using namespace twistslam;

namespace {

const geometry::StereoCamera kCamera = test_scenes::kitti_camera();

// 16 x 8 viewing rays of the first camera (world frame = camera 0), 8 to 40 m deep.
std::vector<Vec3> scene_points(double depth_shift = 0) {
  std::vector<Vec3> points;
  for (int r = 0; r < 8; ++r)
    for (int c = 0; c < 16; ++c) {
      const Vec2 uv(80 + 70.0 * c, 40 + 40.0 * r);
      const double depth = 8 + 2.0 * ((5 * r + 3 * c) % 17) + depth_shift;
      points.push_back(kCamera.backproject(uv, depth));
    }
  return points;
}

// 0.5 m forward and 1 deg of yaw per frame.
Mat4 true_T_c_w(int index) {
  Vec6 xi;
  xi << 0, 0, 0.5 * index, 0, M_PI / 180.0 * index, 0;
  return geometry::se3_inverse(geometry::se3_exp(xi));
}

// A frame at T_c_w whose keypoints are the level-0 stereo projections of points_w; the
// descriptor of point j is the same in every frame. No matches yet.
tracking::Frame frame_seeing(const std::vector<Vec3>& points_w, int index, int first_descriptor = 0) {
  tracking::Frame frame;
  frame.index = index;
  frame.timestamp = 0.1 * index;
  frame.T_c_w = true_T_c_w(index);
  map::StereoKeypoints& k = frame.keypoints;
  for (size_t j = 0; j < points_w.size(); ++j) {
    const Vec3 X_c = frame.T_c_w.topLeftCorner<3, 3>() * points_w[j] + frame.T_c_w.topRightCorner<3, 1>();
    k.uv.push_back(kCamera.project(X_c));
    k.octave.push_back(0);
    k.u_right.push_back(kCamera.project_right(X_c).x());
    k.depth.push_back((X_c + kCamera.t_left).z());
    map::Descriptor d{};
    d.fill(static_cast<std::uint8_t>(first_descriptor + j));
    k.descriptors.push_back(d);
    k.label.push_back(-1);
  }
  frame.usable.assign(points_w.size(), 1);
  frame.clear_matches();
  return frame;
}

tracking::LocalMapper make_mapper(const tracking::SlamOptions& options = {}) {
  const features::OrbExtractor extractor(options.orb);
  return tracking::LocalMapper(kCamera, options, tracking::LevelWeights(extractor.level_sigma2()));
}

double translation_error(const Mat4& T_c_w, const Mat4& truth) {
  return (geometry::se3_inverse(T_c_w).topRightCorner<3, 1>() -
          geometry::se3_inverse(truth).topRightCorner<3, 1>()).norm();
}

}  // namespace

TEST(LocalMapper, SegmentStartTurnsEveryUsableStereoKeypointIntoAPoint) {
  const std::vector<Vec3> points = scene_points();
  tracking::Frame frame = frame_seeing(points, 0);
  for (int i = 0; i < 10; ++i) frame.usable[i] = 0;  // an a priori dynamic class (eq. 3)
  for (int i = 10; i < 20; ++i) frame.keypoints.depth[i] = frame.keypoints.u_right[i] = -1;  // no stereo match
  const int stereo_points = static_cast<int>(points.size()) - 20;

  tracking::SlamOptions strict;
  strict.tracking.min_init_points = stereo_points + 1;
  EXPECT_FALSE(make_mapper(strict).can_start_segment(frame));
  tracking::LocalMapper mapper = make_mapper();
  ASSERT_TRUE(mapper.can_start_segment(frame));

  map::Map map;
  const tracking::KeyframeInsertion insertion = mapper.start_segment(frame, map);
  EXPECT_GE(insertion.keyframe_id, 0);
  EXPECT_EQ(insertion.new_points, stereo_points);
  EXPECT_FALSE(insertion.bundle_adjusted);  // a lone keyframe: nothing to adjust against
  EXPECT_EQ(insertion.ba_ms, 0.0);
  EXPECT_EQ(map.num_keyframes(), 1u);
  EXPECT_EQ(map.num_points(), static_cast<size_t>(stereo_points));
  for (size_t i = 0; i < points.size(); ++i) {
    if (i < 20) {
      EXPECT_EQ(frame.point_ids[i], -1) << i;
      continue;
    }
    ASSERT_GE(frame.point_ids[i], 0) << i;  // the next frame tracks it
    EXPECT_LT((map.point(frame.point_ids[i]).X_w - points[i]).norm(), 1e-9) << i;
  }
}

TEST(LocalMapper, KeyframeDecisionFollowsTheTemporalRule) {
  const std::vector<Vec3> points = scene_points();
  tracking::LocalMapper mapper = make_mapper();  // keyframes.max_frames_between = 2
  map::Map map;
  tracking::Frame first = frame_seeing(points, 0);
  const int reference = mapper.start_segment(first, map).keyframe_id;

  auto tracked_frame = [&](int index, size_t matched) {
    tracking::Frame frame = frame_seeing(points, index);
    for (size_t i = 0; i < matched; ++i) frame.point_ids[i] = first.point_ids[i];
    return frame;
  };
  EXPECT_FALSE(mapper.need_keyframe(tracked_frame(1, points.size()), map, reference));
  EXPECT_TRUE(mapper.need_keyframe(tracked_frame(2, points.size()), map, reference));
  // ORB-SLAM2's floor: fewer than 15 tracked inliers never make a keyframe
  EXPECT_FALSE(mapper.need_keyframe(tracked_frame(2, 14), map, reference));
  EXPECT_FALSE(mapper.need_keyframe(tracked_frame(2, points.size()), map, -1));  // no reference
}

TEST(LocalMapper, AStoppedCameraGetsNoTemporalKeyframe) {
  const std::vector<Vec3> points = scene_points();
  tracking::LocalMapper mapper = make_mapper();  // temporal floor: 0.05 m or 0.5 deg
  map::Map map;
  tracking::Frame first = frame_seeing(points, 0);
  const int reference = mapper.start_segment(first, map).keyframe_id;

  // frame 5 seen from `T_c_w`: every point tracked, so only the temporal rule can fire
  auto tracked_at = [&](const Mat4& T_c_w) {
    tracking::Frame frame = frame_seeing(points, 5);
    frame.T_c_w = T_c_w;
    for (size_t i = 0; i < points.size(); ++i) frame.point_ids[i] = first.point_ids[i];
    return frame;
  };
  // -> Mat4: an auto return would keep a product expression of destroyed temporaries
  auto moved = [&](double forward_m, double yaw_deg) -> Mat4 {
    Vec6 xi;
    xi << 0, 0, forward_m, 0, yaw_deg * M_PI / 180.0, 0;
    return geometry::se3_inverse(geometry::se3_exp(xi)) * first.T_c_w;
  };
  EXPECT_FALSE(mapper.need_keyframe(tracked_at(first.T_c_w), map, reference));  // standing still
  EXPECT_FALSE(mapper.need_keyframe(tracked_at(moved(0.01, 0.1)), map, reference));  // tracking noise
  EXPECT_TRUE(mapper.need_keyframe(tracked_at(moved(0.06, 0.0)), map, reference));  // creeping forward
  EXPECT_TRUE(mapper.need_keyframe(tracked_at(moved(0.0, 0.6)), map, reference));  // turning in place

  tracking::SlamOptions every_frame;  // 0: the temporal rule regardless of motion
  every_frame.keyframes.temporal_min_translation_m = 0;
  every_frame.keyframes.temporal_min_rotation_deg = 0;
  tracking::LocalMapper always = make_mapper(every_frame);
  map::Map map2;
  tracking::Frame first2 = frame_seeing(points, 0);
  const int reference2 = always.start_segment(first2, map2).keyframe_id;
  tracking::Frame still = frame_seeing(points, 5);
  still.T_c_w = first2.T_c_w;
  for (size_t i = 0; i < points.size(); ++i) still.point_ids[i] = first2.point_ids[i];
  EXPECT_TRUE(always.need_keyframe(still, map2, reference2));
}

// A map with a segment's first keyframe, and frame 2 seeing the same points (all matched)
// and 24 new ones, its tracked pose 4 cm off.
struct TwoFrames {
  std::vector<Vec3> points = scene_points();
  tracking::Frame first = frame_seeing(points, 0);
  tracking::Frame second;
  int first_id = -1;

  explicit TwoFrames(tracking::LocalMapper& mapper, map::Map& map) {
    first_id = mapper.start_segment(first, map).keyframe_id;
    std::vector<Vec3> seen = points;
    for (const Vec3& X : scene_points(/*depth_shift=*/3.0)) {
      if (seen.size() == points.size() + 24) break;
      seen.push_back(X + Vec3(0.3, 0.2, 0));
    }
    second = frame_seeing(seen, 2, /*first_descriptor=*/7);
    for (size_t i = 0; i < points.size(); ++i) second.point_ids[i] = first.point_ids[i];
    second.T_c_w(0, 3) += 0.04;
  }
};

tracking::SlamOptions synchronous_ba() {
  tracking::SlamOptions options;
  options.local_ba.asynchronous = false;
  return options;
}

TEST(LocalMapper, SecondKeyframeIsBundleAdjustedAgainstTheFirst) {
  tracking::LocalMapper mapper = make_mapper(synchronous_ba());
  map::Map map;
  TwoFrames frames(mapper, map);
  const std::vector<Vec3>& points = frames.points;
  const tracking::Frame& first = frames.first;
  const int first_id = frames.first_id;
  tracking::Frame& second = frames.second;
  ASSERT_NEAR(translation_error(second.T_c_w, true_T_c_w(2)), 0.04, 1e-9);

  const tracking::KeyframeInsertion insertion = mapper.insert_keyframe(second, map);
  EXPECT_EQ(insertion.new_points, 24);
  EXPECT_TRUE(insertion.bundle_adjusted);
  EXPECT_FALSE(insertion.ba_pending);
  EXPECT_GT(insertion.ba_ms, 0.0);  // reported in the result, the only way out of the mapper
  EXPECT_EQ(map.num_keyframes(), 2u);
  EXPECT_EQ(map.num_points(), points.size() + 24);
  EXPECT_EQ(map.keyframe(first_id).T_c_w, true_T_c_w(0));  // the segment's gauge stays put
  // exact observations: the BA finds the true pose again (seen: 0.06 mm)
  EXPECT_LT(translation_error(map.keyframe(insertion.keyframe_id).T_c_w, true_T_c_w(2)), 0.004);
  EXPECT_EQ(map.point(first.point_ids[20]).observations.size(), 2u);
}

TEST(LocalMapper, AsynchronousBundleAdjustmentChangesTheMapOnlyWhenFinishedAndAsTheSynchronousOne) {
  tracking::LocalMapper sync_mapper = make_mapper(synchronous_ba());
  map::Map sync_map;
  TwoFrames sync_frames(sync_mapper, sync_map);
  sync_mapper.insert_keyframe(sync_frames.second, sync_map);

  tracking::LocalMapper mapper = make_mapper();  // local_ba.asynchronous: the default
  map::Map map;
  TwoFrames frames(mapper, map);
  EXPECT_FALSE(mapper.finish_bundle_adjustment(map).applied);  // nothing pending yet
  const tracking::KeyframeInsertion insertion = mapper.insert_keyframe(frames.second, map);
  EXPECT_TRUE(insertion.ba_pending);
  EXPECT_FALSE(insertion.bundle_adjusted);
  EXPECT_TRUE(mapper.bundle_adjustment_pending());
  // until finished, the keyframe keeps its tracked pose, 4 cm off
  EXPECT_NEAR(translation_error(map.keyframe(insertion.keyframe_id).T_c_w, true_T_c_w(2)), 0.04, 1e-9);

  const tracking::FinishedBundleAdjustment done = mapper.finish_bundle_adjustment(map);
  EXPECT_TRUE(done.applied);
  EXPECT_EQ(done.keyframe_id, insertion.keyframe_id);
  EXPECT_EQ(done.frame_index, 2);
  EXPECT_GT(done.solve_ms, 0.0);
  EXPECT_GE(done.wait_ms, 0.0);
  EXPECT_FALSE(mapper.bundle_adjustment_pending());
  EXPECT_FALSE(mapper.finish_bundle_adjustment(map).applied);  // applied once
  EXPECT_LT(translation_error(map.keyframe(insertion.keyframe_id).T_c_w, true_T_c_w(2)), 0.004);
  // bit for bit the synchronous BA's map
  ASSERT_EQ(map.num_points(), sync_map.num_points());
  for (int id : map.keyframe_ids()) EXPECT_EQ(map.keyframe(id).T_c_w, sync_map.keyframe(id).T_c_w) << id;
  for (const auto& [pid, p] : map.points()) {
    EXPECT_EQ(p.X_w, sync_map.point(pid).X_w) << pid;
    EXPECT_EQ(p.observations.size(), sync_map.point(pid).observations.size()) << pid;
  }
}

TEST(LocalMapper, ResetDropsAPendingBundleAdjustmentUnapplied) {
  tracking::LocalMapper mapper = make_mapper();
  map::Map map;
  TwoFrames frames(mapper, map);
  const tracking::KeyframeInsertion insertion = mapper.insert_keyframe(frames.second, map);
  ASSERT_TRUE(insertion.ba_pending);
  mapper.reset();  // waits for the thread, keeps nothing of it
  EXPECT_FALSE(mapper.bundle_adjustment_pending());
  EXPECT_FALSE(mapper.finish_bundle_adjustment(map).applied);
  EXPECT_NEAR(translation_error(map.keyframe(insertion.keyframe_id).T_c_w, true_T_c_w(2)), 0.04, 1e-9);
}
