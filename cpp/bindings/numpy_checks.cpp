#include "bindings/numpy_checks.hpp"

#include <cmath>
#include <sstream>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"

namespace twistslam::bindings {

DoubleArray as_double_array(const py::handle& obj, const char* name) {
  py::array arr = py::array::ensure(obj);
  if (!arr) throw py::type_error(std::string(name) + ": expected a numpy array (or array-like)");
  const char kind = arr.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    throw py::type_error(std::string(name) + ": expected a numeric array, got dtype " +
                         std::string(py::str(arr.dtype())));
  }
  return DoubleArray::ensure(arr);
}

std::string shape_string(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

DoubleArray as_rows(const py::handle& obj, const char* name, py::ssize_t cols) {
  DoubleArray a = as_double_array(obj, name);
  if (a.ndim() != 2 || a.shape(1) != cols) {
    throw py::value_error(std::string(name) + ": expected shape (N, " + std::to_string(cols) +
                          "), got " + shape_string(a));
  }
  return a;
}

namespace {
template <int R, int C>
Eigen::Matrix<double, R, C> as_fixed(const py::handle& obj, const char* name) {
  DoubleArray a = as_double_array(obj, name);
  const bool is_vector = C == 1 && a.ndim() == 1 && a.shape(0) == R;
  const bool is_matrix = a.ndim() == 2 && a.shape(0) == R && a.shape(1) == C;
  if (!is_vector && !is_matrix) {
    const std::string want = C == 1 ? "(" + std::to_string(R) + ",)"
                                    : "(" + std::to_string(R) + ", " + std::to_string(C) + ")";
    throw py::value_error(std::string(name) + ": expected shape " + want + ", got " +
                          shape_string(a));
  }
  Eigen::Matrix<double, R, C> M;
  for (int i = 0; i < R; ++i)
    for (int j = 0; j < C; ++j) {
      M(i, j) = a.data()[i * C + j];
      if (!std::isfinite(M(i, j)))
        throw py::value_error(std::string(name) + ": contains NaN or Inf at [" + std::to_string(i) +
                              (C == 1 ? "" : ", " + std::to_string(j)) + "]");
    }
  return M;
}

}  // namespace

Mat4 as_rigid_transform(const py::handle& obj, const char* name) {
  const Mat4 T = as_fixed<4, 4>(obj, name);
  const std::string problem = geometry::rigid_transform_problem(T, kRigidTolerance);
  if (!problem.empty())
    throw py::value_error(std::string(name) + ": not a rigid transform [R t; 0 0 0 1]: " + problem);
  return T;
}

Mat3 as_rotation(const py::handle& obj, const char* name) {
  const Mat3 R = as_fixed<3, 3>(obj, name);
  const std::string problem = geometry::rotation_problem(R, kRigidTolerance);
  if (!problem.empty()) throw py::value_error(std::string(name) + ": not a rotation: " + problem);
  return R;
}

Mat4 as_mat4(const py::handle& o, const char* n) { return as_fixed<4, 4>(o, n); }
Mat34 as_mat34(const py::handle& o, const char* n) { return as_fixed<3, 4>(o, n); }
Mat3 as_mat3(const py::handle& o, const char* n) { return as_fixed<3, 3>(o, n); }
Mat6 as_mat6(const py::handle& o, const char* n) { return as_fixed<6, 6>(o, n); }
Vec3 as_vec3(const py::handle& o, const char* n) { return as_fixed<3, 1>(o, n); }
Vec6 as_vec6(const py::handle& o, const char* n) { return as_fixed<6, 1>(o, n); }

DoubleArray new_array(std::initializer_list<py::ssize_t> shape) {
  return DoubleArray(std::vector<py::ssize_t>(shape));
}

}  // namespace twistslam::bindings
