// Extra keypoints inside object masks (tracking/object_keypoints.hpp) and their use by
// FrameBuilder (never usable for the camera). The re-centring of a cluster's frame on its
// points: test_object_recenter.cpp.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "common/textured_planes.hpp"
#include "common/random_descriptor.hpp"
#include "features/stereo.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "tracking/frame_builder.hpp"
#include "tracking/object_keypoints.hpp"
#include "tracking/object_tracker.hpp"

using namespace twistslam;
namespace ts = twistslam::test_scenes;

namespace {

// ---------------------------------------------------------------- object_class_mask

TEST(ObjectClassMask, KeepsInstancePixelsOfTheListedClasses) {
  cv::Mat instances = cv::Mat::zeros(4, 5, CV_32SC1), labels = cv::Mat::zeros(4, 5, CV_32SC1);
  // column u: instance id, row v: class (26 car, 24 person, 7 road, 40 beyond every listed id)
  const int ids[5] = {0, 1, 2, -3, 4};
  const int classes[4] = {26, 24, 7, 40};
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 5; ++u) instances.at<int>(v, u) = ids[u], labels.at<int>(v, u) = classes[v];
  const cv::Mat mask = tracking::object_class_mask(instances, labels, {26, 24});
  ASSERT_EQ(mask.type(), CV_8UC1);
  ASSERT_EQ(mask.size(), instances.size());
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 5; ++u) {
      const bool expected = ids[u] > 0 && (classes[v] == 26 || classes[v] == 24);
      EXPECT_EQ(mask.at<std::uint8_t>(v, u), expected ? 255 : 0) << "u " << u << " v " << v;
    }
  // no labels: every instance pixel, whatever the list
  const cv::Mat any = tracking::object_class_mask(instances, cv::Mat(), {26});
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 5; ++u) EXPECT_EQ(any.at<std::uint8_t>(v, u), ids[u] > 0 ? 255 : 0);
  // an empty list with labels: nothing
  EXPECT_EQ(cv::countNonZero(tracking::object_class_mask(instances, labels, {})), 0);
}

TEST(InstancesOfClasses, KeepsTheIdsOfTheListedClassesOnly) {
  // a car (instance 3, class 26) beside a person (instance 5, class 24) and road (class 7)
  cv::Mat instances = cv::Mat::zeros(2, 3, CV_32SC1), labels = cv::Mat::zeros(2, 3, CV_32SC1);
  const int ids[3] = {3, 5, 0}, classes[3] = {26, 24, 7};
  for (int v = 0; v < 2; ++v)
    for (int u = 0; u < 3; ++u) instances.at<int>(v, u) = ids[u], labels.at<int>(v, u) = classes[u];
  const cv::Mat vehicles = tracking::instances_of_classes(instances, labels, {26, 27});
  ASSERT_EQ(vehicles.type(), CV_32SC1);
  for (int v = 0; v < 2; ++v) {
    EXPECT_EQ(vehicles.at<int>(v, 0), 3);
    EXPECT_EQ(vehicles.at<int>(v, 1), 0);  // the person gets no second pass
    EXPECT_EQ(vehicles.at<int>(v, 2), 0);
  }
}

TEST(MarkOccluderClasses, MarksTheListedStuffClassesWhereThereIsNoInstance) {
  // a car (instance 3, class 26), a tree trunk (vegetation 21), a pole (17), road (7), and a
  // vegetation-labelled pixel under an instance id (kept: the instance wins)
  cv::Mat ids = cv::Mat::zeros(1, 5, CV_32SC1), labels = cv::Mat::zeros(1, 5, CV_32SC1);
  const int inst[5] = {3, 0, 0, 0, 4}, classes[5] = {26, 21, 17, 7, 21};
  for (int u = 0; u < 5; ++u) ids.at<int>(0, u) = inst[u], labels.at<int>(0, u) = classes[u];
  tracking::mark_occluder_classes(labels, {17, 21}, &ids);
  EXPECT_EQ(ids.at<int>(0, 0), 3);
  EXPECT_EQ(ids.at<int>(0, 1), tracking::kOccluderId);
  EXPECT_EQ(ids.at<int>(0, 2), tracking::kOccluderId);
  EXPECT_EQ(ids.at<int>(0, 3), 0);
  EXPECT_EQ(ids.at<int>(0, 4), 4);
  EXPECT_LT(tracking::kOccluderId, 0);  // no instance for the second pass and the id lookups
  // no classes: nothing changes; wrong types or sizes throw
  cv::Mat untouched = cv::Mat::zeros(1, 5, CV_32SC1);
  tracking::mark_occluder_classes(labels, {}, &untouched);
  EXPECT_EQ(cv::countNonZero(untouched), 0);
  cv::Mat wrong_type = cv::Mat::zeros(1, 5, CV_8UC1);
  EXPECT_THROW(tracking::mark_occluder_classes(labels, {21}, &wrong_type), std::invalid_argument);
  EXPECT_THROW(tracking::mark_occluder_classes(labels(cv::Rect(0, 0, 4, 1)), {21}, &untouched),
               std::invalid_argument);
}

