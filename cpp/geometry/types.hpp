#pragma once
// Fixed-size Eigen aliases shared by every module. Twists are xi = [v; w] (docs/design.md).
#include <Eigen/Dense>  // Core + LU + Geometry + SVD: every module needs them

namespace twistslam {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat34 = Eigen::Matrix<double, 3, 4>;
// N x 3 point arrays, row-major so that numpy (N, 3) C-contiguous data maps without a copy.
using Points3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

}  // namespace twistslam
