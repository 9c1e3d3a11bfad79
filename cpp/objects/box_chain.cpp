#include "objects/box_chain.hpp"

#include <limits>

namespace twistslam::objects {

std::vector<int> box_chain(const Vec3& start, const std::vector<std::vector<Vec3>>& earlier,
                           const BoxChainOptions& options) {
  std::vector<int> chain;
  Vec3 position = start;
  Vec3 velocity = Vec3::Zero();  // per frame, forward in time
  for (const std::vector<Vec3>& boxes : earlier) {
    const Vec3 predicted = position - velocity;
    const double gate = chain.empty() ? options.first_gate_m : options.gate_m;
    double nearest = std::numeric_limits<double>::infinity(), second = nearest;
    int best = -1;
    for (size_t i = 0; i < boxes.size(); ++i) {
      const double d = (boxes[i] - predicted).norm();
      if (!(d < second)) continue;  // also skips NaN centres
      if (d < nearest) {
        second = nearest;
        nearest = d;
        best = static_cast<int>(i);
      } else {
        second = d;
      }
    }
    if (best < 0 || nearest > gate || second < nearest + options.ambiguity_m) break;
    velocity = position - boxes[best];
    position = boxes[best];
    chain.push_back(best);
  }
  return chain;
}

}  // namespace twistslam::objects
