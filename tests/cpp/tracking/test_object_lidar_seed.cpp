// The LiDAR returns on an instance's own mask (object_lidar_seed.cpp): they complete a new
// cluster's seed where stereo fails, and keep stereo depths off their surface out of it, on the
// synthetic scenes of tracker_scene.hpp (the camera at the world origin).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "tracking/tracker_scene.hpp"

using namespace twistslam;

namespace {

// Returns on every face of the car's box at frame i, 5-10 cm apart (car_scan's ~20 returns per
// m^2 leave a keypoint at 15 m without the 4 returns within 6 px a local depth needs; an HDL-64
// gives ~200). The hidden faces too, so that every keypoint of the car's silhouette has returns
// around it: the local fit's layer rule keeps the nearer faces.
Points3 box_surface_scan(const Car& car, int i) {
  std::vector<Vec3> pts;
  const Vec3 half(kLength / 2, kHeight / 2, kWidth / 2);
  for (double a = -half.x(); a <= half.x(); a += 0.05) {
    for (double y = -half.y(); y <= half.y(); y += 0.1)
      for (const double side : {-1.0, 1.0}) pts.push_back(on_car(car, i, Vec3(a, y, side * half.z())));
    for (double z = -half.z(); z <= half.z(); z += 0.1)
      for (const double side : {-1.0, 1.0}) pts.push_back(on_car(car, i, Vec3(a, side * half.y(), z)));
  }
  for (double y = -half.y(); y <= half.y(); y += 0.05)
    for (double z = -half.z(); z <= half.z(); z += 0.05)
      for (const double side : {-1.0, 1.0}) pts.push_back(on_car(car, i, Vec3(side * half.x(), y, z)));
  Points3 out(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t k = 0; k < pts.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = pts[k].transpose();
  return out;
}

struct LidarSeed : TrackerScene {
  // A car 15 m ahead, driving across the view (its near face, 0.9 m before its centre, is what
  // the LiDAR sees).
  Car car = make_car(rng, Vec3(-2, 0.5, 15), Vec3(0.3, 0, 0.1), 0.0);

  // The final smoothing (smooth_tracks) of `frames` frames, the camera at the world origin.
  static void smooth_at_origin(tracking::ObjectTracker& tracker, int frames) {
    std::map<int, Mat4> T_c_w_of_frame;
    for (int i = 0; i < frames; ++i) T_c_w_of_frame[i] = Mat4::Identity();
    tracker.smooth_tracks(T_c_w_of_frame);
  }

  // `frames` frames of the car with its scan; `configure` sets up each frame's stereo.
  template <typename Configure>
  void run(tracking::ObjectTracker& tracker, int frames, Configure&& configure) {
    for (int i = 0; i < frames; ++i) {
      SceneFrame f(i);
      configure(f);
      f.add_car(car, i, instance_id(i));
      f.add_background(background);
      const Points3 scan = box_surface_scan(car, i);
      tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp, cv::Mat(),
                    Vec4::Zero(), {}, &scan);
    }
  }
};

// The right camera sees none of the car (hidden behind a nearer one there): no stereo point,
// no road labels for a ground contact. Its mask's LiDAR returns place it.
TEST_F(LidarSeed, KeypointsWithoutStereoTakeTheirMasksLidarDepth) {
  for (const bool use_lidar : {true, false}) {
    tracking::ObjectLidarOptions lidar;
    lidar.instance_lidar_depth = use_lidar;
    auto tracker = make_tracker({}, lidar);
    run(tracker, 3, [](SceneFrame& f) { f.mono = true; });
    if (!use_lidar) {
      EXPECT_TRUE(tracker.tracks().empty()) << "no depth cue: no cluster";
      continue;
    }
    ASSERT_EQ(tracker.tracks().size(), 1u);
    const objects::ObjectTrack& track = tracker.tracks()[0];
    EXPECT_EQ(track.frames.front().frame, 0) << "seeded in the first frame";
    EXPECT_EQ(track.frames.size(), 3u);
    // the seed's points lie on the near face (14.1 m): its centroid, not a stereo guess
    EXPECT_NEAR(track.frames.front().T_w_o(2, 3), 14.1, 0.4);
    EXPECT_NEAR(track.frames.front().T_w_o(0, 3), -2.0, 0.5);
  }
}

// A far car's mask (its returns' median beyond instance_lidar_max_depth_m) takes no LiDAR depth:
// a few returns on a small mask give poor local planes.
TEST_F(LidarSeed, FarMasksTakeNoLidarDepth) {
  car = make_car(rng, Vec3(-4, 0.5, 40), Vec3(0.3, 0, 0.1), 0.0);
  for (const double max_depth_m : {30.0, 50.0}) {
    tracking::ObjectLidarOptions lidar;
    lidar.instance_lidar_max_depth_m = max_depth_m;
    auto tracker = make_tracker({}, lidar);
    run(tracker, 2, [](SceneFrame& f) { f.mono = true; });
    if (max_depth_m < 40) {
      EXPECT_TRUE(tracker.tracks().empty());
    } else {
      ASSERT_EQ(tracker.tracks().size(), 1u);
      EXPECT_NEAR(tracker.tracks()[0].frames[0].T_w_o(2, 3), 40.0, 1.0) << "on the car";
    }
  }
}

// Every stereo depth of the car 40 % short (matches on a nearer car's edge): with the check
// (its default tolerance) they join no cluster; without it the cluster starts 5-6 m before the
// car. The mask test of seed_points (median of the mask's returns) is loosened so that only the
// local check acts.
TEST_F(LidarSeed, StereoDepthsOffTheLidarSurfaceJoinNoCluster) {
  for (const bool check : {true, false}) {
    tracking::ObjectLidarOptions lidar;
    lidar.mask_max_depth_ratio = 2.0;
    if (!check) lidar.instance_lidar_max_depth_error = 0;
    auto tracker = make_tracker({}, lidar);
    run(tracker, 2, [](SceneFrame& f) { f.stereo_depth_scale = 0.6; });
    if (check) {
      EXPECT_TRUE(tracker.tracks().empty()) << "no cluster off the LiDAR's surface";
    } else {
      ASSERT_EQ(tracker.tracks().size(), 1u);
      EXPECT_LT(tracker.tracks()[0].frames[0].T_w_o(2, 3), 10.0) << "at the wrong stereo depths";
    }
  }
  // true stereo depths pass the check: the car starts at its range
  auto tracker = make_tracker();
  run(tracker, 2, [](SceneFrame&) {});
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_NEAR(tracker.tracks()[0].frames[0].T_w_o(2, 3), 15.0, 1.0);
}

// keypoint_lidar_depth (object_keypoint_lidar_depth.cpp): the car's keypoints take the
// depth of the returns on their own mask (here those of its near face, as a LiDAR sees it).
// Mode 1, with no stereo at all and the seed's own LiDAR completion off: those depths alone
// start the cluster and keep it on the near face (14.1 m) for all 6 frames, reported from its
// first tracked frame on; mode 0 starts none.
// Mode 2 with every stereo depth 40 % short (matches on a nearer edge): they are replaced and
// the cluster lies on the car, where mode 0 starts none (the check refuses them).
TEST_F(LidarSeed, VehicleKeypointsTakeTheirMasksLidarDepth) {
  auto near_face_scan = [&](int i) {
    const Points3 all = box_surface_scan(car, i);
    const double face_z = car.pose(i)(2, 3) - 0.9;
    std::vector<Eigen::Index> rows;
    for (Eigen::Index r = 0; r < all.rows(); ++r)
      if (all(r, 2) < face_z + 0.05) rows.push_back(r);
    Points3 out(static_cast<Eigen::Index>(rows.size()), 3);
    for (size_t r = 0; r < rows.size(); ++r) out.row(static_cast<Eigen::Index>(r)) = all.row(rows[r]);
    return out;
  };
  auto run_with = [&](tracking::ObjectTracker& tracker, int frames, bool mono, double scale) {
    for (int i = 0; i < frames; ++i) {
      SceneFrame f(i);
      f.mono = mono;
      f.stereo_depth_scale = scale;
      f.add_car(car, i, instance_id(i));
      f.add_background(background);
      const Points3 scan = near_face_scan(i);
      tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp, cv::Mat(),
                    Vec4::Zero(), {}, &scan);
    }
  };
  for (const int mode : {0, 1}) {
    tracking::ObjectLidarOptions lidar;
    lidar.instance_lidar_depth = false;
    lidar.keypoint_lidar_depth = mode;
    auto tracker = make_tracker({}, lidar);
    run_with(tracker, 6, true, 1.0);
    if (mode == 0) {
      EXPECT_TRUE(tracker.tracks().empty()) << "no depth cue: no cluster";
      continue;
    }
    ASSERT_EQ(tracker.tracks().size(), 1u);
    const objects::ObjectTrack& track = tracker.tracks()[0];
    ASSERT_EQ(track.frames.size(), 6u);
    EXPECT_GE(track.hits, 5);
    for (const objects::TrackFrame& r : track.frames) {
      EXPECT_NEAR(r.T_w_o(2, 3), car.pose(r.frame)(2, 3) - 0.9, 0.4) << "frame " << r.frame;
      // a seed from the scan's depths is reported once tracked (as the seed's LiDAR completion)
      EXPECT_EQ(r.reported, r.frame > 0) << "frame " << r.frame;
    }
  }
  for (const int mode : {0, 2}) {
    tracking::ObjectLidarOptions lidar;
    lidar.mask_max_depth_ratio = 2.0;  // only the keypoints' own test acts (as above)
    lidar.keypoint_lidar_depth = mode;
    auto tracker = make_tracker({}, lidar);
    run_with(tracker, 3, false, 0.6);
    if (mode == 0) {
      EXPECT_TRUE(tracker.tracks().empty()) << "the check refuses every stereo point";
      continue;
    }
    ASSERT_EQ(tracker.tracks().size(), 1u);
    EXPECT_NEAR(tracker.tracks()[0].frames[0].T_w_o(2, 3), 14.1, 0.4) << "on the near face";
  }
}

