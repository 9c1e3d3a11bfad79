#pragma once
// Private (Ceres): the object terms of the keyframe BA beyond e_dyna and the link (paper
// eq. 9): the LiDAR terms (e_det, e_reg, the detection pose prior), measured relative to the
// cameras, so that they act on camera pose blocks T_c_w and object pose blocks T_w_o together
// (bundle_adjustment.hpp: BAObjectMotion, BAObjectBox), and e_const between keyframe poses
// some frames apart. Blocks are 7-vectors [t, q] (pose_parameterization.hpp).
//
//   CameraRelativeMotionCost  W Pi (log(S T_w_cb D T_ca_w S^-1) - log(S T_ob T_oa^-1 S^-1))
//                             blocks (T_ca_w, T_cb_w, T_w_oa, T_w_ob)
//   CameraRelativeBoxCost     W [t_c_o - t_c_box; log(R_c_box^T R_c_o)], T_c_o = T_c_w T_w_o
//                             blocks (T_c_w, T_w_o)
//   KeyframeConstantVelocityCost
//                             W Pi (log(S T_oc T_ob^-1 S^-1) / n_bc - log(S T_ob T_oa^-1 S^-1) / n_ab)
//                             blocks (T_w_oa, T_w_ob, T_w_oc): the mean per-frame twists of
//                             two consecutive keyframe intervals of n_ab and n_bc frames
//                             (at constant velocity log(T_b T_a^-1) = n_ab xi)
//
// S = [I, -c] moves the origin to the object (c: its initial position at pose a). Autodiff:
// a few such terms per object and keyframe window, against hundreds of reprojections, so the
// analytic Jacobians of object_costs.hpp would buy nothing measurable here.
#include <ceres/autodiff_cost_function.h>

#include "optim/object_costs.hpp"
#include "optim/se3_jet.hpp"

namespace twistslam::optim::detail {

// A pose block [t, q] of Jets (or doubles) from a rotation and a translation.
template <typename T>
void to_pose_block(const Eigen::Quaternion<T>& q, const Eigen::Matrix<T, 3, 1>& t, T* out) {
  out[0] = t[0], out[1] = t[1], out[2] = t[2];
  out[3] = q.x(), out[4] = q.y(), out[5] = q.z(), out[6] = q.w();
}

// log(S [q, t] S^-1) for S = [I, -c]: the motion about the point c, as a twist [v; w].
template <typename T>
Eigen::Matrix<T, 6, 1> twist_about(const Eigen::Quaternion<T>& q, const Eigen::Matrix<T, 3, 1>& t,
                                   const Vec3& c) {
  const Eigen::Matrix<T, 3, 1> c_t = c.cast<T>();
  const Eigen::Matrix<T, 3, 1> t_local = t + q * c_t - c_t;  // S M S^-1 X = R X + t + R c - c
  T identity[kPoseSize] = {T(0), T(0), T(0), T(0), T(0), T(0), T(1)};
  T motion[kPoseSize];
  to_pose_block(q, t_local, motion);
  return relative_twist(identity, motion);
}

struct CameraRelativeMotionCost {
  Mat6 M;  // W Pi
  Eigen::Quaterniond q_D;
  Vec3 t_D;
  Vec3 c;

  template <typename T>
  bool operator()(const T* cam_a, const T* cam_b, const T* obj_a, const T* obj_b, T* r) const {
    using Vec3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> qa = pose_quaternion(cam_a), qb = pose_quaternion(cam_b);
    const Eigen::Map<const Vec3T> ta(cam_a), tb(cam_b);
    // measured world motion T_w_cb D T_ca_w: X -> q_b^* (q_D (q_a X + t_a) + t_D - t_b)
    const Eigen::Quaternion<T> qD = q_D.cast<T>();
    const Eigen::Quaternion<T> q_meas = qb.conjugate() * qD * qa;
    const Vec3T t_meas = qb.conjugate() * (qD * ta + t_D.cast<T>() - tb);
    // the object's world motion T_w_ob T_w_oa^-1
    const Eigen::Quaternion<T> qoa = pose_quaternion(obj_a), qob = pose_quaternion(obj_b);
    const Eigen::Quaternion<T> q_obj = qob * qoa.conjugate();
    const Vec3T t_obj = Eigen::Map<const Vec3T>(obj_b) - q_obj * Eigen::Map<const Vec3T>(obj_a);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(r);
    residual = M.cast<T>() * (twist_about(q_meas, t_meas, c) - twist_about(q_obj, t_obj, c));
    return true;
  }
};

struct CameraRelativeBoxCost {
  Vec6 w;  // diag(W)
  Eigen::Quaterniond q_box;
  Vec3 t_box;

