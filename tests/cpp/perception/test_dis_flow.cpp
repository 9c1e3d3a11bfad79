// DIS flow on a textured image shifted by a known sub-pixel amount: the median flow must
// recover the shift; bad inputs and options raise std::invalid_argument.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "perception/dis_flow.hpp"

namespace p = twistslam::perception;

namespace {

// Smooth random texture: white noise blurred so that gradients exist at every scale DIS uses.
cv::Mat textured_image(int width, int height, unsigned seed) {
  cv::Mat noise(height, width, CV_32F);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(0.f, 255.f);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) noise.at<float>(y, x) = uniform(rng);
  cv::Mat blurred;
  cv::GaussianBlur(noise, blurred, cv::Size(0, 0), 2.0);
  cv::normalize(blurred, blurred, 0, 255, cv::NORM_MINMAX);
  return blurred;
}

// current(x, y) = previous(x - du, y - dv): the true flow is (du, dv) everywhere.
cv::Mat shifted(const cv::Mat& image, double du, double dv) {
  cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, du, 0, 1, dv);
  cv::Mat out;
  cv::warpAffine(image, out, M, image.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return out;
}

double median_channel(const cv::Mat& flow, int channel, int margin) {
  std::vector<float> values;
  for (int y = margin; y < flow.rows - margin; ++y)
    for (int x = margin; x < flow.cols - margin; ++x) values.push_back(flow.at<cv::Vec2f>(y, x)[channel]);
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace

TEST(DisFlow, RecoversASubPixelShift) {
  cv::Mat texture = textured_image(320, 160, 7);
  cv::Mat previous, current;
  texture.convertTo(previous, CV_8U);
  shifted(texture, 3.4, -1.7).convertTo(current, CV_8U);
  const cv::Mat flow = p::dis_flow(previous, current, p::DisFlowOptions{});
  ASSERT_EQ(flow.type(), CV_32FC2);
  ASSERT_EQ(flow.size(), previous.size());
  EXPECT_NEAR(median_channel(flow, 0, 16), 3.4, 0.2);
  EXPECT_NEAR(median_channel(flow, 1, 16), -1.7, 0.2);
}

TEST(DisFlow, ColourImagesGiveTheSameFlowAsGrey) {
  cv::Mat texture = textured_image(160, 96, 3);
  cv::Mat grey_a, grey_b, rgb_a, rgb_b;
  texture.convertTo(grey_a, CV_8U);
  shifted(texture, 2.0, 1.0).convertTo(grey_b, CV_8U);
  cv::cvtColor(grey_a, rgb_a, cv::COLOR_GRAY2RGB);
  cv::cvtColor(grey_b, rgb_b, cv::COLOR_GRAY2RGB);
  const cv::Mat from_grey = p::dis_flow(grey_a, grey_b, p::DisFlowOptions{});
  const cv::Mat from_rgb = p::dis_flow(rgb_a, rgb_b, p::DisFlowOptions{});
  EXPECT_LT(cv::norm(from_grey, from_rgb, cv::NORM_INF), 1e-3);
}

TEST(DisFlow, RejectsBadImagesAndOptions) {
  cv::Mat a(40, 60, CV_8UC1, cv::Scalar(0)), b(40, 61, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(p::dis_flow(a, b, p::DisFlowOptions{}), std::invalid_argument);
  EXPECT_THROW(p::dis_flow(cv::Mat(), a, p::DisFlowOptions{}), std::invalid_argument);
  cv::Mat as_float(40, 60, CV_32FC1, cv::Scalar(0));
  EXPECT_THROW(p::dis_flow(as_float, as_float, p::DisFlowOptions{}), std::invalid_argument);
  p::DisFlowOptions bad;
  bad.patch_size_px = 1;
  EXPECT_THROW(p::validate(bad), std::invalid_argument);
  bad = {};
  bad.finest_scale_level = 11;
  EXPECT_THROW(p::validate(bad), std::invalid_argument);
  EXPECT_THROW(p::dis_preset_from_name("slow"), std::invalid_argument);
  EXPECT_EQ(p::dis_preset_from_name("fast"), p::DisPreset::Fast);
}
