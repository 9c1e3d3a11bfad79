#include "objects/instance_association.hpp"

#include <algorithm>
#include <set>
#include <tuple>

namespace twistslam::objects {
namespace {

struct Candidate {
  double score;
  int cluster;
  int instance;
};

// Assigns candidates best first to clusters and instances still free.
void assign_greedy(std::vector<Candidate> candidates, std::vector<int>* instance_of,
                   std::set<int>* taken) {
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(b.score, a.cluster, a.instance) < std::tie(a.score, b.cluster, b.instance);
  });
  for (const Candidate& c : candidates) {
    if ((*instance_of)[c.cluster] >= 0 || taken->count(c.instance)) continue;
    (*instance_of)[c.cluster] = c.instance;
    taken->insert(c.instance);
  }
}

}  // namespace

std::vector<int> associate_instances(const std::vector<ClusterInstanceEvidence>& evidence,
                                     const InstanceAssociationOptions& options) {
  std::vector<int> instance_of(evidence.size(), -1);
  std::set<int> taken;
  std::vector<Candidate> by_points, by_overlap;
  for (int c = 0; c < static_cast<int>(evidence.size()); ++c) {
    for (const auto& [instance, n] : evidence[c].shared.votes())
      if (instance > 0 && n >= options.min_shared_points) by_points.push_back({double(n), c, instance});
    if (evidence[c].num_projected <= 0) continue;
    for (const auto& [instance, n] : evidence[c].projected.votes()) {
      const double overlap = double(n) / evidence[c].num_projected;
      if (instance > 0 && overlap >= options.min_mask_overlap) by_overlap.push_back({overlap, c, instance});
    }
  }
  assign_greedy(std::move(by_points), &instance_of, &taken);
  assign_greedy(std::move(by_overlap), &instance_of, &taken);
  return instance_of;
}

}  // namespace twistslam::objects
