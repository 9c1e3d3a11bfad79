#include "tracking/flow_refinement.hpp"

#include <stdexcept>

#include <opencv2/video/tracking.hpp>

namespace twistslam::tracking {
namespace {

// Lucas-Kanade's window (px, a side) and pyramid levels above the image: started at the
// flow's pixel, one level covers a flow a few pixels off
constexpr int kLkWindowPx = 11;
constexpr int kLkLevels = 1;

}  // namespace

LkPyramids build_lk_pyramids(const cv::Mat& previous, const cv::Mat& current) {
  if (previous.empty() || previous.type() != CV_8UC1 || current.type() != CV_8UC1 ||
      previous.size() != current.size())
    throw std::invalid_argument("Lucas-Kanade: expected two 8-bit gray images of one size");
  LkPyramids out;
  const cv::Size window(kLkWindowPx, kLkWindowPx);
  cv::buildOpticalFlowPyramid(previous, out.previous, window, kLkLevels);
  cv::buildOpticalFlowPyramid(current, out.current, window, kLkLevels);
  return out;
}

LkPyramids build_lk_pyramids(const std::vector<cv::Mat>& previous_pyramid, const cv::Mat& current) {
  if (previous_pyramid.empty() || current.type() != CV_8UC1 ||
      previous_pyramid[0].size() != current.size())
    throw std::invalid_argument("Lucas-Kanade: expected a pyramid and an 8-bit gray image of one size");
  LkPyramids out;
  out.previous = previous_pyramid;
  cv::buildOpticalFlowPyramid(current, out.current, cv::Size(kLkWindowPx, kLkWindowPx), kLkLevels);
  return out;
}

std::vector<char> refine_flow_pixels(const LkPyramids& pyramids, const std::vector<Vec2>& from,
                                     std::vector<Vec2>* to, double max_px) {
  if (!to || to->size() != from.size())
    throw std::invalid_argument("Lucas-Kanade: one predicted pixel per pixel expected");
  std::vector<char> kept(from.size(), 0);
  if (from.empty() || pyramids.empty()) return kept;
  std::vector<cv::Point2f> previous, next;
  for (size_t k = 0; k < from.size(); ++k) {
    previous.emplace_back(static_cast<float>(from[k].x()), static_cast<float>(from[k].y()));
    next.emplace_back(static_cast<float>((*to)[k].x()), static_cast<float>((*to)[k].y()));
  }
  std::vector<unsigned char> status;
  std::vector<float> error;
  cv::calcOpticalFlowPyrLK(pyramids.previous, pyramids.current, previous, next, status, error,
                           cv::Size(kLkWindowPx, kLkWindowPx), kLkLevels,
                           cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.01),
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  for (size_t k = 0; k < from.size(); ++k) {
    const Vec2 refined(next[k].x, next[k].y);
    if (!status[k] || !refined.allFinite() || (refined - (*to)[k]).norm() > max_px) continue;
    (*to)[k] = refined;
    kept[k] = 1;
  }
  return kept;
}

}  // namespace twistslam::tracking
