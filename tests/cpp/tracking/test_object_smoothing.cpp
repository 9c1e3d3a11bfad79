// The final smoothing of the object tracks (ObjectTracker::smooth_tracks, object_windows.cpp):
// once the sequence ends, every track's rows and every observation its points made are refined
// in one problem. A far car whose stereo matches carry sub-pixel noise: the sliding window
// freezes each row after window_frames frames, the smoothing lets every frame's observations
// reach every row, so the frame-to-frame motion gets closer to the truth; the online poses
// are kept; a track is smoothed once; a cluster never tracked keeps its rows; with the option
// off nothing is archived or changed.
// Both the windows and the smoothing take their refined points through
// ObjectTracker::take_window, which refuses a point thrown far along its ray (last suite).
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

#include "tracking/tracker_scene.hpp"

using namespace twistslam;

namespace {

// Its own suite name: gtest refuses one suite name over two fixture classes (each test file
// holds its own anonymous-namespace copy of TrackerScene).
struct SmoothingScene : TrackerScene {};

// A car 28 m ahead driving away and to the side, its stereo matches with 0.3 px of noise.
void run_noisy_car(tracking::ObjectTracker& tracker, const Car& car, const Background& background,
                   int frames, std::mt19937& noise) {
  for (int i = 0; i < frames; ++i) {
    SceneFrame f(i);
    f.disparity_noise_px = 0.3;
    f.noise_rng = &noise;
    f.add_car(car, i, instance_id(i));
    f.add_background(background);
    tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp);
  }
}

// A tracker with `options` that followed the noisy car 28 m ahead for `frames` frames.
tracking::ObjectTracker noisy_car_tracker(const tracking::ObjectTrackingOptions& options,
                                          std::mt19937& rng, const Background& background,
                                          int frames, unsigned noise_seed) {
  std::mt19937 noise(noise_seed);
  const Car car = make_car(rng, Vec3(-3, 0.5, 28), Vec3(0.25, 0, 0.6), 0.01);
  auto tracker = make_tracker(options);
  run_noisy_car(tracker, car, background, frames, noise);
  return tracker;
}

// Mean error of the frame-to-frame motions of `poses` (rows of frames first..) against the
// car's: translation (m) and rotation (deg).
std::pair<double, double> step_errors(const std::vector<Mat4>& poses, const Car& car, int first) {
  double t = 0, r = 0;
  for (size_t k = 0; k + 1 < poses.size(); ++k) {
    const Mat4 est = poses[k + 1] * geometry::se3_inverse(poses[k]);
    const Mat4 truth = car.motion(first + static_cast<int>(k));
    t += (est.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>()).norm();
    r += rotation_angle_deg((geometry::se3_inverse(truth) * est).topLeftCorner<3, 3>());
  }
  const double n = static_cast<double>(poses.size() - 1);
  return {t / n, r / n};
}

std::map<int, Mat4> static_camera(int frames) {
  std::map<int, Mat4> cams;
  for (int i = 0; i < frames; ++i) cams[i] = Mat4::Identity();
  return cams;
}

std::vector<Mat4> poses_of(const objects::ObjectTrack& track) {
  std::vector<Mat4> out;
  for (const auto& row : track.frames) out.push_back(row.T_w_o);
  return out;
}

TEST_F(SmoothingScene, FinalSmoothingBringsAFarCarsStepsCloserToTheTruthAndKeepsTheOnlinePoses) {
  constexpr int kFrames = 30;
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    std::mt19937 noise(seed);
    const Car car = make_car(rng, Vec3(-3, 0.5, 28), Vec3(0.25, 0, 0.6), 0.01);
    auto tracker = make_tracker();
    run_noisy_car(tracker, car, background, kFrames, noise);
    ASSERT_EQ(tracker.tracks().size(), 1u) << "seed " << seed;
    const std::vector<Mat4> online = poses_of(tracker.tracks()[0]);
    ASSERT_EQ(online.size(), static_cast<size_t>(kFrames));
    for (const auto& p : tracker.clusters()[0].points) EXPECT_FALSE(p.archive.empty());

    const tracking::ObjectSmoothingReport report = tracker.smooth_tracks(static_camera(kFrames));
    EXPECT_EQ(report.num_tracks, 1);
    EXPECT_EQ(report.num_rejected, 0);
    EXPECT_GT(report.num_residuals, 0);
    const objects::ObjectTrack& track = tracker.tracks()[0];
    ASSERT_EQ(track.T_w_o_online.size(), online.size());
    for (size_t r = 0; r < online.size(); ++r) EXPECT_TRUE(track.T_w_o_online[r] == online[r]);

    const auto [t_online, r_online] = step_errors(online, car, 0);
    const auto [t_smooth, r_smooth] = step_errors(poses_of(track), car, 0);
    // seeds 1-6 with the default point quota (30 observations per frame): online
    // 0.018-0.025 m and 0.025-0.039 deg per step, smoothed 0.010-0.014 m and 0.014-0.020 deg
    // (ratios 0.46-0.64 and 0.45-0.68)
    EXPECT_LT(t_smooth, 0.7 * t_online) << "seed " << seed;
    EXPECT_LT(r_smooth, 0.75 * r_online) << "seed " << seed;
    EXPECT_LT(t_smooth, 0.016) << "seed " << seed;  // m per 0.65 m step
    EXPECT_LT(r_smooth, 0.025) << "seed " << seed;  // deg per step

    // smoothed once: a second call changes nothing
    const std::vector<Mat4> smoothed = poses_of(track);
    EXPECT_EQ(tracker.smooth_tracks(static_camera(kFrames)).num_tracks, 0);
    for (size_t r = 0; r < smoothed.size(); ++r) EXPECT_TRUE(track.frames[r].T_w_o == smoothed[r]);
  }
}

