#include "io/png_file.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <fstream>
#include <stdexcept>
#include <vector>

#include "io/png_decoder.hpp"

namespace twistslam::io {
namespace {

// The whole file; false when it cannot be opened or read.
bool read_bytes(const std::string& path, std::vector<std::uint8_t>* bytes) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  const std::streamoff size = in.tellg();
  if (size < 0) return false;
  bytes->resize(static_cast<std::size_t>(size));
  in.seekg(0);
  return static_cast<bool>(in.read(reinterpret_cast<char*>(bytes->data()), size));
}

}  // namespace

cv::Mat read_png_rgb8(const std::string& path) {
  std::vector<std::uint8_t> bytes;
  if (!read_bytes(path, &bytes) || bytes.empty())
    throw std::runtime_error(path + ": cannot read or decode the image");
  cv::Mat rgb;
  if (decode_plain_rgb8_png(bytes.data(), bytes.size(), &rgb)) return rgb;
  // every other file (and a damaged one, which OpenCV names): libpng through OpenCV
  cv::Mat bgr;
  try {
    bgr = cv::imdecode(bytes, cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": cannot decode the image (" + e.what() + ")");
  }
  if (bgr.empty()) throw std::runtime_error(path + ": cannot read or decode the image");
  if (bgr.type() != CV_8UC3)
    throw std::runtime_error(path + ": expected an 8-bit colour image");
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);  // a channel swap: exact
  return rgb;
}

}  // namespace twistslam::io
