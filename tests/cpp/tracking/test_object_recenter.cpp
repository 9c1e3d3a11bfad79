// The re-centring of an object cluster's frame on its points (ObjectTracker::recenter, through
// the tracker's public state): a rigid box of points tracked by ObjectTracker, with and without
// the re-centring and its bounds.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

#include "common/kitti_camera.hpp"
#include "common/random_descriptor.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

using namespace twistslam;
namespace ts = twistslam::test_scenes;

namespace {

Vec3 transform(const Mat4& T, const Vec3& X) { return T.topLeftCorner<3, 3>() * X + T.topRightCorner<3, 1>(); }

const Vec3 kUp(0, -1, 0);
constexpr int kCarClass = 26, kRoadClass = 7;  // Cityscapes; cars have a planar link

using test_scenes::random_descriptor;

// A rigid box of points moving on the road in front of a static rig (camera at the world
// origin); its first frame shows only its points with x_o > kFirstSeenX (~40 %), so the
// cluster is born at their centroid, ~1.25 m off the box's centre.
struct MovingBox {
  std::vector<Vec3> X_o;
  std::vector<map::Descriptor> descriptors;
  Vec3 c0{-2, 0.5, 15};
  Vec3 velocity{0.3, 0, 0.05};  // m/frame
  double yaw_rate = 0.01;       // rad/frame about kUp
  int hide_front_from = -1;     // from this frame on, points with x_o > 0 are not seen (-1: never)
  Mat4 pose(int i) const {
    return geometry::make_pose(geometry::so3_exp(kUp * (yaw_rate * i)), c0 + velocity * i);
  }
};
constexpr double kFirstSeenX = 0.5;  // m, object frame

// Frame i: the box's keypoints (in frame 0 only those with x_o > kFirstSeenX), a mask box around them, the flow
// from frame i - 1 at their previous positions, and static background keypoints.
struct BoxFrame {
  tracking::Frame frame;
  cv::Mat instances, flow;
  BoxFrame(const MovingBox& box, const geometry::StereoCamera& cam, int i) {
    frame.index = i;
    instances = cv::Mat::zeros(cam.height, cam.width, CV_32SC1);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    flow = cv::Mat(cam.height, cam.width, CV_32FC2, cv::Scalar(nan, nan));
    double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
    for (size_t k = 0; k < box.X_o.size(); ++k) {
      if (i == 0 && box.X_o[k].x() <= kFirstSeenX) continue;
      if (box.hide_front_from >= 0 && i >= box.hide_front_from && box.X_o[k].x() > 0) continue;
      const Vec3 X = transform(box.pose(i), box.X_o[k]);
      const Vec2 uv = cam.project(X), uv_prev = cam.project(transform(box.pose(i - 1), box.X_o[k]));
      add(cam, X, box.descriptors[k], kCarClass, static_cast<int>(k % 3));
      u0 = std::min(u0, uv.x()), v0 = std::min(v0, uv.y()), u1 = std::max(u1, uv.x()), v1 = std::max(v1, uv.y());
      for (int dy = 0; dy <= 1; ++dy)  // flow at the 2 x 2 pixels a bilinear read uses
        for (int dx = 0; dx <= 1; ++dx) {
          const int fx = static_cast<int>(uv_prev.x()) + dx, fy = static_cast<int>(uv_prev.y()) + dy;
          if (fx >= 0 && fy >= 0 && fx < flow.cols && fy < flow.rows)
            flow.at<cv::Vec2f>(fy, fx) = cv::Vec2f(static_cast<float>(uv.x() - uv_prev.x()),
                                                   static_cast<float>(uv.y() - uv_prev.y()));
        }
    }
    instances(cv::Rect(cv::Point(static_cast<int>(u0) - 2, static_cast<int>(v0) - 2),
                       cv::Point(static_cast<int>(u1) + 3, static_cast<int>(v1) + 3)))
        .setTo(3 + i % 5);  // a new instance id every frame
    std::uniform_real_distribution<double> u(5, cam.width - 6.0), v(5, cam.height - 6.0), z(30, 50);
    std::mt19937 background_rng(99);  // the same static background every frame
    for (int k = 0; k < 50; ++k) {
      const Vec3 X = cam.backproject(Vec2(u(background_rng), v(background_rng)), z(background_rng));
      add(cam, X, random_descriptor(background_rng), kRoadClass, 0);
    }
    const size_t n = frame.keypoints.size();
    frame.point_ids.assign(n, -1);
    frame.outlier.assign(n, 0);
    frame.grid.build(frame.keypoints.uv, cam.width, cam.height);
  }
  void add(const geometry::StereoCamera& cam, const Vec3& X_c, const map::Descriptor& d, int label, int octave) {
    auto& k = frame.keypoints;
    k.uv.push_back(cam.project(X_c));
    k.octave.push_back(octave);
    k.u_right.push_back(cam.project_right(X_c).x());
    k.depth.push_back(X_c.z() + cam.t_left.z());
    k.descriptors.push_back(d);
    k.label.push_back(label);
    frame.usable.push_back(label != kCarClass);
  }
};

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Per-axis median of the cluster's confirmed points (found twice or more), as recenter takes it.
Vec3 median_of_confirmed(const objects::ObjectCluster& cluster) {
  std::vector<double> axis[3];
  for (const objects::ObjectPoint& p : cluster.points)
    for (int a = 0; a < 3 && p.found >= 2; ++a) axis[a].push_back(p.X_o[a]);
  return Vec3(median(axis[0]), median(axis[1]), median(axis[2]));
}

struct RecenterRun {
  objects::ObjectTrack track;
  objects::ObjectCluster cluster;
};

RecenterRun track_box(const MovingBox& box, double recenter_distance_m, int frames,
                      tracking::ObjectTrackingOptions options = {}) {
  const geometry::StereoCamera cam = ts::kitti_camera();
  options.recenter_distance_m = recenter_distance_m;
  tracking::ObjectTracker tracker(cam, options, {1.0f, 1.2f, 1.44f, 1.728f},
                                  tracking::LevelWeights({1.0f, 1.44f, 2.07f, 2.99f}));
  for (int i = 0; i < frames; ++i) {
    const BoxFrame f(box, cam, i);
    const auto report = tracker.track(f.frame, f.instances, i > 0 ? f.flow : cv::Mat(), kUp);
    EXPECT_EQ(report.num_tracked, i > 0 ? 1 : 0) << "frame " << i;
  }
  EXPECT_EQ(tracker.tracks().size(), 1u);
  if (tracker.tracks().empty()) return {};
  return {tracker.tracks()[0], tracker.clusters()[0]};
}

TEST(ObjectTrackerRecenter, OriginFollowsThePointsAndTwistsStillLinkThePoses) {
  MovingBox box;
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> x(-2.0, 2.0), y(-0.75, 0.75), z(-0.9, 0.9);
  for (int k = 0; k < 80; ++k) {
    box.X_o.emplace_back(x(rng), y(rng), z(rng));
    box.descriptors.push_back(random_descriptor(rng));
  }
  constexpr int kFrames = 8;
  const tracking::ObjectTrackingOptions defaults;
  const RecenterRun on = track_box(box, defaults.recenter_distance_m, kFrames);
  const RecenterRun off = track_box(box, 0.0, kFrames);  // control: never re-centred
  ASSERT_EQ(on.track.frames.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(off.track.frames.size(), static_cast<size_t>(kFrames));

  const Vec3 median_on = median_of_confirmed(on.cluster), median_off = median_of_confirmed(off.cluster);
  // each origin against the box's centre in its last frame, in the world
  const Vec3 centre = box.pose(kFrames - 1).topRightCorner<3, 1>();
  const double origin_on = (on.track.last().T_w_o.topRightCorner<3, 1>() - centre).norm();
  const double origin_off = (off.track.last().T_w_o.topRightCorner<3, 1>() - centre).norm();
  std::cout << "[ recenter ] |median of confirmed points| " << median_on.norm() << " m (off: "
            << median_off.norm() << " m), origin to the box centre " << origin_on << " m (off: "
            << origin_off << " m)\n";
  EXPECT_GT(median_off.norm(), 1.0);  // the premise: born ~1.25 m off its points' centre
  constexpr double kToleranceM = 0.1;  // m: points added and culled after the last re-centring
  EXPECT_LE(median_on.norm(), defaults.recenter_distance_m + kToleranceM);
  EXPECT_GT(origin_off, 1.0);
  EXPECT_LT(origin_on, defaults.recenter_distance_m + 0.3);  // + the sampled points' median spread

  for (const RecenterRun* run : {&on, &off}) {
    const auto& rows = run->track.frames;
    for (size_t r = 0; r + 1 < rows.size(); ++r) {
      // eq. 2 with the stored twist: T_w_o(i+1) = exp(Pi xi_i) T_w_o(i)
      const Mat4 linked = geometry::se3_exp(run->track.Pi * rows[r].xi) * rows[r].T_w_o;
      // 5e-4: the window's planar poses are re-linked by a projected log (up to ~1e-4 off
      // without re-centring too); a translation applied on the wrong side would be off by ~1e-2
      EXPECT_LT((linked - rows[r + 1].T_w_o).norm(), 5e-4) << "row " << r << (run == &on ? " (on)" : " (off)");
      // and the motion between them is the box's (re-centring changes no world motion)
      const Mat4 est = rows[r + 1].T_w_o * geometry::se3_inverse(rows[r].T_w_o);
      const Mat4 truth = box.pose(rows[r].frame + 1) * geometry::se3_inverse(box.pose(rows[r].frame));
      EXPECT_LT((est.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>()).norm(), 0.02) << "row " << r;
    }
    // the points, placed with the poses, land on the box's true points in the last frame
    const Mat4 T = run->track.last().T_w_o;
    std::vector<double> distance;
    for (const objects::ObjectPoint& p : run->cluster.points) {
      const Vec3 X = transform(T, p.X_o);
      double best = 1e9;
      for (const Vec3& q : box.X_o) best = std::min(best, (transform(box.pose(kFrames - 1), q) - X).norm());
      distance.push_back(best);
    }
    EXPECT_LT(median(distance), 0.05);
  }
}

// recenter_max_spread_m: a far cluster whose confirmed points spread wider than a car is
// long (urban s7's lead car at 45-60 m, whose lagging track placed its later points metres
// ahead) keeps its origin where it is; the same cluster without the bound, or nearer than
// recenter_spread_min_depth_m, is re-centred.
TEST(ObjectTrackerRecenter, AFarClusterSpreadWiderThanTheBoundKeepsItsOrigin) {
  MovingBox box;
  std::mt19937 rng(78);
  std::uniform_real_distribution<double> x(-5.0, 5.0), y(-0.75, 0.75), z(-0.9, 0.9);
  for (int k = 0; k < 80; ++k) {  // 10 m long: a 10-90 % spread of ~8 m along x
    box.X_o.emplace_back(x(rng), y(rng), z(rng));
    box.descriptors.push_back(random_descriptor(rng));
  }
  constexpr int kFrames = 8;
  tracking::ObjectTrackingOptions options;
  options.max_point_spread_m = 12.0;  // every point of the box joins the cluster
  ASSERT_GT(options.recenter_max_spread_m, 0.0);
  ASSERT_LT(options.recenter_max_spread_m, 7.5);  // the premise: the points spread wider
  ASSERT_GT(options.recenter_spread_min_depth_m, box.c0.z() + 1.0);  // ... and the box is near
  const RecenterRun near = track_box(box, options.recenter_distance_m, kFrames, options);
  options.recenter_spread_min_depth_m = box.c0.z() - 3.0;  // the box lies beyond this
  const RecenterRun bounded = track_box(box, options.recenter_distance_m, kFrames, options);
  options.recenter_max_spread_m = 0.0;  // control: no bound
  const RecenterRun unbounded = track_box(box, options.recenter_distance_m, kFrames, options);
  for (const RecenterRun* run : {&near, &bounded, &unbounded})
    ASSERT_EQ(run->track.frames.size(), static_cast<size_t>(kFrames));

  // born at the centroid of its x > 0.5 m points, ~2.75 m along x from the box's centre
  std::cout << "[ recenter ] spread bound: |median of confirmed points| "
            << median_of_confirmed(bounded.cluster).norm() << " m (no bound: "
            << median_of_confirmed(unbounded.cluster).norm() << " m, nearer than its depth: "
            << median_of_confirmed(near.cluster).norm() << " m)\n";
  EXPECT_GT(median_of_confirmed(bounded.cluster).norm(), 1.0);
  EXPECT_LE(median_of_confirmed(unbounded.cluster).norm(), options.recenter_distance_m + 0.1);
  EXPECT_LE(median_of_confirmed(near.cluster).norm(), options.recenter_distance_m + 0.1);
  // the bounded track's first row still sits where it was born, at its first frame's points'
  // centroid; the others' moved with their origins
  Vec3 centroid = Vec3::Zero();
  int seen = 0;
  for (const Vec3& X_o : box.X_o)
    if (X_o.x() > kFirstSeenX) centroid += transform(box.pose(0), X_o), ++seen;
  centroid /= seen;
  const auto first_position = [](const RecenterRun& run) -> Vec3 {
    return run.track.frames.front().T_w_o.topRightCorner<3, 1>();
  };
  EXPECT_LT((first_position(bounded) - centroid).norm(), 0.05);
  EXPECT_GT((first_position(unbounded) - centroid).norm(), 1.0);
  EXPECT_GT((first_position(near) - centroid).norm(), 1.0);
}

// recenter_with_retired_points: the box's front half is seen in frames 0-3 only, so its points
// are culled (retired for the final smoothing) once predicted often enough without a match.
// With them the re-centring's median stays on the whole box; without them it follows the back
// half that is left.
TEST(ObjectTrackerRecenter, RetiredPointsKeepTheMedianOnTheWholeObject) {
  MovingBox box;
  box.hide_front_from = 4;
  std::mt19937 rng(79);
  std::uniform_real_distribution<double> x(-3.0, 3.0), y(-0.75, 0.75), z(-0.9, 0.9);
  for (int k = 0; k < 120; ++k) {  // back half's median ~1.5 m behind the whole box's
    box.X_o.emplace_back(x(rng), y(rng), z(rng));
    box.descriptors.push_back(random_descriptor(rng));
  }
  constexpr int kFrames = 30;  // the front points are culled after ~16 predictions
  tracking::ObjectTrackingOptions options;
  ASSERT_TRUE(options.final_smoothing);  // retired points are kept for it
  options.recenter_with_retired_points = true;
  const RecenterRun with = track_box(box, options.recenter_distance_m, kFrames, options);
  options.recenter_with_retired_points = false;
  const RecenterRun without = track_box(box, options.recenter_distance_m, kFrames, options);
  ASSERT_EQ(with.track.frames.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(without.track.frames.size(), static_cast<size_t>(kFrames));
  ASSERT_FALSE(with.cluster.retired.empty());  // the premise: the front points were culled

  // the last origin against the box's centre, along the box's own x axis
  const auto offset_x = [&](const RecenterRun& run) {
    const Mat4 T_o_w = geometry::se3_inverse(box.pose(kFrames - 1));
    return transform(T_o_w, run.track.last().T_w_o.topRightCorner<3, 1>()).x();
  };
  std::cout << "[ recenter ] retired points: origin " << offset_x(with) << " m along x from the box "
            << "centre (without them: " << offset_x(without) << " m)\n";
  EXPECT_LT(std::abs(offset_x(with)), 0.8);
  EXPECT_LT(offset_x(without), -1.0);  // on the back half
}

}  // namespace

namespace {

objects::ObjectPoint point_at(const Vec3& X_o, int found, bool stereo) {
  objects::ObjectPoint p;
  p.X_o = X_o;
  p.found = found;
  p.stereo_seen = stereo ? 1 : 0;
  return p;
}

}  // namespace

// recenter_on_stereo_points: a far car seeded at its ground contact holds mono points at a
// guessed depth; the stereo points it gains later are where the car is. The re-centring's
// median takes the stereo ones when there are enough, else every confirmed point.
TEST(ObjectTrackerRecenter, StereoPointsPlaceTheMedianWhenThereAreEnough) {
  objects::ObjectCluster cluster;
  for (int k = 0; k < 10; ++k) cluster.points.push_back(point_at(Vec3(0.1 * k, 0, 9.0), 3, false));
  for (int k = 0; k < 6; ++k) cluster.points.push_back(point_at(Vec3(0.1 * k, 0, 0.0), 3, true));
  cluster.points.push_back(point_at(Vec3(0, 0, 0), 1, true));  // found once: not confirmed
  const auto median_z = [](const std::vector<Vec3>& points) {
    return tracking::detail::median_point(points).z();
  };
  const auto stereo = tracking::detail::recenter_points(cluster, true, true, 6);
  EXPECT_EQ(stereo.size(), 6u);
  EXPECT_NEAR(median_z(stereo), 0.0, 1e-12);
  const auto all = tracking::detail::recenter_points(cluster, true, false, 6);
  EXPECT_EQ(all.size(), 16u);
  EXPECT_NEAR(median_z(all), 9.0, 1e-12);  // the guessed points outnumber them
  // fewer stereo points than asked for: every confirmed point
  EXPECT_EQ(tracking::detail::recenter_points(cluster, true, true, 7).size(), 16u);
  // retired points count when asked to
  cluster.retired.push_back(point_at(Vec3(0, 0, 0), 2, true));
  EXPECT_EQ(tracking::detail::recenter_points(cluster, true, true, 7).size(), 7u);
  EXPECT_EQ(tracking::detail::recenter_points(cluster, false, true, 7).size(), 16u);
}

// A point counts its observations with a disparity, its first one included.
TEST(ObjectTrackerRecenter, ObservationsWithADisparityAreCounted) {
  objects::ObjectPoint p;
  tracking::detail::observe(p, {0, Vec2(10, 10), -1.0, 0}, 8, false);
  EXPECT_EQ(p.stereo_seen, 0);
  tracking::detail::observe(p, {1, Vec2(11, 10), 3.5, 0}, 8, false);
  tracking::detail::observe(p, {2, Vec2(12, 10), -1.0, 0}, 8, false);
  EXPECT_EQ(p.stereo_seen, 1);
}