TEST(ObjectClassMask, WrongTypesOrSizesThrow) {
  const cv::Mat instances = cv::Mat::ones(4, 5, CV_32SC1), labels = cv::Mat::ones(4, 5, CV_32SC1);
  for (const cv::Mat& bad : {cv::Mat(cv::Mat::ones(4, 5, CV_8UC1)), cv::Mat(cv::Mat::ones(4, 5, CV_16SC1))})
    EXPECT_THROW(tracking::object_class_mask(bad, labels, {1}), std::invalid_argument);
  for (const cv::Mat& bad : {cv::Mat(cv::Mat::ones(4, 5, CV_16UC1)), cv::Mat(cv::Mat::ones(5, 4, CV_32SC1))})
    EXPECT_THROW(tracking::object_class_mask(instances, bad, {1}), std::invalid_argument);
  EXPECT_NO_THROW(tracking::object_class_mask(instances, labels, {1}));
}

// ---------------------------------------------------------------- a small car at 40 m

constexpr int kCarPlane = 1;
constexpr double kCarDepthM = 40.0;  // m: where a car covers ~40 x 30 px on KITTI
constexpr double kCarContrast = 0.6;  // of the background's texture contrast
constexpr int kCarRegionLabel = 7, kBackgroundLabel = 11;  // static classes (road, building)

// A textured background at 55 m and a "car" plane of 2.2 x 1.66 m at 40 m (~40 x 30 px) in
// front of it, rendered for KITTI 0000; the mask is the car's pixels in the left image.
struct CarScene {
  geometry::StereoCamera cam = ts::kitti_camera();
  std::vector<ts::Plane> planes;
  cv::Mat left, right, ids_left, ids_right, mask, labels;

  CarScene() {
    planes = {ts::make_plane(55.0, -60, -20, 60, 20, 1.3, cam.fx, 71),
              ts::make_plane(kCarDepthM, -1.0, -0.2, 1.2, 1.46, 1.3, cam.fx, 72)};
    // a car's paint is weaker texture than the background's (std 40 -> kCarContrast x 40):
    // the main pass's FAST threshold finds little there, the object pass's lower one does
    planes[kCarPlane].texture = (planes[kCarPlane].texture - 128.0) * kCarContrast + 128.0;
    left = ts::render(planes, cam, false, &ids_left, 1.0, 700);
    right = ts::render(planes, cam, true, &ids_right, 1.0, 701);
    mask = cv::Mat(ids_left == kCarPlane);
    labels = cv::Mat(left.size(), CV_32SC1, cv::Scalar(kBackgroundLabel));
    labels.setTo(kCarRegionLabel, mask);
  }
  // true depth along the left axis at a left pixel
  double depth(const cv::Point2f& p) const {
    const ts::Hit h = ts::cast_ray(planes, cam, cam.t_left, p.x, p.y);
    return h.plane < 0 ? -1.0 : (h.X_c + cam.t_left).z();
  }
};

const CarScene& car_scene() {
  static const CarScene s;
  return s;
}

bool in_mask(const cv::Mat& mask, const cv::Point2f& p) {
  const int u = cvRound(p.x), v = cvRound(p.y);
  return u >= 0 && v >= 0 && u < mask.cols && v < mask.rows && mask.at<std::uint8_t>(v, u) != 0;
}

