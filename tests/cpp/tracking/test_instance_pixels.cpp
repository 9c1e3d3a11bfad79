// Keypoints at the boundary between two instances belong to neither
// (tracking/instance_pixels.hpp), and a far car whose few stereo points are outnumbered by
// corners taking the depth of the car in front of it still starts at its own depth.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "tracker_scene.hpp"
#include "tracking/instance_pixels.hpp"

using namespace twistslam;

namespace {

// Instance 5 on rows 0-9, instance 7 on rows 10-19, columns 0-19; columns 20-29 unlabelled.
cv::Mat two_instances() {
  cv::Mat ids = cv::Mat::zeros(20, 30, CV_32SC1);
  ids(cv::Rect(0, 0, 20, 10)).setTo(5);
  ids(cv::Rect(0, 10, 20, 10)).setTo(7);
  return ids;
}

TEST(InstanceAtKeypoint, ABoundaryBetweenTwoInstancesBelongsToNeither) {
  const cv::Mat ids = two_instances();
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 4), 3.0), 5);
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 15), 3.0), 7);
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 8), 3.0), 0);   // 2 rows above 7
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 11), 3.0), 0);  // 2 rows below 5
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 6.4), 3.0), 5);  // 4 rows: outside
  // a radius scaled by the keypoint's level reaches farther
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 6), 3.0 * 1.44), 0);
  // radius 0: the pixel alone
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 9), 0.0), 5);
}

TEST(InstanceAtKeypoint, UnlabelledBackgroundAndTheImageBorderDoNotCount) {
  const cv::Mat ids = two_instances();
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(19, 4), 3.0), 5);  // beside the background
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(0, 0), 3.0), 5);   // image corner
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(25, 4), 3.0), 0);  // on the background
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(-3, 4), 3.0), 0);  // outside the image
  EXPECT_EQ(tracking::instance_at_keypoint(ids, Vec2(10, 30), 3.0), 0);
  EXPECT_EQ(tracking::pixel_value(ids, Vec2(10.4, 9.6)), 7);  // nearest pixel (10, 10)
}

// A car 35 m ahead whose lower edge is hidden by a car 14 m ahead. Of its keypoints only
// 8 have a stereo depth (the right camera sees little of it); 12 more sit on its mask just
// above the near car's roof, corners formed by that roof, with the near car's disparity.
struct OccludedCarScene : TrackerScene {
  static constexpr int kFar = 3, kNear = 4;
  static constexpr double kNearDepth = 14.0;

  // The first frame's cluster origin of the far car (NaN z when no cluster started); with_box:
  // the frame comes with a 3D box (of another class, far to the side: it places nothing).
  Vec3 far_cluster_origin(double instance_border_px, bool with_box = false,
                          double lidar_border_px = 0.0) {
    tracking::ObjectTrackingOptions options;
    options.instance_border_px = instance_border_px;
    tracking::ObjectLidarOptions lidar;
    lidar.instance_border_px = lidar_border_px;
    auto tracker = make_tracker(options, lidar);
    std::vector<objects::Detection> boxes;
    if (with_box) {
      objects::Detection d;
      d.box.center = Vec3(-20, 0.8, 40);
      d.box.length = 4, d.box.width = 1.8, d.box.height = 1.5;
      d.score = 1, d.class_id = 99;
      boxes.push_back(d);
    }
    const Car far = make_car(rng, Vec3(0, -0.2, 35), Vec3(0, 0, 0.5), 0.0);
    SceneFrame f(0);
    double v_bottom = -1e9;
    double u0 = 1e9, u1 = -1e9, v0 = 1e9;
    for (size_t k = 0; k < far.X_o.size(); ++k) {
      f.mono = k >= 8;
      const Vec3 X = far.pose(0).topLeftCorner<3, 3>() * far.X_o[k] + far.pose(0).topRightCorner<3, 1>();
      if (!f.add_point(X, far.descriptors[k], kCar, static_cast<int>(k % 3))) continue;
      const Vec2 uv = f.frame.keypoints.uv.back();
      u0 = std::min(u0, uv.x()), u1 = std::max(u1, uv.x());
      v0 = std::min(v0, uv.y()), v_bottom = std::max(v_bottom, uv.y());
    }
    f.mono = false;
    const int top = static_cast<int>(std::floor(v0)) - 2, bottom = static_cast<int>(std::ceil(v_bottom)) + 2;
    const int left = static_cast<int>(std::floor(u0)) - 2, right = static_cast<int>(std::ceil(u1)) + 3;
    f.instances(cv::Rect(left, top, right - left, bottom - top)).setTo(kFar);
    // the near car's mask right below: its roof is the far car's lower edge
    f.instances(cv::Rect(left - 20, bottom, right - left + 40, 60)).setTo(kNear);
    // corners on the far car's mask 1-2 px above the roof, with the near car's depth
    for (int j = 0; j < 12; ++j) {
      const Vec2 uv(left + 2 + (right - left - 4) * (j + 0.5) / 12.0, bottom - 1.0 - (j % 2));
      f.add_point(kCamera.backproject(uv, kNearDepth), random_descriptor(rng), kCar, 0);
    }
    f.add_background(background);
    tracker.track(f.finish(), f.instances, cv::Mat(), kUp, cv::Mat(), Vec4::Zero(), boxes);
    for (const auto& track : tracker.tracks())
      if (!track.frames.empty()) return track.frames[0].T_w_o.topRightCorner<3, 1>();
    return Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  }
};

TEST_F(OccludedCarScene, CornersOnTheOccludersRoofDoNotPullTheFarCarsClusterNear) {
  const Vec3 with_border = far_cluster_origin(3.0);
  const Vec3 without = far_cluster_origin(0.0);
  // its 8 stereo points put it at 35 +- 0.9 m; the 12 roof corners, counted, at ~14 m
  EXPECT_NEAR(with_border.z(), 35.0, 1.0);
  EXPECT_LT(without.z(), 20.0);
}

TEST_F(OccludedCarScene, AFrameWithBoxesUsesTheLidarFusionsBorder) {
  // lidar_objects.instance_border_px (0 by default) replaces it in a frame with 3D boxes
  EXPECT_LT(far_cluster_origin(3.0, /*with_box=*/true).z(), 20.0);
  EXPECT_NEAR(far_cluster_origin(0.0, /*with_box=*/true, /*lidar_border_px=*/3.0).z(), 35.0, 1.0);
}

}  // namespace