// A camera-only car whose stereo depths are all 10 % short (a disparity bias, as far cars'
// corners on a nearer occluder's edge take): its points lie ~4 m before the returns on its
// mask, so once lidar_check_min_rows rows agree its rows are not reported, the earlier ones
// too (object_lidar_check.cpp); still tracked, and reported with unbiased stereo, with the
// check off, or 5 % long (median ratio 0.97, 1.3 m beyond the returns: inside the far side's
// wider bounds). 15 % long (~5 m beyond) is hidden by the far side, unless that side is off.
TEST_F(LidarSeed, RowsTheMasksReturnsContradictAreNotReported) {
  car = make_car(rng, Vec3(-2, 0.5, 40), Vec3(0.3, 0, 0.1), 0.0);
  auto reported = [](const objects::ObjectTrack& t) {
    int n = 0;
    for (const auto& r : t.frames) n += r.reported;
    return n;
  };
  for (const double scale : {1.0, 0.9, 1.05, 1.15})
    for (const bool check : {true, false}) {
      tracking::ObjectLidarOptions lidar;
      if (!check) lidar.lidar_check_max_ratio = 0, lidar.lidar_check_max_far_ratio = 0;
      auto tracker = make_tracker({}, lidar);
      run(tracker, 6, [scale](SceneFrame& f) { f.stereo_depth_scale = scale; });
      ASSERT_EQ(tracker.tracks().size(), 1u) << scale << " " << check;
      const objects::ObjectTrack& track = tracker.tracks()[0];
      ASSERT_EQ(track.frames.size(), 6u);
      EXPECT_GE(track.hits, 5) << "tracked either way";
      const double depth = (track.last().T_c_w * track.last().T_w_o)(2, 3);
      EXPECT_NEAR(depth, scale * 40.0, 0.04 * scale * 40.0) << "where the stereo placed it";
      EXPECT_EQ(reported(track), (scale < 1.0 || scale > 1.07) && check ? 0 : 6)
          << scale << " " << check;
    }
  // each side switched off alone leaves the other acting
  for (const double scale : {0.9, 1.15}) {
    tracking::ObjectLidarOptions lidar;
    (scale < 1.0 ? lidar.lidar_check_max_far_ratio : lidar.lidar_check_max_ratio) = 0;
    auto tracker = make_tracker({}, lidar);
    run(tracker, 6, [scale](SceneFrame& f) { f.stereo_depth_scale = scale; });
    ASSERT_EQ(tracker.tracks().size(), 1u) << scale;
    EXPECT_EQ(reported(tracker.tracks()[0]), 0) << scale << ": the other side is off";
  }
}