// Whether the SAD window of the search (StereoSearchOptions' 15 x 5 level px, plus one pixel)
// around the keypoint lies inside the mask.
bool window_inside(const cv::Mat& mask, const cv::KeyPoint& k) {
  const features::StereoSearchOptions search;
  const double scale = std::pow(1.2, k.octave);
  const int half_w = static_cast<int>(std::ceil((search.patch_radius + 1) * scale));
  const int half_h = static_cast<int>(std::ceil((search.patch_half_height + 1) * scale));
  for (int dv = -half_h; dv <= half_h; ++dv)
    for (int du = -half_w; du <= half_w; ++du)
      if (!in_mask(mask, k.pt + cv::Point2f(static_cast<float>(du), static_cast<float>(dv)))) return false;
  return true;
}

TEST(ObjectKeypointExtractor, AddsSpacedKeypointsWithDepthInsideTheMask) {
  const CarScene& s = car_scene();
  const features::OrbExtractor main_orb(features::OrbOptions{});
  features::StereoFeatures f = features::extract_and_match(main_orb, s.left, s.right, s.cam);
  features::StereoFeatures before = f;
  before.left.descriptors = f.left.descriptors.clone();
  const int n_old = static_cast<int>(f.left.size());
  int old_in_mask = 0;
  for (const cv::KeyPoint& k : f.left.keypoints) old_in_mask += in_mask(s.mask, k.pt);

  tracking::ObjectTrackingOptions options;
  options.extra_min_spacing_px = 5.0;  // px: wider than ORB's own spacing, so the test can bite
  const tracking::ObjectKeypointExtractor extra(main_orb.options(), options);
  const tracking::ObjectKeypointReport report = extra.extract(s.left, s.mask, s.cam, &f);

  const int n = static_cast<int>(f.left.size());
  ASSERT_EQ(report.num_added, n - n_old);
  ASSERT_EQ(f.left.descriptors.rows, n);
  ASSERT_EQ(f.matches.u_right.size(), static_cast<size_t>(n));
  ASSERT_EQ(f.matches.depth.size(), static_cast<size_t>(n));
  // the main pass's keypoints and descriptors are untouched
  for (int i = 0; i < n_old; ++i) {
    EXPECT_EQ(f.left.keypoints[i].pt, before.left.keypoints[i].pt);
    EXPECT_EQ(cv::norm(f.left.descriptors.row(i), before.left.descriptors.row(i), cv::NORM_HAMMING), 0);
  }
  int new_with_depth = 0, new_accurate = 0, gained_depth = 0, interior = 0, interior_accurate = 0;
  for (int i = n_old; i < n; ++i) {
    const cv::KeyPoint& k = f.left.keypoints[i];
    EXPECT_TRUE(in_mask(s.mask, k.pt)) << "new keypoint " << i << " at " << k.pt;
    EXPECT_LE(k.octave, options.extra_keypoint_levels - 1);
    for (int j = 0; j < i; ++j)
      ASSERT_GE(cv::norm(k.pt - f.left.keypoints[j].pt), options.extra_min_spacing_px)
          << "new keypoint " << i << " too close to " << j;
    const bool accurate = f.matches.depth[i] > 0 &&
                          std::abs(f.matches.depth[i] - s.depth(k.pt)) < 0.02 * s.depth(k.pt);
    new_with_depth += f.matches.depth[i] > 0;
    new_accurate += accurate;
    if (window_inside(s.mask, k)) ++interior, interior_accurate += accurate;
  }
  for (int i = 0; i < n; ++i) {
    const bool had = i < n_old && before.matches.depth[i] > 0;
    if (had) EXPECT_EQ(f.matches.depth[i], before.matches.depth[i]) << "keypoint " << i;
    if (!had && f.matches.depth[i] > 0) {
      ++gained_depth;
      EXPECT_TRUE(in_mask(s.mask, f.left.keypoints[i].pt)) << "keypoint " << i;
    }
  }
  std::cout << "[ object keypoints ] mask " << cv::countNonZero(s.mask) << " px, main pass "
            << old_in_mask << " keypoints inside, added " << report.num_added << " (with depth "
            << new_with_depth << ", within 2 % " << new_accurate << "), new depths "
            << report.num_new_depth << "; SAD window inside the car " << interior << " (within 2 % "
            << interior_accurate << ")\n";
  EXPECT_LE(old_in_mask, 3);  // the premise: the main pass leaves the car nearly bare
  EXPECT_GE(report.num_added, 15);
  EXPECT_EQ(report.num_new_depth, gained_depth);
  // keypoints on the car's outline see the background in part of their window (and may take
  // its depth): most keypoints, and nearly all away from the outline, get the car's depth
  EXPECT_GE(new_accurate, 0.6 * report.num_added);
  ASSERT_GE(interior, 8);
  EXPECT_GE(interior_accurate, 0.9 * interior);
}

