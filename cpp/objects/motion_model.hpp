#pragma once
// Constant-velocity motion under a mechanical link (paper eq. 2): the next pose is the last
// one moved by the last twist, projected onto the link's sub-space.
#include "geometry/types.hpp"

namespace twistslam::objects {

// T_w_o(i+1) = exp(Pi xi_i) T_w_o(i)
Mat4 predict_pose(const Mat4& T_w_o, const Vec6& xi, const Mat6& Pi);

}  // namespace twistslam::objects
