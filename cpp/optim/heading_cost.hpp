#pragma once
// Private (Ceres): the non-holonomic heading prior of a wheeled vehicle, on two consecutive
// object pose blocks T_w_o (pose_parameterization.hpp). A car moves along its heading: the
// displacement d_w of the object between frames a and b, measured by tracking, has no
// component across its travel axis h_o (a unit vector of the object frame, in the road
// plane). With the heading of the pair the mean of both frames' (a turn's chord points
// along it),
//   l      = normalize(up_w x (R_a h_o + R_b h_o))   the lateral axis in the world
//   e_head = (l . d_w) / sigma                       metres per frame, whitened
// d_w is data (the window's initial positions), not the blocks' translations: through them
// the term would trade the lateral step against the depth of a far cluster, whose points
// and poses can slide along the viewing ray together (measured: 5 m of depth drift on the
// simulator's lead car at 45 m). So only the rotations are pulled.
// Not in the TwistSLAM paper: its planar link leaves the yaw of a car seen from behind to
// the twist LM, where a near-planar rear face at 30-45 m hardly constrains it (measured:
// 20-35 deg of yaw drift over 80 frames on the simulator's lead cars). Tying the yaw to the
// direction of travel, which the positions observe well, is the classic remedy (CubeSLAM's
// non-holonomic motion model). The lateral velocity of an origin off the rear axle in a
// turn (omega x d) is left to sigma. Autodiff: one residual.
#include <ceres/autodiff_cost_function.h>

#include <cmath>
#include <stdexcept>

#include "geometry/types.hpp"

namespace twistslam::optim::detail {

struct HeadingResidual {
  HeadingResidual(const Vec3& axis_o, const Vec3& up_w, const Vec3& d_w, double weight)
      : axis_o(axis_o), up_w(up_w), d_w(d_w), weight(weight) {}

  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> qa = Eigen::Map<const Eigen::Quaternion<T>>(a + 3).normalized();
    const Eigen::Quaternion<T> qb = Eigen::Map<const Eigen::Quaternion<T>>(b + 3).normalized();
    const V3 h = qa * axis_o.cast<T>() + qb * axis_o.cast<T>();
    const V3 lateral = up_w.cast<T>().cross(h);
    const T norm = lateral.norm();
    if (!(norm > T(1e-9))) return false;  // heading along the normal: not a road vehicle
    residual[0] = T(weight) * lateral.dot(d_w.cast<T>()) / norm;
    return true;
  }

  Vec3 axis_o, up_w, d_w;
  double weight;
};

// axis_o and up_w are normalised here; throws std::invalid_argument for a sigma <= 0 or a
// zero / non-finite vector.
inline ceres::CostFunction* make_heading_cost(const Vec3& axis_o, const Vec3& up_w,
                                              const Vec3& d_w, double sigma_m) {
  if (!(sigma_m > 0) || !std::isfinite(sigma_m) || !axis_o.allFinite() || !up_w.allFinite() ||
      !d_w.allFinite() || !(axis_o.norm() > 0) || !(up_w.norm() > 0))
    throw std::invalid_argument(
        "heading cost: sigma must be finite and > 0, the axis and the normal non-zero");
  return new ceres::AutoDiffCostFunction<HeadingResidual, 1, 7, 7>(
      new HeadingResidual(axis_o.normalized(), up_w.normalized(), d_w, 1.0 / sigma_m));
}

// The same rule without a known travel axis (a track born in a turn, or not straight long
// enough to have one): the object-frame directions of two consecutive displacements agree.
// Each step's direction is taken in the mean rotation of its two frames (a turn's chord
// points along the heading of its middle), d1_w, d2_w are data as above, and
//   u_k = R_mid(k)^T d_k_w,   e = ((u_1 / |u_1|) x u_2) . up_o / sigma,   up_o = R_b^T up_w
// in metres per frame: the second step's motion across the first one's direction. A yaw that
// turns faster or slower than the path it moves along pays; the path itself is fixed data.
struct AxisFreeHeadingResidual {
  AxisFreeHeadingResidual(const Vec3& up_w, const Vec3& d1_w, const Vec3& d2_w, double weight)
      : up_w(up_w), d1_w(d1_w), d2_w(d2_w), weight(weight) {}

  template <typename T>
  static Eigen::Quaternion<T> mean_rotation(const Eigen::Quaternion<T>& a, Eigen::Quaternion<T> b) {
    if (a.dot(b) < T(0)) b.coeffs() = -b.coeffs();  // the same hemisphere
    return Eigen::Quaternion<T>(a.coeffs() + b.coeffs()).normalized();
  }

  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* residual) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> qa = Eigen::Map<const Eigen::Quaternion<T>>(a + 3).normalized();
    const Eigen::Quaternion<T> qb = Eigen::Map<const Eigen::Quaternion<T>>(b + 3).normalized();
    const Eigen::Quaternion<T> qc = Eigen::Map<const Eigen::Quaternion<T>>(c + 3).normalized();
    const V3 u1 = mean_rotation(qa, qb).conjugate() * d1_w.cast<T>();
    const V3 u2 = mean_rotation(qb, qc).conjugate() * d2_w.cast<T>();
    const V3 up_o = qb.conjugate() * up_w.cast<T>();
    const T norm = u1.norm();
    if (!(norm > T(1e-9))) return false;
    residual[0] = T(weight) * (u1 / norm).cross(u2).dot(up_o);
    return true;
  }

  Vec3 up_w, d1_w, d2_w;
  double weight;
};

// up_w is normalised here; throws std::invalid_argument for a sigma <= 0, a zero normal or a
// zero or non-finite displacement.
inline ceres::CostFunction* make_axis_free_heading_cost(const Vec3& up_w, const Vec3& d1_w,
                                                        const Vec3& d2_w, double sigma_m) {
  if (!(sigma_m > 0) || !std::isfinite(sigma_m) || !up_w.allFinite() || !(up_w.norm() > 0) ||
      !d1_w.allFinite() || !d2_w.allFinite() || !(d1_w.norm() > 0))
    throw std::invalid_argument(
        "axis-free heading cost: sigma must be finite and > 0, the normal and the first step "
        "non-zero");
  return new ceres::AutoDiffCostFunction<AxisFreeHeadingResidual, 1, 7, 7, 7>(
      new AxisFreeHeadingResidual(up_w.normalized(), d1_w, d2_w, 1.0 / sigma_m));
}

}  // namespace twistslam::optim::detail
