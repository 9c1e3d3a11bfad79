// LiDAR road returns for the road plane (tracking/road_lidar_points.hpp): a tilted road plane
// with a raised sidewalk and a car on it, its class image ray-cast from the left camera with a
// road mask that bleeds a few pixels onto the car and the curb (as a segmentation's does).
// Only returns on road pixels away from the mask boundary are kept; they give the true plane.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "common/kitti_camera.hpp"
#include "objects/road_plane.hpp"
#include "tracking/road_lidar_points.hpp"

using namespace twistslam;
using namespace twistslam::tracking;

namespace {

constexpr int kRoad = 7, kSidewalk = 8, kCar = 26;
constexpr double kRoadHalfWidth = 6.0;  // m, |x| beyond is sidewalk, 0.15 m higher
constexpr double kCurb = 0.15;          // m
constexpr int kBleedPx = 3;             // px the painted road mask spreads onto its neighbours

// n . X + d = 0, n "up" (y points down in frame c): a 2 % cross slope and a 3 % grade.
Vec4 true_plane() {
  const Vec3 n = Vec3(0.02, -1.0, 0.03).normalized();
  return Vec4(n.x(), n.y(), n.z(), 1.65);
}

// The road's y at (x, z) in frame c.
double road_y(double x, double z) {
  const Vec4 p = true_plane();
  return -(p.x() * x + p.z() * z + p.w()) / p.y();
}

// The car: an axis-aligned box 0.3-1.5 m above the road (its underside is open to the road
// seen below it), rear face at z = 12 m.
struct Box {
  Vec3 lo{-0.9, road_y(0, 12) - 1.5, 12.0}, hi{0.9, road_y(0, 12) - 0.3, 16.5};
};

double ray_box(const Vec3& o, const Vec3& d, const Box& b) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
    t0 = std::max(t0, std::min(a, c));
    t1 = std::min(t1, std::max(a, c));
  }
  return t0 <= t1 ? t0 : std::numeric_limits<double>::infinity();
}

// Class of every left pixel by ray casting, then the road mask dilated by kBleedPx.
cv::Mat paint_labels(const geometry::StereoCamera& cam) {
  cv::Mat labels(cam.height, cam.width, CV_32SC1, cv::Scalar(0));
  const Vec3 origin = -cam.t_left;  // the left camera centre in frame c
  const Vec4 p = true_plane();
  const Box car;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Vec3 d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const double t_car = ray_box(origin, d, car);
      const double denom = p.head<3>().dot(d);
      const double t_road = denom < 0 ? -(p.head<3>().dot(origin) + p.w()) / denom : -1;
      if (std::isfinite(t_car) && (t_road < 0 || t_car < t_road)) {
        labels.at<int>(v, u) = kCar;
      } else if (t_road > 0) {
        const Vec3 X = origin + t_road * d;
        labels.at<int>(v, u) = std::abs(X.x()) <= kRoadHalfWidth ? kRoad : kSidewalk;
      }
    }
  cv::Mat road = labels == kRoad, bled;
  cv::dilate(road, bled, cv::Mat::ones(2 * kBleedPx + 1, 2 * kBleedPx + 1, CV_8U));
  labels.setTo(kRoad, bled);
  return labels;
}

// Returns on the road and the sidewalk (a 0.25 m grid out to 40 m), the car's rear face and
// a few NaN rows, in frame c.
Points3 make_scan() {
  std::vector<Vec3> pts;
  for (double z = 2.0; z <= 40.0; z += 0.25)
    for (double x = -10.0; x <= 10.0; x += 0.25)
      pts.emplace_back(x, road_y(x, z) - (std::abs(x) > kRoadHalfWidth ? kCurb : 0.0), z);
  const Box car;
  for (double x = car.lo.x(); x <= car.hi.x(); x += 0.05)
    for (double y = car.lo.y(); y <= car.hi.y(); y += 0.05) pts.emplace_back(x, y, car.lo.z());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 5; ++k) pts.emplace_back(nan, 1.0, 10.0);
  Points3 out(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  return out;
}

double residual(const Points3& X, Eigen::Index i) {
  const Vec4 p = true_plane();
  return std::abs(p.head<3>().dot(X.row(i).transpose()) + p.w());
}

class RoadLidarPointsTest : public ::testing::Test {
 protected:
  const geometry::StereoCamera cam = test_scenes::kitti_camera();
  const cv::Mat labels = paint_labels(cam);
  const Points3 scan = make_scan();
};

