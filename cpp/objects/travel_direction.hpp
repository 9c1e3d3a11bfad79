#pragma once
// The direction a vehicle travels in, in its own object frame: the axis the non-holonomic
// prior (optim/heading_cost.hpp) ties its yaw to. A cluster's object frame starts
// with the camera's rotation (no canonical pose before detections), so the axis is learned
// from the track: the principal axis of its frame-to-frame displacements expressed in the
// object frame, d_o = R_w_o^T (t_w_o(i) - t_w_o(i-1)), projected onto the road plane. The
// second moment sum(d_o d_o^T) is sign-free (a car that reverses keeps its axis) and weighs
// each step by its length squared, so slow, noisy steps count little. A parked or crawling car's
// steps are mostly the depth jitter of its far stereo (along the line of sight, so just as
// anisotropic) and cancel out: the net displacement, a fraction of the path, tells them apart.
#include "geometry/types.hpp"

namespace twistslam::objects {

struct TravelDirection {
  Mat3 moments = Mat3::Zero();  // sum of d_o d_o^T, m^2
  double path_m = 0;            // sum of |d_o|, m
  Vec3 net_o = Vec3::Zero();    // sum of d_o: the net displacement in the object frame, m

  // Adds one step (object frame, m); up_o: the road normal in the object frame.
  void add_step(const Vec3& d_o, const Vec3& up_o);
  // Unit travel axis (sign arbitrary), or zero while the track has moved less than
  // min_path_m, or its steps spread too much (the largest eigenvalue of the moments must be
  // min_anisotropy times the second), or they cancel out (|net_o| below min_straightness
  // times path_m: jitter, or a car that drove and came most of the way back).
  Vec3 axis(double min_path_m, double min_anisotropy, double min_straightness = 0) const;
  // The object frame turned by R_old_new (a canonical frame replacing the cluster's first
  // one): the steps d_new = R^T d_old, so the moments become R^T M R.
  void rotate(const Mat3& R_old_new) {
    moments = R_old_new.transpose() * moments * R_old_new;
    net_o = R_old_new.transpose() * net_o;
  }
};

}  // namespace twistslam::objects
