// The LiDAR terms the object tracker hands the keyframe BA (object_bundle.cpp,
// add_bundle_lidar_terms): boxes and registrations were put in the world with each row's own
// camera, and go back into those cameras' frames exactly, the registrations chained between
// two keyframes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/textured_planes.hpp"
#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "tracking/object_tracker.hpp"

using namespace twistslam;
namespace ts = twistslam::test_scenes;

namespace {

constexpr int kRows = 4;

Mat4 pose(double yaw, const Vec3& t) {
  const Mat3 R = Eigen::AngleAxisd(yaw, Vec3::UnitY()).toRotationMatrix();
  return geometry::make_pose(R, t);
}

// A car turning ahead of a camera that drives and turns too, so that world motions and
// camera-relative ones differ.
Mat4 camera(int r) { return geometry::se3_inverse(pose(0.03 * r, Vec3(0.1 * r, 0, 1.2 * r))); }
Mat4 car(int r) { return pose(0.05 * r, Vec3(1.0 + 0.2 * r, 0.8, 12.0 + 1.5 * r)); }

// D = T_cb_o(b) T_ca_o(a)^-1 of the truth
Mat4 camera_relative(int a, int b) {
  return camera(b) * car(b) * geometry::se3_inverse(camera(a) * car(a));
}

objects::ObjectTrack make_track(bool canonical) {
  objects::ObjectTrack track;
  track.canonical = canonical;
  track.Pi = geometry::projector_planar(Vec3(0, -1, 0));
  for (int r = 0; r < kRows; ++r) {
    objects::TrackFrame row;
    row.frame = 10 + r;
    row.T_w_o = car(r);
    row.T_c_w = camera(r);
    row.detection_index = r == 1 ? -1 : 0;  // no box in row 1
    row.T_w_o_detected = car(r);
    row.registered = r > 0;
    row.M_w_registered = r > 0 ? Mat4(car(r) * geometry::se3_inverse(car(r - 1))) : Mat4::Identity();
    row.reg_sigma = r == 2 ? Vec2(0.02, 0.002) : Vec2::Zero();  // zero: the options' sigmas
    track.frames.push_back(row);
  }
  return track;
}

tracking::ObjectTracker make_tracker(const tracking::ObjectLidarOptions& lidar) {
  return tracking::ObjectTracker(ts::kitti_camera(), tracking::ObjectTrackingOptions(),
                                 {1.0f, 1.2f, 1.44f, 1.728f},
                                 tracking::LevelWeights({1.0f, 1.44f, 2.07f, 2.99f}), lidar);
}

void expect_near(const Mat4& a, const Mat4& b) {
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-9) << "\n" << a << "\n vs \n" << b;
}

}  // namespace

TEST(ObjectBundleTerms, BoxesAndChainedRegistrationsInTheCamerasFrames) {
  tracking::ObjectLidarOptions lidar;
  const tracking::ObjectTracker tracker = make_tracker(lidar);
  const objects::ObjectTrack track = make_track(true);
  optim::BAObject object;
  tracker.add_bundle_lidar_terms(track, {0, 1, 3}, &object);  // keyframe poses at rows 0, 1, 3

  // box priors where a row has a box: poses 0 (row 0) and 2 (row 3), in their cameras
  ASSERT_EQ(object.boxes.size(), 2u);
  EXPECT_EQ(object.boxes[0].pose, 0);
  EXPECT_EQ(object.boxes[1].pose, 2);
  expect_near(object.boxes[0].T_c_box, camera(0) * car(0));
  expect_near(object.boxes[1].T_c_box, camera(3) * car(3));
  EXPECT_EQ(object.boxes[1].sigma_translation, lidar.det_pose_sigma_translation);

  // no e_det (row 1 has no box); e_reg of row 1 for poses 0-1, rows 2 and 3 chained for 1-2
  ASSERT_EQ(object.motions.size(), 2u);
  const optim::BAObjectMotion& first = object.motions[0];
  const optim::BAObjectMotion& second = object.motions[1];
  EXPECT_EQ(first.pose_a, 0);
  EXPECT_EQ(first.pose_b, 1);
  expect_near(first.D, camera_relative(0, 1));
  EXPECT_DOUBLE_EQ(first.sigma_translation, lidar.reg_sigma_translation);
  EXPECT_EQ(second.pose_a, 1);
  EXPECT_EQ(second.pose_b, 2);
  expect_near(second.D, camera_relative(1, 3));
  // the variances of the two registrations add (row 2 its own, row 3 the options')
  EXPECT_NEAR(second.sigma_translation, std::hypot(0.02, lidar.reg_sigma_translation), 1e-12);
  EXPECT_NEAR(second.sigma_rotation, std::hypot(0.002, lidar.reg_sigma_rotation), 1e-12);
  EXPECT_EQ(second.huber_delta, lidar.huber_reg);
}

TEST(ObjectBundleTerms, BoxPairsGiveEDetAndGapsOrSwitchesLeaveTermsOut) {
  tracking::ObjectLidarOptions lidar;
  lidar.use_registration = false;
  objects::ObjectTrack track = make_track(true);
  track.frames[2].registered = false;  // irrelevant here: no e_reg
  optim::BAObject object;
  make_tracker(lidar).add_bundle_lidar_terms(track, {0, 2, 3}, &object);
  // e_det between the boxes of rows 0-2 and 2-3, from the boxes in their cameras
  ASSERT_EQ(object.motions.size(), 2u);
  expect_near(object.motions[0].D, camera_relative(0, 2));
  expect_near(object.motions[1].D, camera_relative(2, 3));
  EXPECT_EQ(object.motions[0].sigma_translation, lidar.det_sigma_translation);
  EXPECT_EQ(object.boxes.size(), 3u);

  // a registration missing between two keyframes: no e_reg across the gap
  lidar = tracking::ObjectLidarOptions();
  lidar.use_detection_twist = false;
  track = make_track(true);
  track.frames[2].registered = false;
  object = optim::BAObject();
  make_tracker(lidar).add_bundle_lidar_terms(track, {0, 1, 3}, &object);
  ASSERT_EQ(object.motions.size(), 1u);  // poses 0-1 only
  EXPECT_EQ(object.motions[0].pose_b, 1);

  // an object frame that is not a box frame takes no box prior
  object = optim::BAObject();
  make_tracker(lidar).add_bundle_lidar_terms(make_track(false), {0, 1, 3}, &object);
  EXPECT_TRUE(object.boxes.empty());
}
