// Half-occluded object keypoints (features/right_occlusion.hpp).
#include "features/right_occlusion.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

namespace twistslam::features {
namespace {

cv::Point level0_pixel(const cv::KeyPoint& k) {
  // std::lround as the object tracker reads a keypoint's pixel
  return {static_cast<int>(std::lround(k.pt.x)), static_cast<int>(std::lround(k.pt.y))};
}

bool inside(const cv::Point& p, const cv::Mat& image) {
  return p.x >= 0 && p.y >= 0 && p.x < image.cols && p.y < image.rows;
}

}  // namespace

RightOcclusionReport drop_matches_occluded_in_right(const Keypoints& left,
                                                    const std::vector<int>& which,
                                                    const cv::Mat& instances, float margin_px,
                                                    int min_keypoints, StereoMatches* matches) {
  const int n = static_cast<int>(left.size());
  if (matches == nullptr || static_cast<int>(matches->depth.size()) != n ||
      static_cast<int>(matches->u_right.size()) != n)
    throw std::invalid_argument("drop_matches_occluded_in_right: matches do not belong to the keypoints");
  if (instances.empty() || instances.type() != CV_32SC1)
    throw std::invalid_argument("drop_matches_occluded_in_right: instances must be a non-empty int32 image");
  if (!(margin_px >= 0)) throw std::invalid_argument("drop_matches_occluded_in_right: margin_px must be >= 0");
  if (min_keypoints < 1) throw std::invalid_argument("drop_matches_occluded_in_right: min_keypoints must be >= 1");
  for (int i : which)
    if (i < 0 || i >= n) throw std::invalid_argument("drop_matches_occluded_in_right: keypoint index out of range");

  // each instance's disparity: the median over its matched keypoints (before any is dropped,
  // so the order of `which` does not matter)
  std::unordered_map<int, std::vector<float>> samples;
  for (int i : which) {
    if (!(matches->depth[i] > 0)) continue;
    const cv::Point p = level0_pixel(left.keypoints[i]);
    if (!inside(p, instances)) continue;
    const int id = instances.at<int>(p.y, p.x);
    if (id > 0) samples[id].push_back(left.keypoints[i].pt.x - matches->u_right[i]);
  }
  std::unordered_map<int, float> disparity;
  float max_disparity = 0.0f;
  for (auto& [id, d] : samples) {
    if (static_cast<int>(d.size()) < min_keypoints) continue;
    auto mid = d.begin() + d.size() / 2;
    std::nth_element(d.begin(), mid, d.end());
    disparity[id] = *mid;
    max_disparity = std::max(max_disparity, *mid);
  }
  RightOcclusionReport report;
  report.num_instances = static_cast<int>(disparity.size());
  if (disparity.empty()) return report;

  std::vector<int> dropped;
  for (int i : which) {
    if (!(matches->depth[i] > 0)) continue;
    const cv::KeyPoint& k = left.keypoints[i];
    const cv::Point p = level0_pixel(k);
    if (!inside(p, instances)) continue;
    const int own = instances.at<int>(p.y, p.x);
    if (own <= 0) continue;
    const float d = k.pt.x - matches->u_right[i];
    const float reach = max_disparity - d - margin_px;  // farthest column an occluder can be at
    if (reach <= 0) continue;
    const int* row = instances.ptr<int>(p.y);
    const int last = std::min(instances.cols - 1, static_cast<int>(std::floor(k.pt.x + reach)));
    for (int x = p.x + 1; x <= last; ++x) {
      const int id = row[x];
      if (id == own || id <= 0) continue;
      const auto it = disparity.find(id);
      if (it == disparity.end()) continue;  // no disparity known: cannot judge this one
      // any instance on the way may cover the ray (a farther one between does not hide a
      // nearer one's edge beyond it)
      if (it->second - d > (static_cast<float>(x) - k.pt.x) + margin_px) {
        dropped.push_back(i);
        break;
      }
    }
  }
  for (int i : dropped) {
    matches->u_right[i] = -1.0f;
    matches->depth[i] = -1.0f;
  }
  report.num_dropped = static_cast<int>(dropped.size());
  return report;
}

}  // namespace twistslam::features