// smoothing_max_median_move_m: a camera-only track whose smoothing would move its reported
// rows by a median beyond the bound keeps its online poses (counted as rejected); within it,
// it is smoothed as before. The noisy car's smoothing moves its rows by millimetres.
TEST_F(SmoothingScene, ATrackTheSmoothingWouldMoveTooFarKeepsItsOnlinePoses) {
  for (double bound_m : {1e-5, 10.0}) {
    tracking::ObjectTrackingOptions options;
    options.smoothing_max_median_move_m = bound_m;
    auto tracker = noisy_car_tracker(options, rng, background, 20, 5);
    ASSERT_EQ(tracker.tracks().size(), 1u);
    const std::vector<Mat4> online = poses_of(tracker.tracks()[0]);
    const tracking::ObjectSmoothingReport report = tracker.smooth_tracks(static_camera(20));
    const objects::ObjectTrack& track = tracker.tracks()[0];
    if (bound_m < 1.0) {
      EXPECT_EQ(report.num_tracks, 0);
      EXPECT_EQ(report.num_rejected, 1);
      EXPECT_TRUE(track.T_w_o_online.empty());
      for (size_t r = 0; r < online.size(); ++r) EXPECT_TRUE(track.frames[r].T_w_o == online[r]) << r;
    } else {
      EXPECT_EQ(report.num_tracks, 1);
      EXPECT_EQ(report.num_rejected, 0);
      bool moved = false;
      for (size_t r = 0; r < online.size(); ++r) moved |= !(track.frames[r].T_w_o == online[r]);
      EXPECT_TRUE(moved);
    }
  }
}

TEST_F(SmoothingScene, AClusterNeverTrackedKeepsItsRows) {
  // a car whose keypoints change descriptors every frame: no point is found again, each frame
  // re-seeds the cluster from its stereo points, the twist never succeeds (hits 1). Nothing
  // links its rows but e_const: they stay as each frame's stereo placed them
  auto tracker = make_tracker();
  run_reseeding_car(tracker, make_car(rng, Vec3(1.0, 0.9, 30), Vec3(0.0, 0.0, -0.8), 0.0, 40),
                    background, 8, rng);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  const objects::ObjectTrack& track = tracker.tracks()[0];
  ASSERT_EQ(track.frames.size(), 8u);
  EXPECT_EQ(track.hits, 1);
  const std::vector<Mat4> before = poses_of(track);
  EXPECT_EQ(tracker.smooth_tracks(static_camera(8)).num_tracks, 0);
  EXPECT_TRUE(track.T_w_o_online.empty());
  for (size_t r = 0; r < before.size(); ++r) EXPECT_TRUE(track.frames[r].T_w_o == before[r]) << r;
}

TEST_F(SmoothingScene, WithoutFinalSmoothingNothingIsArchivedOrChanged) {
  tracking::ObjectTrackingOptions options;
  options.final_smoothing = false;
  auto tracker = noisy_car_tracker(options, rng, background, 12, 7);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  for (const auto& p : tracker.clusters()[0].points) EXPECT_TRUE(p.archive.empty());
  EXPECT_TRUE(tracker.clusters()[0].retired.empty());
  const std::vector<Mat4> before = poses_of(tracker.tracks()[0]);
  EXPECT_EQ(tracker.smooth_tracks(static_camera(12)).num_tracks, 0);
  EXPECT_TRUE(tracker.tracks()[0].T_w_o_online.empty());
  for (size_t r = 0; r < before.size(); ++r) EXPECT_TRUE(tracker.tracks()[0].frames[r].T_w_o == before[r]);
}

TEST_F(SmoothingScene, ATrackWithAFrameWithoutACameraPoseIsLeftOnline) {
  auto tracker = noisy_car_tracker({}, rng, background, 12, 8);
  std::map<int, Mat4> cams = static_camera(12);
  cams.erase(5);  // a lost frame
  EXPECT_EQ(tracker.smooth_tracks(cams).num_tracks, 0);
  EXPECT_TRUE(tracker.tracks()[0].T_w_o_online.empty());
}