TEST(ObjectKeypointExtractor, EmptyMaskAddsNothing) {
  const CarScene& s = car_scene();
  const features::OrbExtractor main_orb(features::OrbOptions{});
  features::StereoFeatures f = features::extract_and_match(main_orb, s.left, s.right, s.cam);
  const size_t n = f.left.size();
  const std::vector<float> depth = f.matches.depth;
  const tracking::ObjectKeypointExtractor extra(main_orb.options(), tracking::ObjectTrackingOptions{});
  for (const cv::Mat& mask : {cv::Mat(), cv::Mat(cv::Mat::zeros(s.left.size(), CV_8UC1))}) {
    const tracking::ObjectKeypointReport r = extra.extract(s.left, mask, s.cam, &f);
    EXPECT_EQ(r.num_added, 0);
    EXPECT_EQ(r.num_new_depth, 0);
    EXPECT_EQ(f.left.size(), n);
    EXPECT_EQ(f.matches.depth, depth);
  }
  // matches that do not belong to the keypoints are refused
  f.matches.depth.pop_back();
  EXPECT_THROW(extra.extract(s.left, s.mask, s.cam, &f), std::invalid_argument);
}

TEST(ObjectKeypointExtractor, AnInstanceTheSharedBudgetLeavesShortGetsASecondPass) {
  // the car (instance 1) beside a large instance (2: most of the background, its texture
  // stronger than the car's paint): the pass's budget goes to the large one
  const CarScene& s = car_scene();
  cv::Mat instances(s.left.size(), CV_32SC1, cv::Scalar(0));
  instances(cv::Rect(0, 0, s.left.cols * 3 / 5, s.left.rows)).setTo(2);
  instances.setTo(1, s.mask);
  const cv::Mat object_mask = instances > 0;
  const features::OrbExtractor main_orb(features::OrbOptions{});
  const features::StereoFeatures f0 = features::extract_and_match(main_orb, s.left, s.right, s.cam);
  auto on_car_after = [&](int min_instance_keypoints, tracking::ObjectKeypointReport* report,
                          int min_instance_area_px = 0) {
    tracking::ObjectTrackingOptions options;
    options.extra_keypoints_max = 150;
    options.extra_min_instance_keypoints = min_instance_keypoints;
    options.extra_min_instance_area_px = min_instance_area_px;
    features::StereoFeatures f = f0;
    f.left.descriptors = f0.left.descriptors.clone();
    *report = tracking::ObjectKeypointExtractor(main_orb.options(), options)
                  .extract(s.left, object_mask, s.cam, &f, instances);
    int on_car = 0;
    for (const cv::KeyPoint& k : f.left.keypoints) on_car += in_mask(s.mask, k.pt);
    EXPECT_EQ(f.left.descriptors.rows, static_cast<int>(f.left.size()));
    EXPECT_EQ(f.matches.depth.size(), f.left.size());
    return on_car;
  };
  tracking::ObjectKeypointReport shared, second;
  const int shared_only = on_car_after(0, &shared);
  const int with_second = on_car_after(40, &second);
  std::cout << "[ object keypoints ] car keypoints: shared budget " << shared_only
            << ", with the second pass " << with_second << "\n";
  EXPECT_EQ(shared.num_deprived, 0);
  EXPECT_EQ(second.num_deprived, 1);  // the car; the large instance holds its share
  EXPECT_LE(shared_only, 10);         // the premise: the shared budget leaves the car short
  EXPECT_GE(with_second, shared_only + 15);
  // a mask smaller than the area floor gets no second pass
  const int car_px = cv::countNonZero(s.mask);
  tracking::ObjectKeypointReport small;
  EXPECT_EQ(on_car_after(40, &small, car_px + 1), shared_only);
  EXPECT_EQ(small.num_deprived, 0);
  EXPECT_EQ(on_car_after(40, &small, car_px), with_second);
  EXPECT_EQ(small.num_deprived, 1);
  // instances of another type or size are refused
  features::StereoFeatures f = f0;
  const tracking::ObjectKeypointExtractor extra(main_orb.options(), tracking::ObjectTrackingOptions{});
  for (const cv::Mat& bad : {cv::Mat(object_mask), cv::Mat(cv::Mat::ones(10, 10, CV_32SC1))})
    EXPECT_THROW(extra.extract(s.left, object_mask, s.cam, &f, bad), std::invalid_argument);
}

