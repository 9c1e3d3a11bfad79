#include "objects/motion_model.hpp"

#include "geometry/se3.hpp"

namespace twistslam::objects {

Mat4 predict_pose(const Mat4& T_w_o, const Vec6& xi, const Mat6& Pi) {
  return geometry::se3_exp(Pi * xi) * T_w_o;
}

}  // namespace twistslam::objects
