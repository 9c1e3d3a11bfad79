#include "core_info/build_info.hpp"

#include <Eigen/Core>
#include <ceres/version.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/core/version.hpp>
#include <pcl/pcl_config.h>

#define TWISTSLAM_STR2(x) #x
#define TWISTSLAM_STR(x) TWISTSLAM_STR2(x)

namespace twistslam {

std::map<std::string, std::string> build_info() {
  return {
      {"twistslam", TWISTSLAM_VERSION},
      {"eigen", TWISTSLAM_STR(EIGEN_WORLD_VERSION) "." TWISTSLAM_STR(
          EIGEN_MAJOR_VERSION) "." TWISTSLAM_STR(EIGEN_MINOR_VERSION)},
      {"ceres", CERES_VERSION_STRING},
      {"opencv_compiled", CV_VERSION},
      {"opencv_runtime", cv::getVersionString()},
      {"pcl", PCL_VERSION_PRETTY},
      {"compiler", __VERSION__},
  };
}

}  // namespace twistslam
