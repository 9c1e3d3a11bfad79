// Lucas-Kanade refinement of flow-predicted pixels (tracking/flow_refinement.hpp): a flow a few
// tenths of a pixel off is brought back onto the texture's true motion; a prediction farther
// off than the bound, or a patch without texture, is not kept.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "tracking/flow_refinement.hpp"

namespace twistslam::tracking {
namespace {

// Blurred uniform noise (a car's paint and trim at a few pixels' scale), and the same image
// moved by (dx, dy) px with bilinear interpolation.
struct ShiftedPair {
  cv::Mat previous, current;
};

ShiftedPair textured_pair(double dx, double dy) {
  cv::Mat noise(160, 240, CV_8UC1);
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  ShiftedPair pair;
  cv::GaussianBlur(noise, pair.previous, cv::Size(0, 0), 1.5);
  cv::normalize(pair.previous, pair.previous, 0, 255, cv::NORM_MINMAX);
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::warpAffine(pair.previous, pair.current, shift, pair.previous.size(), cv::INTER_LINEAR,
                 cv::BORDER_REFLECT);
  return pair;
}

std::vector<Vec2> grid_pixels() {
  std::vector<Vec2> out;
  for (int y = 30; y <= 130; y += 10)
    for (int x = 30; x <= 210; x += 10) out.emplace_back(x + 0.25, y + 0.5);
  return out;
}

TEST(FlowRefinement, ABiasedFlowIsBroughtBackOntoTheTrueMotion) {
  const Vec2 motion(2.3, -1.4), flow_error(0.6, -0.4);  // px
  const ShiftedPair pair = textured_pair(motion.x(), motion.y());
  const LkPyramids pyramids = build_lk_pyramids(pair.previous, pair.current);
  const std::vector<Vec2> from = grid_pixels();
  std::vector<Vec2> to;
  for (const Vec2& p : from) to.push_back(p + motion + flow_error);
  const std::vector<char> kept = refine_flow_pixels(pyramids, from, &to, 1.5);
  std::vector<double> errors;
  for (size_t k = 0; k < from.size(); ++k) {
    ASSERT_TRUE(kept[k]) << k;
    errors.push_back((to[k] - (from[k] + motion)).norm());
  }
  std::sort(errors.begin(), errors.end());
  std::cout << "[ Lucas-Kanade ] flow error " << flow_error.norm() << " px -> median "
            << errors[errors.size() / 2] << ", 95 % " << errors[errors.size() * 95 / 100] << " px\n";
  // measured: the flow's 0.72 px error down to a median of ~0.01 px
  EXPECT_LT(errors[errors.size() / 2], 0.05);
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.15);
}

// A frame's current pyramid is the next frame's previous one (ObjectTracker keeps it): the
// pixels refined on the kept pyramid equal those refined on two freshly built ones, bit for
// bit; a pyramid of another size is refused.
TEST(FlowRefinement, TheLastFramesPyramidServesAsThePreviousOne) {
  const Vec2 motion(1.7, 0.9);
  const ShiftedPair first = textured_pair(0.0, 0.0), second = textured_pair(motion.x(), motion.y());
  // frame 1 -> 2: `second.current`'s pyramid, built as frame 1's current one
  const LkPyramids last = build_lk_pyramids(first.previous, second.previous);
  const std::vector<Vec2> from = grid_pixels();
  std::vector<Vec2> fresh_to, kept_to;
  for (const Vec2& p : from) fresh_to.push_back(p + motion + Vec2(0.4, -0.3));
  kept_to = fresh_to;
  const std::vector<char> fresh =
      refine_flow_pixels(build_lk_pyramids(second.previous, second.current), from, &fresh_to, 1.5);
  const std::vector<char> kept =
      refine_flow_pixels(build_lk_pyramids(last.current, second.current), from, &kept_to, 1.5);
  EXPECT_EQ(kept, fresh);
  EXPECT_EQ(kept_to, fresh_to);
  EXPECT_GT(std::count(kept.begin(), kept.end(), 1), static_cast<long>(from.size()) * 9 / 10);
  cv::Mat smaller;
  cv::resize(second.current, smaller, cv::Size(), 0.5, 0.5);
  EXPECT_THROW(build_lk_pyramids(last.current, smaller), std::invalid_argument);
}

TEST(FlowRefinement, APredictionFartherThanTheBoundOrNoTextureIsNotKept) {
  const Vec2 motion(2.3, -1.4);
  const ShiftedPair pair = textured_pair(motion.x(), motion.y());
  const std::vector<Vec2> from = grid_pixels();
  // 3 px off: Lucas-Kanade finds the texture 3 px away, beyond the 1 px bound
  std::vector<Vec2> to;
  for (const Vec2& p : from) to.push_back(p + motion + Vec2(3.0, 0.0));
  const std::vector<Vec2> predicted = to;
  const std::vector<char> kept =
      refine_flow_pixels(build_lk_pyramids(pair.previous, pair.current), from, &to, 1.0);
  int kept_count = 0;
  for (size_t k = 0; k < from.size(); ++k) {
    kept_count += kept[k];
    if (!kept[k]) EXPECT_EQ(to[k], predicted[k]) << "a rejected pixel keeps the prediction";
  }
  EXPECT_LE(kept_count, static_cast<int>(from.size()) / 20);
  // a flat image: no gradient to align
  const cv::Mat flat(160, 240, CV_8UC1, cv::Scalar(128));
  std::vector<Vec2> flat_to;
  for (const Vec2& p : from) flat_to.push_back(p + Vec2(0.3, 0.2));
  const std::vector<char> flat_kept = refine_flow_pixels(build_lk_pyramids(flat, flat), from, &flat_to, 1.0);
  EXPECT_EQ(std::count(flat_kept.begin(), flat_kept.end(), 1), 0);
}

TEST(FlowRefinement, BadInputThrows) {
  const ShiftedPair pair = textured_pair(1.0, 0.0);
  EXPECT_THROW(build_lk_pyramids(pair.previous, cv::Mat(10, 10, CV_8UC1)), std::invalid_argument);
  EXPECT_THROW(build_lk_pyramids(cv::Mat(), pair.current), std::invalid_argument);
  cv::Mat color;
  cv::cvtColor(pair.previous, color, cv::COLOR_GRAY2BGR);
  EXPECT_THROW(build_lk_pyramids(color, color), std::invalid_argument);
  const LkPyramids pyramids = build_lk_pyramids(pair.previous, pair.current);
  std::vector<Vec2> to(2, Vec2(50, 50));
  EXPECT_THROW(refine_flow_pixels(pyramids, {Vec2(50, 50)}, &to, 1.0), std::invalid_argument);
  EXPECT_THROW(refine_flow_pixels(pyramids, {Vec2(50, 50)}, nullptr, 1.0), std::invalid_argument);
  // nothing to refine, or no pyramids: nothing kept
  std::vector<Vec2> none;
  EXPECT_TRUE(refine_flow_pixels(pyramids, {}, &none, 1.0).empty());
  std::vector<Vec2> one(1, Vec2(50, 50));
  EXPECT_EQ(refine_flow_pixels(LkPyramids(), {Vec2(50, 50)}, &one, 1.0), std::vector<char>(1, 0));
}

}  // namespace
}  // namespace twistslam::tracking
