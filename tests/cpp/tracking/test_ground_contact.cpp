// The ground-contact depth of an instance (tracking/ground_contact.hpp): a car mask standing
// on the road gives the depth of its lower edge on the road plane; a mask whose lower edge is
// hidden (no road below it), or shows road below only at a few columns, gives none, unless the
// other columns rest on another instance (a queue); bad images give none rather than throwing.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "common/kitti_camera.hpp"
#include "geometry/se3.hpp"
#include "tracking/ground_contact.hpp"

using namespace twistslam;
using namespace twistslam::tracking;

namespace {

constexpr int kRoad = 7, kCar = 26, kInstance = 26001;
const Vec4 kRoadPlane(0, -1, 0, 1.65);  // camera 1.65 m above the road (y points down)

struct Images {
  cv::Mat instances, labels;
};

// Road below the horizon row, sky above; a car mask from column u0 to u1 whose lowest row is
// the road row at `depth` (a car standing on the road at that depth).
Images car_on_road(const geometry::StereoCamera& cam, double depth, int u0, int u1) {
  Images im;
  im.instances = cv::Mat::zeros(cam.height, cam.width, CV_32SC1);
  im.labels = cv::Mat(cam.height, cam.width, CV_32SC1, cv::Scalar(kRoad));
  im.labels.rowRange(0, static_cast<int>(cam.cy)).setTo(23);  // sky
  // the pixel row whose lower edge (v + 0.5) sees the road at `depth`
  const int v_bottom = static_cast<int>(std::lround(cam.cy + cam.fy * 1.65 / depth - 0.5));
  const int v_top = v_bottom - 40;
  im.instances(cv::Range(v_top, v_bottom + 1), cv::Range(u0, u1)).setTo(kInstance);
  im.labels(cv::Range(v_top, v_bottom + 1), cv::Range(u0, u1)).setTo(kCar);
  return im;
}

TEST(GroundContact, CarStandingOnTheRoadGetsTheDepthOfItsLowerEdge) {
  const geometry::StereoCamera cam = test_scenes::kitti_camera();
  for (double depth : {8.0, 14.0, 25.0, 40.0}) {
    const Images im = car_on_road(cam, depth, 500, 600);
    const GroundContact c = ground_contact_depth(im.instances, im.labels, kInstance, kRoad, cam,
                                                 Mat4::Identity(), kRoadPlane, 5, 0.5, 60.0);
    ASSERT_TRUE(c.valid) << depth;
    EXPECT_EQ(c.columns, 100);
    EXPECT_EQ(c.mask_columns, 100);
    // the row is rounded: at most half a pixel of the road's slope in the image
    const double tol = 0.5 * depth * depth / (cam.fy * 1.65) + 1e-6;
    EXPECT_NEAR(c.depth, depth, tol) << depth;
  }
  // the same car seen from a camera 3 m further along the road: the plane is in the world
  Mat4 T_w_c = Mat4::Identity();
  T_w_c(2, 3) = 3.0;
  const Images im = car_on_road(test_scenes::kitti_camera(), 14.0, 500, 600);
  const GroundContact moved = ground_contact_depth(im.instances, im.labels, kInstance, kRoad, cam,
                                                   T_w_c, kRoadPlane, 5, 0.5, 60.0);
  ASSERT_TRUE(moved.valid);
  EXPECT_NEAR(moved.depth, 14.0, 0.2);
}

TEST(GroundContact, HiddenLowerEdgeGivesNoDepth) {
  const geometry::StereoCamera cam = test_scenes::kitti_camera();
  Images im = car_on_road(cam, 14.0, 500, 600);
  // a nearer car covers the lower part of the mask at 90 of its 100 columns
  cv::Mat occluder = im.labels(cv::Range(0, cam.height), cv::Range(510, 600));
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < occluder.cols; ++u)
      if (im.instances.at<int>(v, 510 + u) != kInstance && v > cam.cy) occluder.at<int>(v, u) = kCar;
  const GroundContact c = ground_contact_depth(im.instances, im.labels, kInstance, kRoad, cam,
                                               Mat4::Identity(), kRoadPlane, 5, 0.5, 60.0);
  EXPECT_FALSE(c.valid);
  EXPECT_EQ(c.columns, 10);
  EXPECT_EQ(c.mask_columns, 100);
  // with the fraction rule off, the 10 visible columns are enough
  EXPECT_TRUE(ground_contact_depth(im.instances, im.labels, kInstance, kRoad, cam,
                                   Mat4::Identity(), kRoadPlane, 5, 0.0, 60.0).valid);
  // a car above the horizon never meets the plane in front of the camera
  Images sky;
  sky.instances = cv::Mat::zeros(cam.height, cam.width, CV_32SC1);
  sky.labels = cv::Mat(cam.height, cam.width, CV_32SC1, cv::Scalar(kRoad));
  sky.instances(cv::Range(50, 100), cv::Range(500, 600)).setTo(kInstance);
  EXPECT_FALSE(ground_contact_depth(sky.instances, sky.labels, kInstance, kRoad, cam,
                                    Mat4::Identity(), kRoadPlane, 5, 0.5, 60.0).valid);
}