// The LiDAR sees the car 10 % farther than the stereo in its first 5 frames (a scan moved
// along its rays), then where the stereo does. Online, the track's medians contradict it until
// its unbiased rows are the majority (frame 10): rows 0-9 hidden, 10-14 reported. At the end
// (smooth_tracks) the medians over all 15 rows decide: every row is reported again. A scan
// 10 % farther in every frame keeps them all hidden.
TEST_F(LidarSeed, TheWholeTracksMediansDecideAtTheEnd) {
  car = make_car(rng, Vec3(-2, 0.5, 40), Vec3(0.3, 0, 0.1), 0.0);
  for (const int biased_frames : {5, 15}) {
    auto tracker = make_tracker();
    std::map<int, Mat4> T_c_w_of_frame;
    for (int i = 0; i < 15; ++i) {
      SceneFrame f(i);
      f.add_car(car, i, instance_id(i));
      f.add_background(background);
      const Points3 scan = (i < biased_frames ? 1.1 : 1.0) * box_surface_scan(car, i);
      tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp, cv::Mat(),
                    Vec4::Zero(), {}, &scan);
      T_c_w_of_frame[i] = Mat4::Identity();
    }
    ASSERT_EQ(tracker.tracks().size(), 1u);
    auto reported = [&] {
      std::vector<int> out;
      for (const auto& r : tracker.tracks()[0].frames) out.push_back(r.reported);
      return out;
    };
    ASSERT_EQ(reported().size(), 15u);
    const std::vector<int> online = reported();
    for (int i = 0; i < 15; ++i)
      EXPECT_EQ(online[i], biased_frames == 5 && i >= 10) << biased_frames << " biased, row " << i;
    tracker.smooth_tracks(T_c_w_of_frame);
    EXPECT_EQ(reported(), std::vector<int>(15, biased_frames == 5)) << biased_frames << " biased";
  }
}

