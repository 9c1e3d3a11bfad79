#pragma once
// Residual weights per pyramid level: a keypoint detected at level l is located to within
// scale^l px, so its reprojection residual is weighted by 1 / sigma_l^2 (ORB-SLAM's
// invLevelSigma2), in the pose optimisation of camera tracking and in the local BA alike.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace twistslam::tracking {

class LevelWeights {
 public:
  explicit LevelWeights(const std::vector<float>& level_sigma2) {
    for (float s2 : level_sigma2) inv_sigma2_.push_back(1.0 / s2);
  }
  // Levels beyond the pyramid take the coarsest level's weight.
  double at(int octave) const {
    return inv_sigma2_[std::min<std::size_t>(octave, inv_sigma2_.size() - 1)];
  }

 private:
  std::vector<double> inv_sigma2_;
};

}  // namespace twistslam::tracking
