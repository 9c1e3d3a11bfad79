#pragma once
// Shape / dtype checks at the pybind boundary. Every bound function converts its numpy inputs
// through these helpers, so a wrong shape raises ValueError naming the argument instead of
// reaching Eigen with a bad size. float64 C-contiguous arrays pass without a copy; float32 and
// integer arrays are converted once.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "geometry/types.hpp"

namespace twistslam::bindings {

namespace py = pybind11;
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Converts any numeric array-like to C-contiguous float64; TypeError for non-numeric dtypes.
DoubleArray as_double_array(const py::handle& obj, const char* name);

std::string shape_string(const py::array& a);

// (N, cols) array; N may be 0. Raises ValueError on other shapes.
DoubleArray as_rows(const py::handle& obj, const char* name, py::ssize_t cols);

// Fixed-size arrays: a (rows, cols) matrix or, with cols == 0, a vector of length rows.
// Every value must be finite: ValueError "name: contains NaN or Inf at [i, j]" (a NaN twist
// or projection matrix has no meaning, and NaN propagates silently through everything after).
Mat4 as_mat4(const py::handle& obj, const char* name);
Mat34 as_mat34(const py::handle& obj, const char* name);
Mat3 as_mat3(const py::handle& obj, const char* name);
Mat6 as_mat6(const py::handle& obj, const char* name);
Vec3 as_vec3(const py::handle& obj, const char* name);
Vec6 as_vec6(const py::handle& obj, const char* name);

// Largest deviation from a rotation or rigid transform that is still accepted: |R^T R - I|
// (max entry) and the last row's offset from [0, 0, 0, 1]. Poses read from text
// files with 6 significant digits are off by ~1e-6; a scale, shear or reflection is off by
// 0.1 or more.
inline constexpr double kRigidTolerance = 1e-4;

// A (4, 4) rigid transform [R t; 0 0 0 1] / a (3, 3) rotation, within kRigidTolerance; else
// ValueError naming `name` and what is wrong ("T: not a rigid transform: R^T R differs from I
// by 8").
Mat4 as_rigid_transform(const py::handle& obj, const char* name);
Mat3 as_rotation(const py::handle& obj, const char* name);

// Eigen view of an (N, 3) float64 array, no copy.
inline Eigen::Map<const Points3> points_view(const DoubleArray& a) {
  return Eigen::Map<const Points3>(a.data(), a.shape(0), 3);
}

// New numpy array of the given shape, filled by the caller.
DoubleArray new_array(std::initializer_list<py::ssize_t> shape);

// numpy array (copy) of a fixed-size Eigen matrix, row-major as numpy expects.
template <typename Derived>
DoubleArray to_numpy(const Eigen::MatrixBase<Derived>& M) {
  if (M.cols() == 1) {
    DoubleArray out = new_array({M.rows()});
    for (Eigen::Index i = 0; i < M.rows(); ++i) out.mutable_data()[i] = M(i, 0);
    return out;
  }
  DoubleArray out = new_array({M.rows(), M.cols()});
  auto view = out.template mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < M.rows(); ++i)
    for (Eigen::Index j = 0; j < M.cols(); ++j) view(i, j) = M(i, j);
  return out;
}

}  // namespace twistslam::bindings
