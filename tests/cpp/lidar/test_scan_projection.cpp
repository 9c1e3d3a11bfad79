// Scan projection: the buckets hold exactly the returns in the image and the depth range;
// NaN points are dropped and counted; the dynamic-class mask removes returns (eq. 3).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "lidar/lidar_depth.hpp"
#include "synthetic_scan.hpp"

using namespace twistslam;
using namespace twistslam::lidar;
using namespace twistslam::test_scenes;

TEST(ScanProjection, KeepsReturnsInTheImageAndDepthRange) {
  const auto cam = kitti_camera();
  Points3 pts(5, 3);
  pts.row(0) = point_c_at(cam, 100.5, 50.25, 12.0).transpose();  // kept
  pts.row(1) = point_c_at(cam, -5, 50, 12.0).transpose();        // left of the image
  pts.row(2) = point_c_at(cam, 100, 50, 0.5).transpose();        // nearer than min_depth_m
  pts.row(3) = point_c_at(cam, 100, 50, 150).transpose();        // beyond max_depth_m
  pts.row(4) = Vec3(0, 0, -10).transpose();                      // behind the camera
  const ScanProjection scan = project_scan(pts, cam, {});
  ASSERT_EQ(scan.returns.size(), 1u);
  EXPECT_NEAR(scan.returns[0].u, 100.5, 1e-4);
  EXPECT_NEAR(scan.returns[0].v, 50.25, 1e-4);
  EXPECT_NEAR(scan.returns[0].depth, 12.0, 1e-5);
  EXPECT_EQ(scan.returns[0].index, 0);
  EXPECT_EQ(scan.cell_start.back(), 1);
}

TEST(ScanProjection, DropsAndCountsNonFinitePoints) {
  const auto cam = kitti_camera();
  Points3 wall = scan_lines(cam, 300, 900, 100, 300, [](double, double) { return 30.0; });
  const auto clean = project_scan(wall, cam, {});
  ASSERT_EQ(clean.returns.size(), static_cast<std::size_t>(wall.rows()));  // all in the image
  std::vector<int> seen(wall.rows(), 0);
  for (const ProjectedReturn& r : clean.returns) ++seen[r.index];
  for (const int s : seen) ASSERT_EQ(s, 1);
  wall(3, 0) = NAN;
  wall(10, 2) = INFINITY;
  wall(11, 1) = -NAN;
  const ScanProjection scan = project_scan(wall, cam, {});
  EXPECT_EQ(scan.num_non_finite, 3);
  EXPECT_EQ(scan.returns.size(), clean.returns.size() - 3);
  const LidarDepth d = lidar_depth_at(Vec2(600, 202.5), scan, LidarDepthOptions{});
  EXPECT_TRUE(d.valid());
  EXPECT_NEAR(d.depth, 30.0, 1e-3);
}

TEST(ScanProjection, MaskExcludesDynamicReturns) {
  const auto cam = kitti_camera();
  const Points3 wall = scan_lines(cam, 300, 900, 100, 300, [](double, double) { return 30.0; });
  const Points3 car = scan_lines(cam, 550, 650, 150, 250, [](double, double) { return 10.0; });
  cv::Mat mask(cam.height, cam.width, CV_8UC1, cv::Scalar(255));
  mask(cv::Rect(550, 150, 101, 101)).setTo(0);  // the car's pixels: dynamic class
  const ScanProjection scan = project_scan(stack(wall, car), cam, {}, mask);
  EXPECT_GT(scan.num_masked, 0);
  for (const ProjectedReturn& r : scan.returns) EXPECT_NE(mask.at<uchar>(int(r.v), int(r.u)), 0);
  // On the car: nothing left. Beside it: the wall alone, no depth edge any more.
  EXPECT_EQ(lidar_depth_at(Vec2(600, 202.5), scan, {}).num_returns, 0);
  const LidarDepth beside = lidar_depth_at(Vec2(547, 202.5), scan, {});
  EXPECT_EQ(beside.status, LidarDepthStatus::kPlane);
  EXPECT_NEAR(beside.depth, 30.0, 1e-3);
}

TEST(ScanProjection, RefusesBadCameraMaskAndOptions) {
  auto cam = kitti_camera();
  const Points3 pts = Points3::Zero(2, 3);
  EXPECT_THROW(project_scan(pts, cam, {}, cv::Mat(10, 10, CV_8UC1)), std::invalid_argument);
  EXPECT_THROW(project_scan(pts, cam, {}, cv::Mat(cam.height, cam.width, CV_32F)),
               std::invalid_argument);
  LidarDepthOptions bad;
  bad.search_radius_px = NAN;
  EXPECT_THROW(project_scan(pts, cam, bad), std::invalid_argument);
  bad = {};
  bad.min_returns = 2;
  EXPECT_THROW(project_scan(pts, cam, bad), std::invalid_argument);
  cam.width = 0;
  EXPECT_THROW(project_scan(pts, cam, {}), std::invalid_argument);
}
