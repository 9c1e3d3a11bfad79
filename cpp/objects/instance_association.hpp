#pragma once
// Associating a frame's panoptic instances with the existing object clusters (paper sec.
// "Clusters creation"): first by the matched points they share -- a cluster's points matched
// in this frame vote for the instance under their keypoint -- then, for the clusters left
// without an instance (too few matches), by mask overlap of the cluster's points projected
// with its predicted pose. One-to-one: an instance belongs to at most one cluster.
#include <vector>

#include "objects/label_votes.hpp"

namespace twistslam::objects {

struct InstanceAssociationOptions {
  int min_shared_points = 5;      // matched points on an instance to claim it
  double min_mask_overlap = 0.5;  // fraction of the projected points inside the mask
};

struct ClusterInstanceEvidence {
  LabelVotes shared;     // instance id -> matched points of the cluster on it
  LabelVotes projected;  // instance id -> projected points of the cluster inside its mask
  int num_projected = 0; // points of the cluster projected inside the image
};

// Instance id per cluster (-1: none), greedily by decreasing evidence, one-to-one. Instance
// ids <= 0 (background) never match.
std::vector<int> associate_instances(const std::vector<ClusterInstanceEvidence>& evidence,
                                     const InstanceAssociationOptions& options);

}  // namespace twistslam::objects