// The same 10 % short stereo, with a 3D box in the first frame (a frame that is not the box's:
// canonical_pose off). A track with boxes is placed by them, not by its points' depth: its
// rows are all reported.
TEST_F(LidarSeed, ATrackWithBoxesIsNotJudgedByItsPointsDepth) {
  car = make_car(rng, Vec3(-2, 0.5, 40), Vec3(0.3, 0, 0.1), 0.0);
  tracking::ObjectLidarOptions lidar;
  lidar.canonical_pose = false;
  auto tracker = make_tracker({}, lidar);
  for (int i = 0; i < 6; ++i) {
    SceneFrame f(i);
    f.stereo_depth_scale = 0.9;
    f.add_car(car, i, instance_id(i));
    f.add_background(background);
    const Points3 scan = box_surface_scan(car, i);
    std::vector<objects::Detection> boxes;
    if (i == 0) {
      const Mat4 P = car.pose(i);
      objects::Detection d;
      d.box.center = P.topRightCorner<3, 1>();
      d.box.length = kLength, d.box.width = kWidth, d.box.height = kHeight;
      d.box.yaw = std::atan2(-P(2, 0), P(0, 0));
      d.score = 1.0;
      d.class_id = kCar;
      boxes.push_back(d);
    }
    tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp, cv::Mat(),
                  Vec4::Zero(), boxes, &scan);
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  const objects::ObjectTrack& track = tracker.tracks()[0];
  ASSERT_FALSE(track.canonical);
  ASSERT_TRUE(track.frames[0].has_detection());
  ASSERT_GE(track.lidar_depth_ratios.size(), 5u) << "its rows without a box were checked";
  for (const auto& r : track.frames) EXPECT_TRUE(r.reported) << "frame " << r.frame;
}

}  // namespace