TEST_F(RoadLidarPointsTest, ReturnsNearTheMaskBoundaryAreRejected) {
  RoadLidarSelection s;
  s.max_points = 1000000;  // every candidate tested
  s.border_px = 0;
  const RoadLidarPoints loose = select_road_lidar_points(scan, cam, labels, s);
  int off_plane = 0;
  for (Eigen::Index i = 0; i < loose.points_c.rows(); ++i) off_plane += residual(loose.points_c, i) > 0.1;
  ASSERT_GT(off_plane, 10) << "the bled mask must put car and curb returns on road pixels";

  // a return on the car's silhouette projects onto the true mask boundary: the window must
  // reach one pixel past the bleed
  s.border_px = kBleedPx + 1;
  const RoadLidarPoints strict = select_road_lidar_points(scan, cam, labels, s);
  ASSERT_GT(strict.points_c.rows(), 1000);
  EXPECT_EQ(strict.num_non_finite, 5);
  EXPECT_EQ(loose.num_near_border, 0);  // a 1 x 1 window is the pixel itself
  EXPECT_GT(strict.num_near_border, off_plane);
  for (Eigen::Index i = 0; i < strict.points_c.rows(); ++i) {
    ASSERT_LT(residual(strict.points_c, i), 1e-9) << "an off-road return was kept";
    const Vec3 X = strict.points_c.row(i).transpose();
    EXPECT_LE(X.z() + cam.t_left.z(), s.max_depth_m);
    const Vec2 uv = cam.project(X);
    const int u = static_cast<int>(std::floor(uv.x() + 0.5)), v = static_cast<int>(std::floor(uv.y() + 0.5));
    for (int y = v - s.border_px; y <= v + s.border_px; ++y)
      for (int x = u - s.border_px; x <= u + s.border_px; ++x) ASSERT_EQ(labels.at<int>(y, x), kRoad);
  }
}

TEST_F(RoadLidarPointsTest, TheCapSpreadsTheKeptReturnsOverTheRoad) {
  RoadLidarSelection s;
  s.max_points = 60;
  const RoadLidarPoints road = select_road_lidar_points(scan, cam, labels, s);
  ASSERT_LE(road.points_c.rows(), 60);
  ASSERT_GE(road.points_c.rows(), 55);  // few blocks are all boundary
  const Eigen::VectorXd z = road.points_c.col(2);
  EXPECT_LT(z.minCoeff(), 8.0);  // near and far road, not the first 60 returns of the scan
  EXPECT_GT(z.maxCoeff(), 20.0);
  EXPECT_GT(road.points_c.col(0).maxCoeff() - road.points_c.col(0).minCoeff(), 6.0);
}

TEST_F(RoadLidarPointsTest, KeptReturnsGiveTheTruePlane) {
  RoadLidarSelection s;
  s.max_points = 300;
  const RoadLidarPoints road = select_road_lidar_points(scan, cam, labels, s);
  objects::RoadPlaneEstimator estimator;  // world = frame c here
  estimator.add_points(road.points_c);
  ASSERT_TRUE(estimator.valid());
  const Vec4 fitted = estimator.plane(), truth = true_plane();
  const double angle_deg = std::acos(std::min(1.0, fitted.head<3>().dot(truth.head<3>()))) * 180.0 / M_PI;
  EXPECT_LT(angle_deg, 0.01);
  EXPECT_NEAR(fitted.w(), truth.w(), 1e-3);
}

TEST_F(RoadLidarPointsTest, EmptyScansLabelsAndBadInput) {
  const RoadLidarSelection s;
  EXPECT_EQ(select_road_lidar_points(Points3(0, 3), cam, labels, s).points_c.rows(), 0);
  EXPECT_EQ(select_road_lidar_points(scan, cam, cv::Mat(), s).points_c.rows(), 0);
  Points3 all_nan = Points3::Constant(4, 3, std::numeric_limits<double>::quiet_NaN());
  const RoadLidarPoints none = select_road_lidar_points(all_nan, cam, labels, s);
  EXPECT_EQ(none.points_c.rows(), 0);
  EXPECT_EQ(none.num_non_finite, 4);
  RoadLidarSelection zero = s;
  zero.max_points = 0;
  EXPECT_EQ(select_road_lidar_points(scan, cam, labels, zero).points_c.rows(), 0);
  cv::Mat bytes(labels.size(), CV_8UC1, cv::Scalar(kRoad));
  EXPECT_THROW(select_road_lidar_points(scan, cam, bytes, s), std::invalid_argument);
  RoadLidarSelection bad = s;
  bad.border_px = -1;
  EXPECT_THROW(select_road_lidar_points(scan, cam, labels, bad), std::invalid_argument);
  // a road class absent from the image: nothing
  RoadLidarSelection other = s;
  other.road_class_id = 99;
  EXPECT_EQ(select_road_lidar_points(scan, cam, labels, other).points_c.rows(), 0);
}

}  // namespace
