// Colour PNG files decoded by the core (io/png_file.hpp): the pixels written come back in RGB
// order, exactly; a missing and a truncated file are errors naming the file.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/png_file.hpp"

using twistslam::io::read_png_rgb8;

namespace {

std::string temp_path(const std::string& name) {
  return testing::TempDir() + "twistslam_png_" + name;
}

// The message of the exception `read` throws ("" when none).
std::string error_of(const std::string& path) {
  try {
    read_png_rgb8(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(PngFile, ColourPixelsComeBackInRgbOrderExactly) {
  cv::Mat bgr(37, 53, CV_8UC3);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(256));
  const std::string path = temp_path("rgb.png");
  ASSERT_TRUE(cv::imwrite(path, bgr));  // OpenCV writes its BGR Mat as an RGB file
  const cv::Mat rgb = read_png_rgb8(path);
  ASSERT_EQ(rgb.type(), CV_8UC3);
  ASSERT_EQ(rgb.size(), bgr.size());
  for (int r = 0; r < bgr.rows; ++r)
    for (int c = 0; c < bgr.cols; ++c) {
      const cv::Vec3b a = bgr.at<cv::Vec3b>(r, c), b = rgb.at<cv::Vec3b>(r, c);
      ASSERT_EQ(a[0], b[2]) << r << " " << c;
      ASSERT_EQ(a[1], b[1]) << r << " " << c;
      ASSERT_EQ(a[2], b[0]) << r << " " << c;
    }
  std::remove(path.c_str());
}

TEST(PngFile, MissingAndTruncatedFilesAreErrorsNamingTheFile) {
  const std::string missing = temp_path("missing.png");
  EXPECT_EQ(error_of(missing).rfind(missing + ": ", 0), 0u);
  cv::Mat bgr(40, 60, CV_8UC3);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(256));
  const std::string whole = temp_path("whole.png"), cut = temp_path("cut.png");
  ASSERT_TRUE(cv::imwrite(whole, bgr));
  std::ifstream in(whole, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(cut, std::ios::binary).write(bytes.data(), 200);  // the header and a little data
  EXPECT_EQ(error_of(cut).rfind(cut + ": ", 0), 0u);
  std::remove(whole.c_str());
  std::remove(cut.c_str());
}