// A far camera-only car whose stereo depths are 5 % long or 3 % short (inside the LiDAR
// check's bounds: still reported). At the end (smooth_tracks) its rows move along their lines
// of sight to the returns' depth (object_lidar_align.cpp): at 40 m the scale is ramped in to
// 2 / 3 or more of the ratio (far_lidar_align_ramp_m 15 beyond 30 m): beyond 40 m over 40 % of
// the error goes (the synthetic scan covers every face, so a point meets returns of both). With
// the alignment off, for a car at 20 m (nearer than far_lidar_align_min_depth_m), and for the
// rows nearer than that bound of a car coming from 42 m to 28 m, the rows stay where the stereo
// put them.
TEST_F(LidarSeed, FarRowsMoveToTheirReturnsDepthAtTheEnd) {
  struct Case {
    double z0, vz;  // m, m/frame along the camera's z
  };
  for (const Case c : {Case{40.0, 0.1}, Case{20.0, 0.1}, Case{42.0, -1.6}})
    for (const double scale : {1.05, 0.97}) {
      std::vector<double> depth[2];  // per row, without / with the alignment
      car = make_car(rng, Vec3(-2, 0.5, c.z0), Vec3(0.3, 0, c.vz), 0.0);  // one car both ways
      for (const bool align : {false, true}) {
        tracking::ObjectLidarOptions lidar;
        if (!align) lidar.far_lidar_align_min_depth_m = 0;
        auto tracker = make_tracker({}, lidar);
        std::map<int, Mat4> T_c_w_of_frame;
        run(tracker, 10, [scale](SceneFrame& f) { f.stereo_depth_scale = scale; });
        for (int i = 0; i < 10; ++i) T_c_w_of_frame[i] = Mat4::Identity();
        ASSERT_EQ(tracker.tracks().size(), 1u) << c.z0 << " " << scale;
        tracker.smooth_tracks(T_c_w_of_frame);
        const objects::ObjectTrack& track = tracker.tracks()[0];
        ASSERT_EQ(track.frames.size(), 10u);
        for (const objects::TrackFrame& row : track.frames) {
          EXPECT_TRUE(row.reported) << c.z0 << " " << scale << " " << align;
          depth[align].push_back(row.T_w_o(2, 3));
        }
      }
      for (int i = 0; i < 10; ++i) {
        const double truth = car.pose(i)(2, 3), stereo_error = depth[0][i] - truth;
        EXPECT_GT(std::abs(stereo_error), 0.6 * std::abs(scale - 1.0) * truth) << "the bias is there";
        if (depth[0][i] < 30.0) {
          EXPECT_DOUBLE_EQ(depth[1][i], depth[0][i]) << c.z0 << " row " << i << ": nearer than the bound";
        } else if (depth[0][i] > 40.0) {
          EXPECT_LT(std::abs(depth[1][i] - truth), 0.6 * std::abs(stereo_error))
              << c.z0 << " " << scale << " row " << i << ": stereo " << depth[0][i] << ", aligned "
              << depth[1][i] << ", truth " << truth;
        }
      }
    }
}

// A far camera-only free-link track whose stereo puts it a quarter nearer than it is (urban
// s34's track 35: a pedestrian standing at 46-41 m, reported at 35-28 m, its rows' origins 27-38 %
// in front of the returns on its mask). No move within far_lidar_align_max_ratio can put it
// there: with far_lidar_align_free_hide_beyond its far rows are not reported; without it, or
// with the points' ratio (far_lidar_align_free_from_origin off, which leaves such rows out), they
// are, where the stereo put them.
TEST_F(LidarSeed, FarFreeLinkRowsTheReturnsContradictAreNotReported) {
  car = make_car(rng, Vec3(-2, 0.5, 45.0), Vec3(0.3, 0, -0.5), 0.0);
  struct Case {
    bool from_origin, hide;
  };
  for (const Case c : {Case{true, true}, Case{true, false}, Case{false, true}}) {
    tracking::ObjectTrackingOptions options;
    options.planar_class_ids = {};
    tracking::ObjectLidarOptions lidar;
    lidar.far_lidar_align_min_depth_m = 0;  // the vehicles' alignment: not this track's
    lidar.far_lidar_align_free_from_origin = c.from_origin;
    lidar.far_lidar_align_free_hide_beyond = c.hide;
    // the birth's LiDAR gates would refuse these points (StereoDepthsOffTheLidarSurfaceJoinNoCluster);
    // off, the test holds the final rows' rule alone, as for a pedestrian whose thin mask keeps
    // few returns around its points
    lidar.mask_max_depth_ratio = 2.0;
    lidar.instance_lidar_max_depth_error = 0;
    auto tracker = make_tracker(options, lidar);
    run(tracker, 10, [](SceneFrame& f) { f.stereo_depth_scale = 0.75; });
    ASSERT_EQ(tracker.tracks().size(), 1u);
    std::map<int, Mat4> T_c_w_of_frame;
    for (int i = 0; i < 10; ++i) T_c_w_of_frame[i] = Mat4::Identity();
    std::vector<double> before;
    for (const objects::TrackFrame& r : tracker.tracks()[0].frames) before.push_back(r.T_w_o(2, 3));
    tracker.smooth_tracks(T_c_w_of_frame);
    const objects::ObjectTrack& track = tracker.tracks()[0];
    ASSERT_EQ(track.frames.size(), 10u);
    int far_rows = 0;
    for (size_t i = 0; i < track.frames.size(); ++i) {
      const objects::TrackFrame& r = track.frames[i];
      const double truth = car.pose(static_cast<int>(i))(2, 3);
      if (r.T_w_o(2, 3) < 25.0) continue;
      ++far_rows;
      EXPECT_LT(r.T_w_o(2, 3), 0.85 * truth) << "row " << i << ": the stereo's quarter is there";
      const bool hidden = c.from_origin && c.hide;
      EXPECT_EQ(r.reported, !hidden) << c.from_origin << c.hide << " row " << i << " at " << r.T_w_o(2, 3);
    }
    EXPECT_GE(far_rows, 8) << "the track's rows lie beyond 25 m";
  }
}

