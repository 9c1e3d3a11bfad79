#pragma once
// Votes of the 2D labels of a 3D point or cluster (S3LAM / TwistSLAM "Clusters creation"):
// every observation adds one vote for the class (or instance) under it, and the label with
// most votes is the point's. A handful of distinct labels per point: a flat vector.
#include <utility>
#include <vector>

namespace twistslam::objects {

class LabelVotes {
 public:
  void add(int label, int count = 1) {
    for (auto& [l, n] : votes_)
      if (l == label) {
        n += count;
        return;
      }
    votes_.emplace_back(label, count);
  }
  // Label with most votes (the first reached on ties); `none` without any vote.
  int best(int none = -1) const {
    int label = none, most = 0;
    for (const auto& [l, n] : votes_)
      if (n > most) label = l, most = n;
    return label;
  }
  int count(int label) const {
    for (const auto& [l, n] : votes_)
      if (l == label) return n;
    return 0;
  }
  int total() const {
    int t = 0;
    for (const auto& v : votes_) t += v.second;
    return t;
  }
  const std::vector<std::pair<int, int>>& votes() const { return votes_; }

 private:
  std::vector<std::pair<int, int>> votes_;  // (label, count)
};

}  // namespace twistslam::objects