// ---------------------------------------------------------------- FrameBuilder

TEST(FrameBuilderObjectMask, ExtraKeypointsCarryLabelsAndNeverTrackTheCamera) {
  const CarScene& s = car_scene();
  tracking::SlamOptions options;
  const tracking::FrameBuilder builder(s.cam, options);
  tracking::Frame plain, with_mask;
  builder.build(0, 0.0, s.left, s.right, s.labels, Points3(), &plain);
  const tracking::FrameBuildReport report =
      builder.build(0, 0.0, s.left, s.right, s.labels, Points3(), &with_mask, s.mask);
  const size_t n_plain = plain.keypoints.size(), n = with_mask.keypoints.size();
  ASSERT_GT(n, n_plain);
  EXPECT_EQ(static_cast<int>(n - n_plain), report.object_keypoints.num_added);
  ASSERT_EQ(with_mask.usable.size(), n);
  ASSERT_EQ(with_mask.keypoints.label.size(), n);
  int main_on_car = 0;
  for (size_t i = 0; i < n_plain; ++i) {
    EXPECT_EQ(with_mask.keypoints.uv[i], plain.keypoints.uv[i]);
    EXPECT_EQ(with_mask.usable[i], plain.usable[i]);
    main_on_car += with_mask.keypoints.label[i] == kCarRegionLabel && with_mask.usable[i];
  }
  int extra_on_car = 0;
  for (size_t i = n_plain; i < n; ++i) {
    const Vec2& uv = with_mask.keypoints.uv[i];
    // the car's class is static: only the keypoint's origin keeps it from camera tracking
    EXPECT_EQ(with_mask.usable[i], 0) << "extra keypoint " << i;
    EXPECT_EQ(with_mask.keypoints.label[i],
              s.labels.at<int>(static_cast<int>(std::lround(uv.y())), static_cast<int>(std::lround(uv.x()))));
    extra_on_car += with_mask.keypoints.label[i] == kCarRegionLabel;
  }
  // Not all: a keypoint of octave >= 1 can sit on a half pixel (632.5) at the mask's edge,
  // inside it by the extractor's cvRound (half to even, 632) and read outside by the
  // builder's std::lround (633); see the test report.
  EXPECT_GE(extra_on_car, 0.9 * (n - n_plain));
  EXPECT_GT(main_on_car, 0);  // control: main-pass keypoints of the same class are usable
  EXPECT_EQ(with_mask.point_ids.size(), n);  // the frame's matches cover them

  // extra keypoints switched off: the mask changes nothing
  tracking::SlamOptions off = options;
  off.visual_objects.extra_keypoints = false;
  tracking::Frame unchanged;
  tracking::FrameBuilder(s.cam, off).build(0, 0.0, s.left, s.right, s.labels, Points3(), &unchanged, s.mask);
  EXPECT_EQ(unchanged.keypoints.size(), n_plain);
}

TEST(FrameBuilderObjectMask, MaskOfWrongSizeOrTypeThrows) {
  const CarScene& s = car_scene();
  const tracking::FrameBuilder builder(s.cam, tracking::SlamOptions{});
  tracking::Frame frame;
  cv::Mat as_int;
  s.mask.convertTo(as_int, CV_32S);
  const cv::Mat half = cv::Mat::zeros(s.left.rows / 2, s.left.cols / 2, CV_8UC1);
  const cv::Mat three_channels = cv::Mat::zeros(s.left.size(), CV_8UC3);
  for (const cv::Mat& bad : {as_int, half, three_channels})
    EXPECT_THROW(builder.build(0, 0.0, s.left, s.right, s.labels, Points3(), &frame, bad),
                 std::invalid_argument);
}

}  // namespace
