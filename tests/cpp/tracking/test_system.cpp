// The stereo SLAM system on rendered sequences with known motion: textured planes in a world
// frame, the KITTI rig driving forward while turning slowly. Checks tracking accuracy against
// the ground-truth poses, keyframes and local BA, tracking loss on a blank frame, and that
// keypoints of a priori dynamic classes never become map points (paper eq. 3).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "common/textured_planes.hpp"
#include "geometry/se3.hpp"
#include "tracking/system.hpp"

using namespace twistslam;
using namespace twistslam::test_scenes;

namespace {

// A back wall at 60 m and panels at 18-35 m: corners at every depth, occlusion edges.
std::vector<Plane> world_planes(const geometry::StereoCamera& cam) {
  return {make_plane(60.0, -60, -20, 60, 12, 1.3, cam.fx, 51),
          make_plane(20.0, -12, -4, -4, 1.0, 1.3, cam.fx, 52),
          make_plane(25.0, 3, -5, 10, 1.2, 1.3, cam.fx, 53),
          make_plane(30.0, -3, -6, 2, -1, 1.3, cam.fx, 54),
          make_plane(18.0, 6, -2, 9, 1.5, 1.3, cam.fx, 55),
          make_plane(35.0, -20, -8, -10, 1.0, 1.3, cam.fx, 56)};
}

// Ground truth: 0.25 m per frame along +z with a yaw of 0.2 deg per frame (about y).
Mat4 gt_pose(int i) {
  const double yaw = 0.2 * M_PI / 180.0 * i;
  Vec6 xi;
  xi << 0, 0, 0, 0, yaw, 0;
  Mat4 T = geometry::se3_exp(xi);
  T.topRightCorner<3, 1>() = Vec3(0.25 * i * std::sin(yaw / 2), 0, 0.25 * i * std::cos(yaw / 2));
  return T;
}

double translation_error(const Mat4& A, const Mat4& B) {
  return (A.topRightCorner<3, 1>() - B.topRightCorner<3, 1>()).norm();
}

double rotation_error_deg(const Mat4& A, const Mat4& B) {
  const Mat3 dR = A.topLeftCorner<3, 3>().transpose() * B.topLeftCorner<3, 3>();
  return std::acos(std::clamp((dR.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / M_PI;
}

// Mean translation error (m) of the refined trajectory's frame-to-frame steps against the
// ground truth's.
double mean_step_error(const std::vector<std::pair<tracking::TrajectoryEntry, Mat4>>& trajectory) {
  double error = 0;
  for (size_t i = 1; i < trajectory.size(); ++i) {
    const Mat4 est = geometry::se3_inverse(trajectory[i - 1].second) * trajectory[i].second;
    const Mat4 gt = geometry::se3_inverse(gt_pose(static_cast<int>(i) - 1)) * gt_pose(static_cast<int>(i));
    error += translation_error(est, gt) / (trajectory.size() - 1);
  }
  return error;
}

struct StereoFrame {
  cv::Mat left, right, ids;  // ids: plane index of every left pixel
};

const std::vector<StereoFrame>& sequence() {
  static const std::vector<StereoFrame> frames = [] {
    const geometry::StereoCamera cam = kitti_camera();
    const std::vector<Plane> planes = world_planes(cam);
    std::vector<StereoFrame> out;
    for (int i = 0; i < 14; ++i) {
      StereoFrame f;
      f.left = render(planes, cam, gt_pose(i), false, &f.ids, 1.0, 1000 + 2 * i);
      f.right = render(planes, cam, gt_pose(i), true, nullptr, 1.0, 1001 + 2 * i);
      out.push_back(f);
    }
    return out;
  }();
  return frames;
}

bool has_stage(const tracking::TrackResult& r, const std::string& name) {
  return std::any_of(r.timings_ms.begin(), r.timings_ms.end(),
                     [&](const auto& s) { return s.first == name; });
}

}  // namespace

TEST(TrackingSystem, TracksARenderedSequenceWithKnownMotion) {
  tracking::System system(kitti_camera(), tracking::SlamOptions{});
  const auto& frames = sequence();
  int keyframes = 0, bundle_adjustments = 0;
  for (int i = 0; i < static_cast<int>(frames.size()); ++i) {
    const tracking::TrackResult r = system.track(i, 0.1 * i, frames[i].left, frames[i].right);
    EXPECT_EQ(r.status, i == 0 ? tracking::Status::kInitialized : tracking::Status::kOk) << i;
    // world = the first camera = the ground truth's frame
    EXPECT_LT(translation_error(r.T_w_c, gt_pose(i)), 0.015) << "frame " << i;  // seen: <= 6 mm
    EXPECT_LT(rotation_error_deg(r.T_w_c, gt_pose(i)), 0.03) << "frame " << i;  // seen: <= 0.01 deg
    EXPECT_GT(r.num_inliers, 200) << i;
    keyframes += r.is_keyframe;
    bundle_adjustments += has_stage(r, "local_ba");
  }
  EXPECT_GE(keyframes, 6);  // at least every second frame
  EXPECT_GE(bundle_adjustments, keyframes - 1);
  EXPECT_GT(system.map().num_points(), 1000u);

  // The refined trajectory: every frame, each step close to the true step.
  const auto trajectory = system.trajectory();
  ASSERT_EQ(trajectory.size(), frames.size());
  const double step_error = mean_step_error(trajectory);
  EXPECT_LT(step_error, 0.006);  // m per frame, of 0.25 m steps (seen: 2.5 mm)
}

// local_ba.asynchronous solves each keyframe's BA beside the next frame's front end and
// applies it before that frame is tracked: every pose and the map are those of the
// synchronous BA, bit for bit, and the accessors apply the last keyframe's BA still pending.
TEST(TrackingSystem, AsynchronousBundleAdjustmentGivesTheSynchronousResults) {
  tracking::SlamOptions sync_options;
  sync_options.local_ba.asynchronous = false;
  tracking::System sync_system(kitti_camera(), sync_options);
  tracking::System async_system(kitti_camera(), tracking::SlamOptions{});
  ASSERT_TRUE(async_system.options().local_ba.asynchronous);  // the default
  const auto& frames = sequence();
  const int n = 9;  // frame 8 is a keyframe: its BA is pending when the loop ends
  int async_reported = 0, sync_reported = 0;
  for (int i = 0; i < n; ++i) {
    const tracking::TrackResult a = sync_system.track(i, 0.1 * i, frames[i].left, frames[i].right);
    const tracking::TrackResult b = async_system.track(i, 0.1 * i, frames[i].left, frames[i].right);
    EXPECT_EQ(a.T_w_c, b.T_w_c) << i;
    EXPECT_EQ(a.is_keyframe, b.is_keyframe) << i;
    EXPECT_EQ(a.num_inliers, b.num_inliers) << i;
    sync_reported += has_stage(a, "local_ba");
    async_reported += has_stage(b, "local_ba");  // on the frame after its keyframe
    EXPECT_EQ(has_stage(b, "local_ba"), has_stage(b, "local_ba_wait")) << i;
    if (i == n - 1) ASSERT_TRUE(b.is_keyframe);
  }
  EXPECT_EQ(async_reported, sync_reported - 1);  // the last one is applied by the accessors
  const auto a = sync_system.trajectory();
  const auto b = async_system.trajectory();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].second, b[i].second) << i;
  const map::Map& ma = sync_system.map();
  const map::Map& mb = async_system.map();
  ASSERT_EQ(ma.keyframe_ids(), mb.keyframe_ids());
  for (int id : ma.keyframe_ids()) EXPECT_EQ(ma.keyframe(id).T_c_w, mb.keyframe(id).T_c_w) << id;
  ASSERT_EQ(ma.num_points(), mb.num_points());
  for (const auto& [pid, p] : ma.points()) EXPECT_EQ(p.X_w, mb.point(pid).X_w) << pid;
}

// local_ba.apply_delay_frames = 1: the frame after a keyframe is tracked while its BA still
// solves (against the map as it was), and the BA is applied before the frame after that, or
// before the next keyframe insertion, whichever comes first. Tracking stays as accurate.
TEST(TrackingSystem, DelayedBundleAdjustmentOverlapsTheNextFrameAndStaysAccurate) {
  tracking::SlamOptions options;
  options.local_ba.apply_delay_frames = 1;
  tracking::System system(kitti_camera(), options);
  const auto& frames = sequence();
  int last_keyframe = -1, keyframes = 0, reported = 0;
  for (int i = 0; i < static_cast<int>(frames.size()); ++i) {
    const tracking::TrackResult r = system.track(i, 0.1 * i, frames[i].left, frames[i].right);
    EXPECT_LT(translation_error(r.T_w_c, gt_pose(i)), 0.015) << "frame " << i;
    EXPECT_LT(rotation_error_deg(r.T_w_c, gt_pose(i)), 0.03) << "frame " << i;
    if (has_stage(r, "local_ba")) {
      ++reported;
      // two frames after its keyframe, or one when this frame's insertion needed the map
      EXPECT_TRUE(i - last_keyframe == 2 || (i - last_keyframe == 1 && r.is_keyframe)) << i;
    }
    if (r.is_keyframe) last_keyframe = i, ++keyframes;
  }
  EXPECT_GE(keyframes, 6);
  EXPECT_GE(reported, keyframes - 3);  // not the first keyframe's (none) nor the pending ones
  const auto trajectory = system.trajectory();  // applies the last one
  ASSERT_EQ(trajectory.size(), frames.size());
  const double step_error = mean_step_error(trajectory);
  EXPECT_LT(step_error, 0.006);  // m per frame, as with the BA applied at once
}

// Tracks frames [0, n) with the frames in `blank` replaced by uniform grey; returns statuses.
std::vector<tracking::Status> track_with_blanks(tracking::System& system, int n,
                                                const std::vector<int>& blank) {
  const auto& frames = sequence();
  const cv::Mat grey(frames[0].left.size(), CV_8UC1, cv::Scalar(128));
  std::vector<tracking::Status> status;
  for (int i = 0; i < n; ++i) {
    const bool is_blank = std::count(blank.begin(), blank.end(), i) > 0;
    const tracking::TrackResult r = system.track(i, 0.1 * i, is_blank ? grey : frames[i].left,
                                                 is_blank ? grey : frames[i].right);
    status.push_back(r.status);
    // lost: the pose is the constant-velocity prediction, still close to the truth
    EXPECT_LT(translation_error(r.T_w_c, gt_pose(i)), is_blank ? 0.1 : 0.03) << "frame " << i;
  }
  return status;
}

int num_segments(tracking::System& system) {
  int last = -1;
  for (const auto& [id, kf] : system.map().keyframes()) last = std::max(last, kf.segment);
  return last + 1;
}

TEST(TrackingSystem, BlankFrameIsLostThenRelocalisedInTheSameMap) {
  tracking::System system(kitti_camera(), tracking::SlamOptions{});
  const std::vector<tracking::Status> status = track_with_blanks(system, 10, {5});
  EXPECT_EQ(status[5], tracking::Status::kLost);
  EXPECT_EQ(status[6], tracking::Status::kRelocalized);
  for (int i : {7, 8, 9}) EXPECT_EQ(status[i], tracking::Status::kOk) << i;
  EXPECT_EQ(num_segments(system), 1);  // found the old map again: no restart
}

TEST(TrackingSystem, ThreeBlankFramesAreLostThenTrackingResumes) {
  tracking::System system(kitti_camera(), tracking::SlamOptions{});
  const std::vector<tracking::Status> status = track_with_blanks(system, 12, {5, 6, 7});
  for (int i : {5, 6, 7}) EXPECT_EQ(status[i], tracking::Status::kLost) << i;
  EXPECT_EQ(status[8], tracking::Status::kRelocalized);
  for (int i : {9, 10, 11}) EXPECT_EQ(status[i], tracking::Status::kOk) << i;
  EXPECT_LE(num_segments(system), 2);
}

TEST(TrackingSystem, DynamicClassesNeverBecomeMapPoints) {
  // Label the two nearest panels (planes 1 and 4) as cars (Cityscapes 26), the rest as
  // buildings (11). Unmasked, the cars get map points; masked, none of them does.
  constexpr int kCar = 26, kBuilding = 11;
  const auto& frames = sequence();
  auto labels_of = [&](int i) {
    cv::Mat labels(frames[i].ids.size(), CV_32SC1, cv::Scalar(kBuilding));
    labels.setTo(kCar, (frames[i].ids == 1) | (frames[i].ids == 4));
    return labels;
  };
  auto car_points = [&](const std::vector<int>& dynamic) {
    tracking::SlamOptions options;
    options.tracking.dynamic_class_ids = dynamic;
    tracking::System system(kitti_camera(), options);
    for (int i = 0; i < 6; ++i) {
      const auto r = system.track(i, 0.1 * i, frames[i].left, frames[i].right, labels_of(i));
      EXPECT_NE(r.status, tracking::Status::kLost) << i;
    }
    int n = 0;
    for (const auto& [id, p] : system.map().points()) n += p.label == kCar;
    EXPECT_GT(system.map().num_points(), 500u);
    return n;
  };
  EXPECT_GT(car_points({}), 50);
  EXPECT_EQ(car_points({kCar}), 0);
}