// A camera-only car at 15 m whose stereo depths are 12 % short: its origin lies in front of the
// near face the LiDAR sees (crowded s21's DIS ghost 27: 2.2 m in front of a car's rear at
// 15.7 m). At the end (smooth_tracks) each row moves onto the face its own mask's returns
// measured (lidar_objects.near_lidar_surface_lift); without the lift the rows stay in front of
// it. The LiDAR check is off here: every point of this car is short by the same fraction, and
// its track medians would hide the whole track (the ghost's drifted onto its car, and passed).
TEST_F(LidarSeed, NearVehicleRowsInFrontOfTheirFaceMoveOntoIt) {
  std::vector<double> depth[2], face;
  for (const bool lift : {false, true}) {
    tracking::ObjectLidarOptions lidar;
    lidar.near_lidar_surface_lift = lift;
    lidar.lidar_check_max_ratio = 0;
    auto tracker = make_tracker({}, lidar);
    run(tracker, 10, [](SceneFrame& f) { f.stereo_depth_scale = 0.88; });
    ASSERT_EQ(tracker.tracks().size(), 1u);
    smooth_at_origin(tracker, 10);
    const objects::ObjectTrack& track = tracker.tracks()[0];
    ASSERT_EQ(track.frames.size(), 10u);
    for (const objects::TrackFrame& r : track.frames) {
      EXPECT_TRUE(r.reported) << "row " << r.frame << ": inside the LiDAR check's bounds";
      depth[lift].push_back(r.T_w_o(2, 3));
      if (lift) face.push_back(r.lidar_face_depth_m);
    }
  }
  for (int i = 0; i < 10; ++i) {
    const double near_face = car.pose(i)(2, 3) - kWidth / 2;  // the side the camera sees
    ASSERT_TRUE(std::isfinite(face[i])) << "row " << i << " kept its face";
    EXPECT_NEAR(face[i], near_face, 0.15) << "row " << i << ": the nearest tenth of its returns";
    EXPECT_LT(depth[0][i], near_face - 0.5) << "row " << i << ": the stereo's shortfall is there";
    EXPECT_GE(depth[1][i], 0.985 * face[i]) << "row " << i << ": on its face, less the 1 % margin";
    EXPECT_LE(depth[1][i], face[i]) << "row " << i << ": not beyond it";
  }
}

