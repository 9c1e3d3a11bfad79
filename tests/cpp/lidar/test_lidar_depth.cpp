// LiDAR depth of keypoints on synthetic scans with known geometry: a near box in front of a
// far wall whose returns continue behind the box (the LiDAR-camera parallax case), a slanted
// road and a tilted wall (exact planes), support and fit rejections.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lidar/lidar_depth.hpp"
#include "synthetic_scan.hpp"

using namespace twistslam;
using namespace twistslam::lidar;
using namespace twistslam::test_scenes;

namespace {

constexpr double kWall = 30.0, kBox = 10.0;  // m
constexpr double kBoxU0 = 550, kBoxU1 = 650, kBoxV0 = 150, kBoxV1 = 250;  // px
constexpr double kBetweenLines = 202.5;  // px, between the scan lines at v = 200 and 205

// Wall returns over the whole region (also behind the box) plus the box's own returns.
Points3 box_and_wall(const geometry::StereoCamera& cam) {
  const Points3 wall = scan_lines(cam, 300, 900, 100, 300, [](double, double) { return kWall; });
  const Points3 box = scan_lines(cam, kBoxU0, kBoxU1, kBoxV0, kBoxV1,
                                 [](double, double) { return kBox; });
  return stack(wall, box);
}

LidarDepth depth_at(const ScanProjection& scan, double u, double v) {
  return lidar_depth_at(Vec2(u, v), scan, LidarDepthOptions{});
}

}  // namespace

TEST(LidarDepth, ForegroundBoxInFrontOfWallTakesTheNearLayer) {
  const auto cam = kitti_camera();
  const ScanProjection scan = project_scan(box_and_wall(cam), cam, {});
  const LidarDepth box = depth_at(scan, 600, kBetweenLines);
  EXPECT_EQ(box.status, LidarDepthStatus::kForeground);
  EXPECT_NEAR(box.depth, kBox, 1e-4);
  const LidarDepth wall = depth_at(scan, 400, kBetweenLines);
  EXPECT_EQ(wall.status, LidarDepthStatus::kPlane);
  EXPECT_NEAR(wall.depth, kWall, 1e-3);
}

TEST(LidarDepth, NoDepthLeaksAcrossTheBoxEdge) {
  const auto cam = kitti_camera();
  const ScanProjection scan = project_scan(box_and_wall(cam), cam, {});
  int valid_box = 0, valid_wall = 0, rejected_at_edge = 0;
  for (double u = kBoxU0 - 12; u <= kBoxU0 + 12; u += 0.25) {
    const LidarDepth d = depth_at(scan, u, kBetweenLines);
    const bool on_box = u >= kBoxU0;  // the camera sees the box from u = 550 on
    if (!d.valid()) {
      ++rejected_at_edge;
      continue;
    }
    // Valid depths are the true surface at the keypoint, never the other layer or a blend.
    EXPECT_NEAR(d.depth, on_box ? kBox : kWall, 1e-3) << "u = " << u;
    ++(on_box ? valid_box : valid_wall);
  }
  EXPECT_GT(valid_box, 0);
  EXPECT_GT(valid_wall, 0);
  EXPECT_GT(rejected_at_edge, 0);  // wall keypoints within the radius of the box are refused
  EXPECT_EQ(depth_at(scan, kBoxU0 - 3, kBetweenLines).status, LidarDepthStatus::kDepthEdge);
}

TEST(LidarDepth, SlantedRoadDepthIsExact) {
  const auto cam = kitti_camera();
  const double height = 1.65;  // m, camera above a flat road (y down in frame c)
  auto road = [&](double, double v) { return v > cam.cy + 1 ? cam.fy * height / (v - cam.cy) : 0; };
  const ScanProjection scan = project_scan(scan_lines(cam, 300, 900, 200, 370, road), cam, {});
  for (const double v : {212.5, 252.5, 301.0}) {
    const LidarDepth d = depth_at(scan, 600, v);
    ASSERT_EQ(d.status, LidarDepthStatus::kPlane) << "v = " << v;
    EXPECT_NEAR(d.depth / road(600, v), 1.0, 1e-5) << "v = " << v;  // float storage only
    EXPECT_GE(d.num_returns, 8);
  }
}

TEST(LidarDepth, TiltedWallDepthIsExact) {
  const auto cam = kitti_camera();
  // Plane z = 20 + 0.4 x in frame left: along the ray x = (u - cx) z / fx.
  auto wall = [&](double u, double) { return 20.0 / (1.0 - 0.4 * (u - cam.cx) / cam.fx); };
  const ScanProjection scan = project_scan(scan_lines(cam, 100, 1100, 100, 300, wall), cam, {});
  for (const double u : {150.3, 609.0, 1050.7}) {
    const LidarDepth d = depth_at(scan, u, 151.0);
    ASSERT_EQ(d.status, LidarDepthStatus::kPlane);
    EXPECT_NEAR(d.depth / wall(u, 0), 1.0, 1e-5);
  }
}

TEST(LidarDepth, RejectsKeypointsOutsideTheScanSupport) {
  const auto cam = kitti_camera();
  const ScanProjection scan = project_scan(box_and_wall(cam), cam, {});
  EXPECT_EQ(depth_at(scan, 400, 97).status, LidarDepthStatus::kOutsideSupport);  // above line 1
  const LidarDepth none = depth_at(scan, 50, 50);
  EXPECT_EQ(none.status, LidarDepthStatus::kTooFewReturns);
  EXPECT_EQ(none.num_returns, 0);
  EXPECT_EQ(depth_at(scan, NAN, 200).status, LidarDepthStatus::kTooFewReturns);
  EXPECT_FALSE(depth_at(scan, -1e9, 1e9).valid());
}

TEST(LidarDepth, RejectsANonPlanarNeighbourhood) {
  const auto cam = kitti_camera();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> leaves(20.0, 23.0);  // m, foliage: no plane, no gap
  const ScanProjection scan =
      project_scan(scan_lines(cam, 300, 900, 100, 300, [&](double, double) { return leaves(rng); }),
                   cam, {});
  const LidarDepth d = depth_at(scan, 600, kBetweenLines);
  EXPECT_EQ(d.status, LidarDepthStatus::kPoorFit);
  EXPECT_FALSE(d.valid());
}

TEST(LidarDepth, EmptyScanGivesNoDepth) {
  const auto cam = kitti_camera();
  const ScanProjection scan = project_scan(Points3(0, 3), cam, {});
  EXPECT_TRUE(scan.returns.empty());
  const auto out = lidar_depth_at(std::vector<Vec2>{Vec2(600, 200), Vec2(10, 10)}, scan, {});
  ASSERT_EQ(out.size(), 2u);
  for (const LidarDepth& d : out) EXPECT_EQ(d.status, LidarDepthStatus::kTooFewReturns);
}
