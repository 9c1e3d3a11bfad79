#include "io/png_file.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <stdexcept>

namespace twistslam::io {

cv::Mat read_png_rgb8(const std::string& path) {
  cv::Mat bgr;
  try {
    bgr = cv::imread(path, cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": cannot decode the image (" + e.what() + ")");
  }
  if (bgr.empty()) throw std::runtime_error(path + ": cannot read or decode the image");
  if (bgr.type() != CV_8UC3)
    throw std::runtime_error(path + ": expected an 8-bit colour image");
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);  // a channel swap: exact
  return rgb;
}

}  // namespace twistslam::io