// The same car cut by the image's right border (its centre at 6 m right of the camera, 9 m
// ahead: the part in view is its farther end): no row keeps a face, and none moves, though its
// origin lies as far in front of its returns as in the test above.
TEST_F(LidarSeed, NoFaceIsKeptForACarTheImageCuts) {
  car = make_car(rng, Vec3(6.5, 0.5, 9.0), Vec3(0.0, 0, 0.05), 0.0);
  ASSERT_GT(kCamera.project(car.pose(0).topRightCorner<3, 1>() + Vec3(kLength / 2, 0, 0)).x(), kCamera.width)
      << "the car's right end is out of the image";
  std::vector<double> depth[2];
  for (const bool lift : {false, true}) {
    tracking::ObjectLidarOptions lidar;
    lidar.near_lidar_surface_lift = lift;
    lidar.lidar_check_max_ratio = 0;
    auto tracker = make_tracker({}, lidar);
    for (int i = 0; i < 10; ++i) {  // run(), with the mask carried on to the border as the car is
      SceneFrame f(i);
      f.stereo_depth_scale = 0.88;
      f.add_car(car, i, instance_id(i));
      f.add_background(background);
      for (int r = 0; r < f.instances.rows; ++r)
        for (int c = 0; c < f.instances.cols; ++c)
          if (f.instances.at<int>(r, c) == instance_id(i)) {
            f.instances.row(r).colRange(c, f.instances.cols).setTo(instance_id(i));
            break;
          }
      const Points3 scan = box_surface_scan(car, i);
      tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp, cv::Mat(), Vec4::Zero(), {}, &scan);
    }
    ASSERT_EQ(tracker.tracks().size(), 1u);
    smooth_at_origin(tracker, 10);
    for (const objects::TrackFrame& r : tracker.tracks()[0].frames) {
      EXPECT_FALSE(std::isfinite(r.lidar_face_depth_m)) << "row " << r.frame << " kept a face";
      depth[lift].push_back(r.T_w_o(2, 3));
    }
  }
  ASSERT_EQ(depth[0].size(), depth[1].size());
  for (size_t i = 0; i < depth[0].size(); ++i) EXPECT_DOUBLE_EQ(depth[1][i], depth[0][i]) << "row " << i;
}

// A far camera-only track on the free link (every link free: planar_class_ids empty; a
// pedestrian's, a cyclist's), its stereo depths biased by a fraction that grows row by row (a far
// track drifting along its line of sight, as urban s24's pedestrian ghost 18), or 5 % long in
// every row. At the end each row beyond far_lidar_align_free_min_depth_m moves by the running
// median of its own and its neighbours' ratios: every row's error shrinks, the last rows' most
// (one track-wide ratio would over-correct the first and under-correct the last). With the
// window 0 the rows stay where the stereo put them, and a car at 20 m (nearer than the bound)
// is not moved.
TEST_F(LidarSeed, FarFreeLinkRowsMoveEachToItsOwnReturnsDepth) {
  struct Case {
    double z0, drift_per_row, bias;  // m, stereo depth scale 1 + bias + drift_per_row * row
  };
  for (const Case c : {Case{40.0, 0.008, 0.0}, Case{40.0, 0.0, 0.05}, Case{20.0, 0.0, 0.05}}) {
    std::vector<double> depth[2];  // per row, window off / on
    car = make_car(rng, Vec3(-2, 0.5, c.z0), Vec3(0.3, 0, 0.1), 0.0);
    for (const bool align : {false, true}) {
      tracking::ObjectTrackingOptions options;
      options.planar_class_ids = {};
      tracking::ObjectLidarOptions lidar;
      lidar.far_lidar_align_min_depth_m = 0;  // the vehicles' alignment: not this track's
      if (!align) lidar.far_lidar_align_free_window_rows = 0;
      auto tracker = make_tracker(options, lidar);
      int row = 0;
      run(tracker, 10, [&](SceneFrame& f) { f.stereo_depth_scale = 1.0 + c.bias + c.drift_per_row * row++; });
      ASSERT_EQ(tracker.tracks().size(), 1u) << c.z0;
      ASSERT_NE(tracker.tracks()[0].link, geometry::LinkType::kPlanar);
      smooth_at_origin(tracker, 10);
      const objects::ObjectTrack& track = tracker.tracks()[0];
      ASSERT_EQ(track.frames.size(), 10u);
      for (const objects::TrackFrame& r : track.frames) {
        EXPECT_TRUE(r.reported) << c.z0 << " " << align;
        depth[align].push_back(r.T_w_o(2, 3));
      }
    }
    for (int i = 0; i < 10; ++i) {
      const double truth = car.pose(i)(2, 3), stereo_error = depth[0][i] - truth;
      const double bias = c.bias + c.drift_per_row * i;
      if (c.z0 < 25.0) {
        EXPECT_DOUBLE_EQ(depth[1][i], depth[0][i]) << "row " << i << ": nearer than the bound";
        continue;
      }
      if (bias < 0.03) continue;  // the first rows of the drift: their error is the points' spread
      EXPECT_GT(stereo_error, 0.4 * bias * truth) << "row " << i << ": the bias is there";
      EXPECT_LT(std::abs(depth[1][i] - truth), 0.6 * stereo_error)
          << c.drift_per_row << " row " << i << ": stereo " << depth[0][i] << ", aligned " << depth[1][i]
          << ", truth " << truth;
    }
    if (c.drift_per_row > 0) {  // each row by its own ratio: the drift itself goes, not only its mean
      auto error = [&](int side, int i) { return depth[side][i] - car.pose(i)(2, 3); };
      EXPECT_LT(std::abs(error(1, 9) - error(1, 4)), 0.5 * (error(0, 9) - error(0, 4)))
          << "aligned errors " << error(1, 4) << " .. " << error(1, 9) << ", stereo " << error(0, 4) << " .. "
          << error(0, 9);
    }
  }
}