  template <typename T>
  bool operator()(const T* cam, const T* obj, T* r) const {
    using Vec3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> qc = pose_quaternion(cam), qo = pose_quaternion(obj);
    const Eigen::Quaternion<T> q_co = qc * qo;
    const Vec3T t_co = qc * Eigen::Map<const Vec3T>(obj) + Eigen::Map<const Vec3T>(cam);
    T theta2;
    const Vec3T phi = quaternion_log<T>(q_box.cast<T>().conjugate() * q_co, &theta2);
    for (int i = 0; i < 3; ++i) {
      r[i] = T(w[i]) * (t_co[i] - T(t_box[i]));
      r[3 + i] = T(w[3 + i]) * phi[i];
    }
    return true;
  }
};

struct KeyframeConstantVelocityCost {
  Mat6 M;  // W Pi
  double inv_n_ab, inv_n_bc;
  Vec3 c;

  template <typename T>
  Eigen::Matrix<T, 6, 1> twist(const T* a, const T* b) const {
    using Vec3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> q = pose_quaternion(b) * pose_quaternion(a).conjugate();
    const Vec3T t = Eigen::Map<const Vec3T>(b) - q * Eigen::Map<const Vec3T>(a);
    return twist_about(q, t, c);
  }

  template <typename T>
  bool operator()(const T* a, const T* b, const T* pc, T* r) const {
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(r);
    residual = M.cast<T>() * (T(inv_n_bc) * twist(b, pc) - T(inv_n_ab) * twist(a, b));
    return true;
  }
};

// Throw std::invalid_argument for a sigma that is not finite and > 0 (twist_weights).
inline ceres::CostFunction* make_camera_relative_motion_cost(const Mat6& Pi, const Mat4& D,
                                                             const Vec3& c, double sigma_t,
                                                             double sigma_r) {
  CameraRelativeMotionCost* f = new CameraRelativeMotionCost;
  f->M = twist_weights(sigma_t, sigma_r).asDiagonal() * Pi;
  f->q_D = Eigen::Quaterniond(Mat3(D.topLeftCorner<3, 3>())).normalized();
  f->t_D = D.topRightCorner<3, 1>();
  f->c = c;
  return new ceres::AutoDiffCostFunction<CameraRelativeMotionCost, 6, kPoseSize, kPoseSize,
                                         kPoseSize, kPoseSize>(f);
}

inline ceres::CostFunction* make_camera_relative_box_cost(const Mat4& T_c_box, double sigma_t,
                                                          double sigma_r) {
  CameraRelativeBoxCost* f = new CameraRelativeBoxCost;
  f->w = twist_weights(sigma_t, sigma_r);
  f->q_box = Eigen::Quaterniond(Mat3(T_c_box.topLeftCorner<3, 3>())).normalized();
  f->t_box = T_c_box.topRightCorner<3, 1>();
  return new ceres::AutoDiffCostFunction<CameraRelativeBoxCost, 6, kPoseSize, kPoseSize>(f);
}

// n_ab, n_bc >= 1 frames; sigmas per frame (twist change), W from them.
inline ceres::CostFunction* make_keyframe_constant_velocity_cost(const Mat6& Pi, int n_ab, int n_bc,
                                                                 const Vec3& c, double sigma_t,
                                                                 double sigma_r) {
  if (n_ab < 1 || n_bc < 1)
    throw std::invalid_argument("keyframe e_const: frame gaps must be >= 1");
  KeyframeConstantVelocityCost* f = new KeyframeConstantVelocityCost;
  f->M = twist_weights(sigma_t, sigma_r).asDiagonal() * Pi;
  f->inv_n_ab = 1.0 / n_ab;
  f->inv_n_bc = 1.0 / n_bc;
  f->c = c;
  return new ceres::AutoDiffCostFunction<KeyframeConstantVelocityCost, 6, kPoseSize, kPoseSize,
                                         kPoseSize>(f);
}

}  // namespace twistslam::optim::detail
