#pragma once
// Private (Ceres, through problem_builder.hpp): the residual families of the local BA
// (paper eq. 9) beyond e_stat, each a small class that adds its blocks and residuals to the
// one ProblemBuilder of bundle_adjust(), reports its per-observation errors and writes its
// blocks back. Included by this module's .cpp files only.
#include <cmath>
#include <cstdint>
#include <vector>

#include "optim/bundle_adjustment.hpp"
#include "optim/problem_builder.hpp"
#include "optim/stereo_projection.hpp"

namespace twistslam::optim::detail {

struct ObservationError {
  bool in_front = false;  // the point is in front of the camera(s)
  double chi2 = 0;        // inv_sigma2 * |error|^2
  double sq_px = 0;       // |error|^2 in pixels^2
  int dims = 0;           // 3 stereo, 2 mono
};

// Error of the keypoint (uv, u_right < 0: mono) against the world point X_w seen by T_c_w.
inline ObservationError observation_error(const geometry::StereoCamera& cam, const Mat4& T_c_w,
                                          const Vec3& X_w, const Vec2& uv, double u_right,
                                          double inv_sigma2, double min_depth) {
  ObservationError e;
  const Vec3 X_c = T_c_w.topLeftCorner<3, 3>() * X_w + T_c_w.topRightCorner<3, 1>();
  if (u_right >= 0) {
    Vec3 z;
    e.dims = 3;
    if (!predict_measurement<3>(cam, X_c, min_depth, &z, nullptr)) return e;
    e.sq_px = (z - Vec3(uv.x(), uv.y(), u_right)).squaredNorm();
  } else {
    Vec2 z;
    e.dims = 2;
    if (!predict_measurement<2>(cam, X_c, min_depth, &z, nullptr)) return e;
    e.sq_px = (z - uv).squaredNorm();
  }
  e.in_front = std::isfinite(e.sq_px);
  e.chi2 = inv_sigma2 * e.sq_px;
  return e;
}

// e_dyna + e_link: the objects of the problem (BAObject), their poses and points as blocks,
// their keypoints reprojected through the keyframe blocks of e_stat; and the objects' e_const
// and LiDAR terms (BAObjectMotion, BAObjectBox) between those poses (and cameras). An object is used when
// at least two of its poses are valid and seen; a point when two of its observations are
// usable (a point seen once is fixed by its own observation and tells the poses nothing).
class DynamicReprojectionTerms {
 public:
  DynamicReprojectionTerms(const BAProblem& problem, const geometry::StereoCamera& cam,
                           const BundleAdjustmentOptions& opt)
      : p_(problem), cam_(cam), opt_(opt) {}

  // keyframe_blocks: the builder block of each keyframe (-1: not in the problem, its
  // observations are skipped).
  void add_to(ProblemBuilder& b, const std::vector<int>& keyframe_blocks);
  int num_used() const { return num_used_; }
  int num_motions() const { return num_motions_; }  // BAObjectMotion terms added
  int num_boxes() const { return num_boxes_; }      // BAObjectBox terms added
  int num_const() const { return num_const_; }      // e_const terms added
  // Outlier flag per dynamic observation at the builder's current state (unused: outlier).
  std::vector<std::uint8_t> outliers(const ProblemBuilder& b) const;
  void write_back(const ProblemBuilder& b, BAProblem& problem) const;

 private:
  double threshold(const BADynamicObservation& o) const {
    return o.u_right >= 0 ? opt_.chi2_stereo : opt_.chi2_mono;
  }
  bool usable(const BADynamicObservation& o) const;
  // e_const and e_det / e_reg / the box prior of each object between its poses in the problem
  void add_object_motion_terms(ProblemBuilder& b);

  const BAProblem& p_;
  const geometry::StereoCamera& cam_;
  const BundleAdjustmentOptions& opt_;
  std::vector<int> keyframe_blocks_;
  std::vector<std::vector<int>> pose_block_, point_block_;  // per object
  std::vector<std::uint8_t> used_;
  int num_used_ = 0;
  int num_motions_ = 0, num_boxes_ = 0, num_const_ = 0;
};

// Throws std::invalid_argument naming the first dynamic observation or object pose whose
// indices are out of range.
void check_dynamic_indices(const BAProblem& p);

}  // namespace twistslam::optim::detail
