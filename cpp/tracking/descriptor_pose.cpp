#include "tracking/descriptor_pose.hpp"

#include <limits>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "geometry/so3.hpp"

namespace twistslam::tracking {

std::optional<DescriptorPose> pose_from_descriptors(const Frame& frame, const map::Map& map,
                                                    const std::vector<int>& point_ids,
                                                    const geometry::StereoCamera& camera,
                                                    const DescriptorPoseOptions& options) {
  const map::StereoKeypoints& kp = frame.keypoints;
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  // brute force over all keypoints, as it runs once per map start only; the ratio test over
  // the whole image keeps repeated texture out
  for (int pid : point_ids) {
    if (!map.has_point(pid)) continue;
    const map::MapPoint& point = map.point(pid);
    int best = std::numeric_limits<int>::max(), second = best, best_index = -1;
    for (size_t i = 0; i < kp.size(); ++i) {
      const int d = map::hamming(point.descriptor, kp.descriptors[i]);
      if (d < best) {
        second = best, best = d, best_index = static_cast<int>(i);
      } else if (d < second) {
        second = d;
      }
    }
    if (best_index < 0 || best > options.max_hamming ||
        static_cast<double>(best) > options.ratio_test * static_cast<double>(second))
      continue;
    object.emplace_back(point.X_w.x(), point.X_w.y(), point.X_w.z());
    image.emplace_back(kp.uv[best_index].x(), kp.uv[best_index].y());
  }
  DescriptorPose result;
  result.matches = static_cast<int>(object.size());
  if (result.matches < std::max(options.min_inliers, 4)) return std::nullopt;
  cv::Mat K;
  cv::eigen2cv(camera.K(), K);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  // the left image sees X_left = X_c + t_left: PnP finds [R | t + t_left] (stereo_camera.hpp)
  if (!cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false,
                          options.ransac_iterations, options.max_reprojection_px, 0.999, inliers,
                          cv::SOLVEPNP_EPNP))
    return std::nullopt;
  result.inliers = static_cast<int>(inliers.size());
  if (result.inliers < options.min_inliers) return std::nullopt;
  Vec3 w, t;
  cv::cv2eigen(rvec, w);
  cv::cv2eigen(tvec, t);
  result.T_c_w.topLeftCorner<3, 3>() = geometry::so3_exp(w);
  result.T_c_w.topRightCorner<3, 1>() = t - camera.t_left;
  return result;
}

}  // namespace twistslam::tracking
