// Masks from boxes on a synthetic scan: a flat road 1.65 m under a KITTI-like camera and a
// box-shaped car of points standing on it. The car's pixels take its class and instance, the
// road in front of it is road, the sky is unknown; a nearer box paints over a farther one.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "perception/box_masks.hpp"

namespace p = twistslam::perception;
using twistslam::Mat34;
using twistslam::Points3;
using twistslam::Vec3;

namespace {

constexpr int kHeight = 188, kWidth = 621;
constexpr double kCameraHeight = 1.65;  // m above the road (y down)

Mat34 projection() {
  Mat34 P = Mat34::Zero();
  P << 360, 0, 310, 0,  //
      0, 360, 90, 0,    //
      0, 0, 1, 0;
  return P;
}

// road points on a 0.2 m lattice out to 40 m, and the surface of a car (l 4, w 1.8, h 1.5)
// centred at (x, z), 0.2 m above the road
void add_road(std::vector<Vec3>* points) {
  for (double z = 2; z < 40; z += 0.2)
    for (double x = -8; x <= 8; x += 0.2) points->emplace_back(x, kCameraHeight, z);
}

void add_car(double x, double z, std::vector<Vec3>* points) {
  for (double a = -2; a <= 2; a += 0.1)
    for (double h = 0.2; h <= 1.5; h += 0.1) {
      points->emplace_back(x + 0.9 * (a > 0 ? 1 : -1) * std::min(1.0, std::abs(a)), kCameraHeight - h, z - 2 + std::abs(a));
      points->emplace_back(x + a * 0.45, kCameraHeight - h, z - 2);  // rear face
    }
}

p::MaskBox car_box(double x, double z, int instance) {
  p::MaskBox b;
  b.centre = Vec3(x, kCameraHeight - 0.85, z);
  b.length = 4.2;  // along x at yaw 0: rotated below so the length runs along z
  b.width = 2.0;
  b.height = 1.8;
  b.yaw = M_PI / 2;
  b.class_id = 26;
  b.instance_id = instance;
  return b;
}

Points3 stack(const std::vector<Vec3>& points) {
  Points3 out(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  return out;
}

int pixel_of(const Vec3& X, int* u, int* v) {
  const Vec3 x = projection().leftCols<3>() * X;
  *u = static_cast<int>(std::floor(x.x() / x.z()));
  *v = static_cast<int>(std::floor(x.y() / x.z()));
  return *v * kWidth + *u;
}

}  // namespace

TEST(BoxMasks, CarRoadAndSky) {
  std::vector<Vec3> points;
  add_road(&points);
  add_car(0, 12, &points);
  const p::BoxMasks m = p::masks_from_boxes(stack(points), {car_box(0, 12, 5)}, projection(), kHeight, kWidth, {}, 0, 7);
  ASSERT_TRUE(m.plane.has_value());
  EXPECT_NEAR(m.plane->w(), kCameraHeight, 0.02);
  EXPECT_LT(m.plane->y(), -0.99);
  int u, v;
  const int car = pixel_of(Vec3(0, kCameraHeight - 0.8, 10), &u, &v);  // the car's rear face
  EXPECT_EQ(m.class_id[car], 26);
  EXPECT_EQ(m.instance_id[car], 5);
  const int road = pixel_of(Vec3(0, kCameraHeight, 8), &u, &v);  // road before the car
  EXPECT_EQ(m.class_id[road], 7);
  EXPECT_EQ(m.instance_id[road], 0);
  EXPECT_EQ(m.class_id[5 * kWidth + 300], 0);  // sky
  // the car's mask lies within its projected box: nothing far left or right of it
  const int beside = pixel_of(Vec3(4, kCameraHeight - 0.8, 10), &u, &v);
  EXPECT_EQ(m.instance_id[beside], 0);
}

TEST(BoxMasks, NearerBoxPaintsOverFarther) {
  std::vector<Vec3> points;
  add_road(&points);
  add_car(0, 12, &points);
  add_car(0.5, 25, &points);
  // the far box listed first and last: the near one wins either way
  for (bool far_first : {true, false}) {
    std::vector<p::MaskBox> boxes = {car_box(0.5, 25, 2), car_box(0, 12, 1)};
    if (!far_first) std::swap(boxes[0], boxes[1]);
    const p::BoxMasks m = p::masks_from_boxes(stack(points), boxes, projection(), kHeight, kWidth, {}, 0, 7);
    int u, v;
    EXPECT_EQ(m.instance_id[pixel_of(Vec3(0.3, kCameraHeight - 0.8, 10), &u, &v)], 1);
    // the far car's roof shows above the near one's
    EXPECT_EQ(m.instance_id[pixel_of(Vec3(0.5, kCameraHeight - 1.45, 23), &u, &v)], 2);
  }
}

TEST(BoxMasks, TooFewPointsNoPlaneAndBadInput) {
  std::vector<Vec3> points;
  add_car(0, 12, &points);
  p::BoxMaskOptions o;
  o.low_point_below_camera_m = 2.0;  // nothing that low: no plane, every point a hull candidate
  const p::BoxMasks m = p::masks_from_boxes(stack(points), {car_box(0, 12, 3), car_box(0, 30, 4)}, projection(), kHeight, kWidth, o, -1, 7);
  EXPECT_FALSE(m.plane.has_value());
  int u, v;
  EXPECT_EQ(m.instance_id[pixel_of(Vec3(0, kCameraHeight - 0.8, 10), &u, &v)], 3);
  for (size_t i = 0; i < m.class_id.size(); ++i) {
    ASSERT_NE(m.class_id[i], 7);               // no road without a plane
    ASSERT_NE(m.instance_id[i], 4);            // the empty box has no mask
    if (!m.instance_id[i]) ASSERT_EQ(m.class_id[i], -1);  // unknown_id elsewhere
  }
  EXPECT_THROW(p::masks_from_boxes(stack(points), {}, projection(), 0, kWidth, o, 0, 7), std::invalid_argument);
  o.min_box_points = 2;
  EXPECT_THROW(p::masks_from_boxes(stack(points), {}, projection(), kHeight, kWidth, o, 0, 7), std::invalid_argument);
}
