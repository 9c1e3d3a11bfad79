#include <gtest/gtest.h>

#include "core_info/build_info.hpp"

TEST(BuildInfo, ReportsEveryLinkedLibrary) {
  const auto info = twistslam::build_info();
  for (const char* lib : {"eigen", "ceres", "opencv_runtime", "pcl"}) {
    ASSERT_TRUE(info.count(lib)) << lib;
    EXPECT_FALSE(info.at(lib).empty()) << lib;
  }
  EXPECT_EQ(info.at("opencv_compiled"), info.at("opencv_runtime"));
}
