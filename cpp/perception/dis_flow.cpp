#include "perception/dis_flow.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <stdexcept>

namespace twistslam::perception {

namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

int opencv_preset(DisPreset preset) {
  switch (preset) {
    case DisPreset::UltraFast: return cv::DISOpticalFlow::PRESET_ULTRAFAST;
    case DisPreset::Fast: return cv::DISOpticalFlow::PRESET_FAST;
    case DisPreset::Medium: return cv::DISOpticalFlow::PRESET_MEDIUM;
  }
  throw std::invalid_argument("DisFlowOptions.preset: unknown value");
}

// DIS works on 8-bit grey images; the datasets deliver RGB.
cv::Mat to_grey(const cv::Mat& image, const char* name) {
  require(!image.empty(), std::string("dis_flow: ") + name + " image is empty");
  if (image.type() == CV_8UC1) return image;
  require(image.type() == CV_8UC3, std::string("dis_flow: ") + name + " image must be CV_8UC1 or CV_8UC3");
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_RGB2GRAY);
  return grey;
}

}  // namespace

void validate(const DisFlowOptions& o) {
  // -1 = the preset's value; otherwise the ranges OpenCV accepts without asserting.
  require(o.finest_scale_level >= -1 && o.finest_scale_level <= 10,
          "DisFlowOptions.finest_scale_level: expected -1 (preset) or 0..10");
  require(o.patch_size_px == -1 || (o.patch_size_px >= 2 && o.patch_size_px <= 64),
          "DisFlowOptions.patch_size_px: expected -1 (preset) or 2..64");
  require(o.patch_stride_px == -1 || o.patch_stride_px >= 1,
          "DisFlowOptions.patch_stride_px: expected -1 (preset) or >= 1");
  require(o.patch_stride_px == -1 || o.patch_size_px == -1 || o.patch_stride_px <= o.patch_size_px,
          "DisFlowOptions.patch_stride_px: must not exceed patch_size_px (pixels would be skipped)");
  require(o.gradient_descent_iterations == -1 || o.gradient_descent_iterations >= 1,
          "DisFlowOptions.gradient_descent_iterations: expected -1 (preset) or >= 1");
  require(o.variational_refinement_iterations >= -1,
          "DisFlowOptions.variational_refinement_iterations: expected -1 (preset) or >= 0");
}

DisPreset dis_preset_from_name(const std::string& name) {
  if (name == "ultrafast") return DisPreset::UltraFast;
  if (name == "fast") return DisPreset::Fast;
  if (name == "medium") return DisPreset::Medium;
  throw std::invalid_argument("DIS preset '" + name + "': expected ultrafast, fast or medium");
}

cv::Mat dis_flow(const cv::Mat& previous, const cv::Mat& current, const DisFlowOptions& o) {
  validate(o);
  const cv::Mat a = to_grey(previous, "previous");
  const cv::Mat b = to_grey(current, "current");
  require(a.size() == b.size(), "dis_flow: previous and current images differ in size");
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(opencv_preset(o.preset));
  if (o.finest_scale_level >= 0) dis->setFinestScale(o.finest_scale_level);
  if (o.patch_size_px > 0) dis->setPatchSize(o.patch_size_px);
  if (o.patch_stride_px > 0) dis->setPatchStride(o.patch_stride_px);
  if (o.gradient_descent_iterations > 0) dis->setGradientDescentIterations(o.gradient_descent_iterations);
  if (o.variational_refinement_iterations >= 0)
    dis->setVariationalRefinementIterations(o.variational_refinement_iterations);
  dis->setUseSpatialPropagation(o.use_spatial_propagation);
  cv::Mat flow;
  dis->calc(a, b, flow);
  return flow;
}

}  // namespace twistslam::perception
