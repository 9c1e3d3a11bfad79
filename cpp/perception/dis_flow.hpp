#pragma once
// Dense optical flow between two grey images with OpenCV's DIS (Dense Inverse Search,
// Kroeger et al. 2016): the default classical flow source of the perception stage. It needs
// no weights and runs in tens of milliseconds on a KITTI-sized image on one core.
#include <opencv2/core.hpp>

#include <string>

namespace twistslam::perception {

// The speed / accuracy preset of cv::DISOpticalFlow; the fields below override its values.
enum class DisPreset { UltraFast, Fast, Medium };

// Options of the DIS flow; -1 keeps the preset's value. Names carry their units.
struct DisFlowOptions {
  DisPreset preset = DisPreset::Medium;
  // Finest pyramid level searched (0 = full resolution). Coarser is faster but blurs
  // motion boundaries: each level halves the resolution of the flow.
  int finest_scale_level = -1;
  int patch_size_px = -1;    // side of the square patches matched by inverse search
  int patch_stride_px = -1;  // distance between patch centres; smaller = denser, slower
  int gradient_descent_iterations = -1;  // per patch and level
  int variational_refinement_iterations = -1;  // 0 disables the variational smoothing
  bool use_spatial_propagation = true;
};

// Checks every field; std::invalid_argument naming the field when one is out of range.
void validate(const DisFlowOptions& options);

// Preset name "ultrafast" | "fast" | "medium" -> enum; std::invalid_argument otherwise.
DisPreset dis_preset_from_name(const std::string& name);

// Flow from `previous` to `current` (same size, CV_8UC1 or CV_8UC3 RGB): a CV_32FC2 image of
// (u, v) in pixels such that previous(x, y) ~ current(x + u, y + v).
// std::invalid_argument on empty images, size or type mismatch.
cv::Mat dis_flow(const cv::Mat& previous, const cv::Mat& current, const DisFlowOptions& options);

}  // namespace twistslam::perception