// Points the tracker culls (the car's left half hidden from frame 3 on: found in 3 of the 12
// frames that predict them, below min_found_ratio) leave the cluster
// with their observations: the smoothing still uses them for the frames that saw them.
TEST_F(SmoothingScene, CulledPointsRetireWithTheirObservations) {
  std::mt19937 noise(9);
  Car car = make_car(rng, Vec3(-3, 0.5, 20), Vec3(0.25, 0, 0.5), 0.0);
  auto tracker = make_tracker();
  for (int i = 0; i < 20; ++i) {
    SceneFrame f(i);
    f.disparity_noise_px = 0.2;
    f.noise_rng = &noise;
    Car seen = car;
    if (i >= 3) {  // the points with x_o < 0 are hidden (another car in front of them)
      seen.X_o.clear();
      seen.descriptors.clear();
      for (size_t k = 0; k < car.X_o.size(); ++k)
        if (car.X_o[k].x() >= 0) seen.X_o.push_back(car.X_o[k]), seen.descriptors.push_back(car.descriptors[k]);
    }
    f.add_car(seen, i, instance_id(i));
    f.add_background(background);
    tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp);
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  const auto& cluster = tracker.clusters()[0];
  ASSERT_FALSE(cluster.retired.empty());
  for (const auto& p : cluster.retired) {
    EXPECT_GE(p.archive.size(), 2u);
    EXPECT_LT(p.archive.back().frame, 3);  // seen before the occlusion only
    EXPECT_TRUE(p.history.empty());
  }
  EXPECT_EQ(tracker.smooth_tracks(static_camera(20)).num_tracks, 1);
}

}  // namespace

namespace {

// A car driving slowly away along the line of sight, 8 of its 30 keypoints matched in stereo
// and the rest mask pixels seen by the left camera only, at whole-pixel positions, their
// depths filled from the stereo ones (tracking/stereo_depth_fill.hpp). Without parallax
// nothing but the filled depth places such a point: windows free to move it along its ray
// threw it 60-310 m deep on a few pixel roundings (ObjectTracker::take_window).
struct PointRunawayScene : TrackerScene {};

// The largest distance of a cluster point from the car's true body (its box, grown by 0.5 m),
// in the car's frame, at the track's last frame.
double farthest_from_body(const tracking::ObjectTracker& tracker, const Car& car, int frame) {
  const Mat4 T_w_o = tracker.tracks()[0].frames.back().T_w_o;
  const Mat4 T_car_w = geometry::se3_inverse(car.pose(frame));
  const Vec3 half(2.0 + 0.5, 0.75 + 0.5, 0.9 + 0.5);
  double farthest = 0;
  for (const auto& p : tracker.clusters()[0].points) {
    const Vec3 X_w = T_w_o.topLeftCorner<3, 3>() * p.X_o + T_w_o.topRightCorner<3, 1>();
    const Vec3 X_car = T_car_w.topLeftCorner<3, 3>() * X_w + T_car_w.topRightCorner<3, 1>();
    farthest = std::max(farthest, (X_car.cwiseAbs() - half).cwiseMax(0.0).norm());
  }
  return farthest;
}

TEST_F(PointRunawayScene, AWindowMayNotThrowAPointFarFromWhereItJoined) {
  constexpr int kFrames = 25, kStereo = 8;
  const Car car = make_car(rng, Vec3(-1, 0.5, 18), Vec3(0.0, 0, 0.05), 0.0, 30);
  Car stereo = car, mono = car;
  stereo.X_o.resize(kStereo);
  stereo.descriptors.resize(kStereo);
  mono.X_o.erase(mono.X_o.begin(), mono.X_o.begin() + kStereo);
  mono.descriptors.erase(mono.descriptors.begin(), mono.descriptors.begin() + kStereo);
  std::map<bool, double> farthest;
  for (bool limited : {false, true}) {
    tracking::ObjectTrackingOptions options;  // limited: the defaults
    if (!limited) options.window_max_point_move_depth_ratio = 1e6;
    auto tracker = make_tracker(options);
    for (int i = 0; i < kFrames; ++i) {
      SceneFrame f(i);
      f.add_car(stereo, i, instance_id(i));
      f.mono = f.round_uv = true;
      f.add_car(mono, i, 0);  // inside the stereo points' mask rectangle
      f.mono = f.round_uv = false;
      f.add_background(background);
      tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp);
      if (i == 0) {
        ASSERT_EQ(tracker.clusters().size(), 1u);
        EXPECT_GT(tracker.clusters()[0].points.size(), size_t{kStereo}) << "depth-filled points joined";
      }
    }
    ASSERT_EQ(tracker.tracks().size(), 1u);
    farthest[limited] = farthest_from_body(tracker, car, kFrames - 1);
    if (limited) {  // the track still follows the car
      expect_motion(tracker.tracks()[0], car, 0);
      const Mat4 err = geometry::se3_inverse(car.pose(kFrames - 1)) * tracker.tracks()[0].frames.back().T_w_o;
      EXPECT_LT((err.topRightCorner<3, 1>().norm()), 3.0);  // the frame's origin: the points' centre
    }
  }
  // measured: free, a point ends 53 m from the body (60-310 m deep during the run); limited,
  // the runaways are culled and every point left lies within 0.5 m of it
  EXPECT_GT(farthest[false], 20.0);
  EXPECT_LT(farthest[true], 2.0);
}

}  // namespace