TEST(GroundContact, ColumnsHiddenBehindAnotherInstanceDoNotCount) {
  const geometry::StereoCamera cam = test_scenes::kitti_camera();
  constexpr int kNearer = 26002, kSidewalk = 8;
  // the car queued behind a nearer car (an instance of its own) that covers the lower part
  // of 90 of its 100 columns: the 10 columns with road below are its own contact
  Images queued = car_on_road(cam, 14.0, 500, 600);
  for (int v = static_cast<int>(cam.cy) + 1; v < cam.height; ++v)
    for (int u = 510; u < 600; ++u)
      if (queued.instances.at<int>(v, u) != kInstance) {
        queued.instances.at<int>(v, u) = kNearer;
        queued.labels.at<int>(v, u) = kCar;
      }
  const GroundContact c = ground_contact_depth(queued.instances, queued.labels, kInstance, kRoad,
                                               cam, Mat4::Identity(), kRoadPlane, 5, 0.5, 60.0);
  ASSERT_TRUE(c.valid);
  EXPECT_EQ(c.columns, 10);
  EXPECT_EQ(c.hidden_columns, 90);
  EXPECT_EQ(c.mask_columns, 10);
  EXPECT_NEAR(c.depth, 14.0, 0.5 * 14.0 * 14.0 / (cam.fy * 1.65) + 1e-6);
  // still at least min_columns: 4 columns of road are not enough
  for (int v = static_cast<int>(cam.cy) + 1; v < cam.height; ++v)
    for (int u = 504; u < 510; ++u)
      if (queued.instances.at<int>(v, u) != kInstance) {
        queued.instances.at<int>(v, u) = kNearer;
        queued.labels.at<int>(v, u) = kCar;
      }
  EXPECT_FALSE(ground_contact_depth(queued.instances, queued.labels, kInstance, kRoad, cam,
                                    Mat4::Identity(), kRoadPlane, 5, 0.5, 60.0).valid);
  // the same car with sidewalk (no instance) below those 90 columns: parked on the kerb, its
  // few road columns do not count as a contact
  Images kerb = car_on_road(cam, 14.0, 500, 600);
  for (int v = static_cast<int>(cam.cy) + 1; v < cam.height; ++v)
    for (int u = 510; u < 600; ++u)
      if (kerb.instances.at<int>(v, u) != kInstance) kerb.labels.at<int>(v, u) = kSidewalk;
  const GroundContact on_kerb = ground_contact_depth(kerb.instances, kerb.labels, kInstance, kRoad,
                                                     cam, Mat4::Identity(), kRoadPlane, 5, 0.5, 60.0);
  EXPECT_FALSE(on_kerb.valid);
  EXPECT_EQ(on_kerb.hidden_columns, 0);
  EXPECT_EQ(on_kerb.mask_columns, 100);
}

TEST(GroundContact, BadInputGivesNoDepth) {
  const geometry::StereoCamera cam = test_scenes::kitti_camera();
  const Images im = car_on_road(cam, 14.0, 500, 600);
  auto depth = [&](const cv::Mat& inst, const cv::Mat& lab, int id, const Vec4& plane) {
    return ground_contact_depth(inst, lab, id, kRoad, cam, Mat4::Identity(), plane, 5, 0.5, 60.0).valid;
  };
  EXPECT_TRUE(depth(im.instances, im.labels, kInstance, kRoadPlane));
  EXPECT_FALSE(depth(cv::Mat(), im.labels, kInstance, kRoadPlane));
  EXPECT_FALSE(depth(im.instances, cv::Mat(), kInstance, kRoadPlane));
  cv::Mat as_float;
  im.labels.convertTo(as_float, CV_32F);
  EXPECT_FALSE(depth(im.instances, as_float, kInstance, kRoadPlane));
  EXPECT_FALSE(depth(im.instances, im.labels(cv::Rect(0, 0, 100, 100)).clone(), kInstance, kRoadPlane));
  EXPECT_FALSE(depth(im.instances, im.labels, 0, kRoadPlane));
  EXPECT_FALSE(depth(im.instances, im.labels, 999, kRoadPlane));  // not in the image
  EXPECT_FALSE(depth(im.instances, im.labels, kInstance, Vec4::Zero()));
  EXPECT_FALSE(depth(im.instances, im.labels, kInstance, Vec4(NAN, -1, 0, 1.65)));
}

}  // namespace

TEST(GroundContact, ContactHeightMeetsTheRaysAboveTheRoad) {
  // between its wheels a car's lowest pixel is its body, 0.2 m above the road: on the road
  // plane that ray lands 1.65 / 1.45 times too far; raised by 0.2 m it meets the body's depth
  const geometry::StereoCamera cam = test_scenes::kitti_camera();
  const double depth = 30.0, clearance = 0.2;
  Images im = car_on_road(cam, depth * 1.65 / (1.65 - clearance), 500, 600);
  for (const Vec4& plane : {kRoadPlane, Vec4(-kRoadPlane)}) {  // either orientation of (n, d)
    const GroundContact on_road = ground_contact_depth(im.instances, im.labels, kInstance, kRoad,
                                                       cam, Mat4::Identity(), plane, 5, 0.5, 60.0);
    ASSERT_TRUE(on_road.valid);
    EXPECT_NEAR(on_road.depth, depth * 1.65 / (1.65 - clearance), 0.6);
    const GroundContact raised = ground_contact_depth(im.instances, im.labels, kInstance, kRoad, cam,
                                                      Mat4::Identity(), plane, 5, 0.5, 60.0, 2,
                                                      0.5, clearance);
    ASSERT_TRUE(raised.valid);
    EXPECT_NEAR(raised.depth, depth, 0.5);
  }
}