// A far camera-only car at 45 m whose stereo depths lag further behind it row by row, 4 % more
// each row (urban s40's DIS
// ghost 29: a parked car at 60-45 m tracked as if it drove with the camera, its rows 0.1 m off
// the returns on its mask at 55 m and 4.3 m beyond them at 50 m). The track-wide scale moves
// every row by one ratio and leaves the last rows metres beyond the car; with
// far_lidar_align_max_behind_m each row whose running median lies more than that beyond the
// median depth of its mask's returns moves nearer by the excess. The first rows, within the
// bound, stay where the track-wide scale put them.
TEST_F(LidarSeed, FarVehicleRowsLaggingBehindTheirReturnsMoveNearer) {
  car = make_car(rng, Vec3(-2, 0.5, 45.0), Vec3(0.3, 0, 0.1), 0.0);
  const double max_behind_m = 1.5;
  std::vector<double> depth[2];  // per row, the rule off / on
  std::vector<double> returns_m;
  for (const bool pull : {false, true}) {
    tracking::ObjectLidarOptions lidar;
    lidar.lidar_check_max_ratio = 0;  // every row is off by its own fraction: the check would hide them
    lidar.far_lidar_align_max_behind_m = pull ? max_behind_m : 0.0;
    auto tracker = make_tracker({}, lidar);
    int row = 0;
    run(tracker, 10, [&](SceneFrame& f) { f.stereo_depth_scale = 1.0 + 0.04 * row++; });
    ASSERT_EQ(tracker.tracks().size(), 1u);
    ASSERT_EQ(tracker.tracks()[0].link, geometry::LinkType::kPlanar);
    smooth_at_origin(tracker, 10);
    const objects::ObjectTrack& track = tracker.tracks()[0];
    ASSERT_EQ(track.frames.size(), 10u);
    for (const objects::TrackFrame& r : track.frames) {
      EXPECT_TRUE(r.reported) << "row " << r.frame;
      depth[pull].push_back(r.T_w_o(2, 3));
      if (!pull) continue;
      ASSERT_GT(r.far_lidar_returns.rows(), 0) << "row " << r.frame << " kept its returns";
      std::vector<double> d;
      for (Eigen::Index i = 0; i < r.far_lidar_returns.rows(); ++i) d.push_back(r.far_lidar_returns(i, 2));
      std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
      returns_m.push_back(d[d.size() / 2]);
    }
  }
  int lagging = 0;
  for (int i = 0; i < 10; ++i) {
    const double behind_before = depth[0][i] - returns_m[i], behind_after = depth[1][i] - returns_m[i];
    if (behind_before <= max_behind_m) {
      EXPECT_DOUBLE_EQ(depth[1][i], depth[0][i]) << "row " << i << ": within the bound";
      continue;
    }
    ++lagging;
    EXPECT_LT(depth[1][i], depth[0][i]) << "row " << i << " moved nearer";
    // the running median of 7 rows trails a steady drift at the track's end by a row's step
    EXPECT_LE(behind_after, max_behind_m + 0.9) << "row " << i << ": " << behind_before << " m behind before";
    EXPECT_GE(behind_after, max_behind_m - 0.9) << "row " << i << ": not past the returns";
  }
  EXPECT_GE(lagging, 3) << "the last rows lag more than the bound behind the returns";
  EXPECT_GT(depth[0][9] - returns_m[9], 2.5) << "the track-wide scale leaves the last row metres beyond";
}
