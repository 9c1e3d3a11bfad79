// Bindings of cpp/geometry: SE(3)/SO(3), mechanical links, stereo camera, plane fitting.
// Boxes are in boxes_bindings.cpp.
#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "bindings/numpy_checks.hpp"
#include "geometry/link_projection.hpp"
#include "geometry/plane_fit.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "geometry/stereo_camera.hpp"

namespace twistslam::bindings {
namespace g = twistslam::geometry;
using namespace pybind11::literals;

void bind_boxes(py::module_& m);

namespace {

void bind_lie(py::module_& m) {
  m.def("so3_exp", [](py::handle w) { return to_numpy(g::so3_exp(as_vec3(w, "w"))); }, "w"_a,
        R"doc(Rotation matrix of a rotation vector (Rodrigues).

Parameters
----------
w : (3,) array_like
    Rotation vector, axis times angle in radians.

Returns
-------
(3, 3) ndarray

Raises
------
ValueError
    If w is not of shape (3,) or holds NaN or Inf (as every twist argument of this module).
)doc");
  m.def("so3_log", [](py::handle R) { return to_numpy(g::so3_log(as_rotation(R, "R"))); }, "R"_a,
        "Rotation vector (3,) of a rotation matrix (3, 3), angle in [0, pi]; accurate near pi.\n"
        "ValueError unless R is finite and a rotation (R^T R = I within 1e-4, det R > 0).");
  m.def("so3_left_jacobian",
        [](py::handle w) { return to_numpy(g::so3_left_jacobian(as_vec3(w, "w"))); }, "w"_a,
        "Left Jacobian J_l(w) (3, 3): exp(w + d) ~= exp(J_l d) exp(w).");
  m.def("so3_right_jacobian",
        [](py::handle w) { return to_numpy(g::so3_right_jacobian(as_vec3(w, "w"))); }, "w"_a,
        "Right Jacobian J_r(w) = J_l(-w) (3, 3): exp(w + d) ~= exp(w) exp(J_r d).");
  m.def("so3_left_jacobian_inverse",
        [](py::handle w) { return to_numpy(g::so3_left_jacobian_inverse(as_vec3(w, "w"))); },
        "w"_a, "Inverse of the SO(3) left Jacobian (3, 3).");
  m.def("so3_right_jacobian_inverse",
        [](py::handle w) { return to_numpy(g::so3_right_jacobian_inverse(as_vec3(w, "w"))); },
        "w"_a, "Inverse of the SO(3) right Jacobian (3, 3).");

  m.def("se3_exp", [](py::handle xi) { return to_numpy(g::se3_exp(as_vec6(xi, "xi"))); },
        "xi"_a, R"doc(Exponential map of a twist.

Parameters
----------
xi : (6,) array_like
    Twist [v; w], translation part first.

Returns
-------
(4, 4) ndarray
    The rigid transform exp(xi^).

Raises
------
ValueError
    If xi is not of shape (6,) or holds NaN or Inf.
)doc");
  m.def("se3_log", [](py::handle T) { return to_numpy(g::se3_log(as_rigid_transform(T, "T"))); }, "T"_a,
        "Twist (6,) [v; w] of a rigid transform (4, 4); rotation angle in [0, pi].\n"
        "ValueError unless T is finite and rigid (R^T R = I within 1e-4, det R > 0, last row\n"
        "[0, 0, 0, 1]); every function taking a transform checks the same.");
  m.def("se3_inverse", [](py::handle T) { return to_numpy(g::se3_inverse(as_rigid_transform(T, "T"))); },
        "T"_a, "Inverse (4, 4) of a rigid transform, using R^T.");
  m.def("se3_compose",
        [](py::handle A, py::handle B) {
          return to_numpy(Mat4(as_rigid_transform(A, "A") * as_rigid_transform(B, "B")));
        },
        "A"_a, "B"_a, "Composition A @ B of two rigid transforms (4, 4).");
  m.def("se3_adjoint", [](py::handle T) { return to_numpy(g::se3_adjoint(as_rigid_transform(T, "T"))); },
        "T"_a, "Adjoint (6, 6) for [v; w] twists: exp(Ad(T) xi) = T exp(xi) T^-1.");
  m.def("se3_left_jacobian",
        [](py::handle xi) { return to_numpy(g::se3_left_jacobian(as_vec6(xi, "xi"))); }, "xi"_a,
        "SE(3) left Jacobian (6, 6): exp(xi + d) ~= exp(J_l d) exp(xi).");
  m.def("se3_right_jacobian",
        [](py::handle xi) { return to_numpy(g::se3_right_jacobian(as_vec6(xi, "xi"))); },
        "xi"_a, "SE(3) right Jacobian (6, 6): exp(xi + d) ~= exp(xi) exp(J_r d).");
  m.def("se3_left_jacobian_inverse",
        [](py::handle xi) { return to_numpy(g::se3_left_jacobian_inverse(as_vec6(xi, "xi"))); },
        "xi"_a, "Inverse of the SE(3) left Jacobian (6, 6).");
  m.def("se3_right_jacobian_inverse",
        [](py::handle xi) { return to_numpy(g::se3_right_jacobian_inverse(as_vec6(xi, "xi"))); },
        "xi"_a, "Inverse of the SE(3) right Jacobian (6, 6).");
  m.def("twist_between",
        [](py::handle A, py::handle B) {
          return to_numpy(g::twist_between(as_rigid_transform(A, "T_a"), as_rigid_transform(B, "T_b")));
        },
        "T_a"_a, "T_b"_a, "Twist xi (6,) with T_b = exp(xi) T_a (left, world-frame increment).");
  m.def("transform_points",
        [](py::handle T, py::handle X) {
          const Mat4 M = as_rigid_transform(T, "T");
          const DoubleArray pts = as_rows(X, "points", 3);
          DoubleArray out = new_array({pts.shape(0), 3});
          Eigen::Map<Points3> dst(out.mutable_data(), pts.shape(0), 3);
          dst = (points_view(pts) * M.topLeftCorner<3, 3>().transpose()).rowwise() +
                M.topRightCorner<3, 1>().transpose();
          return out;
        },
        "T"_a, "points"_a, "Points (N, 3) mapped by the rigid transform T (4, 4): T @ X.");
  m.def("predict_constant_velocity",
        [](py::handle A, py::handle B) {
          return to_numpy(g::predict_constant_velocity(as_rigid_transform(A, "T_previous"),
                                                       as_rigid_transform(B, "T_last")));
        },
        "T_previous"_a, "T_last"_a, R"doc(Constant-velocity prediction of the next pose.

Parameters
----------
T_previous, T_last : (4, 4) array_like
    The last two poses (rigid transforms, both T_w_c or both T_c_w).

Returns
-------
(4, 4) ndarray
    ``T_last @ inv(T_previous) @ T_last``: the last motion applied once more, as the SLAM
    core predicts the next camera pose.
)doc");
}

void bind_links(py::module_& m) {
  m.def("projector_free", [] { return to_numpy(g::projector_free()); }, "Mechanical link of a free object: Pi = I (6, 6).");
  m.def("projector_planar",
        [](py::handle n) { return to_numpy(g::projector_planar(as_vec3(n, "normal"))); },
        "normal"_a, R"doc(Mechanical link of an object moving on a plane.

Parameters
----------
normal : (3,) array_like
    Plane normal in the world frame (normalised internally).

Returns
-------
(6, 6) ndarray
    Pi = blockdiag(I - n n^T, n n^T): in-plane translation and rotation about n (3 DoF).
)doc");
}

// (N, 3) points from left pixels (N, 2) and one value per pixel (depth or disparity).
template <typename F>
DoubleArray per_pixel(py::handle uv, py::handle values, const char* name, F&& to_point) {
  const DoubleArray px = as_rows(uv, "uv", 2);
  const DoubleArray v = as_double_array(values, name);
  if (v.ndim() != 1 || v.shape(0) != px.shape(0))
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(px.shape(0)) +
                          ",), got " + shape_string(v));
  DoubleArray out = new_array({px.shape(0), 3});
  for (py::ssize_t i = 0; i < px.shape(0); ++i) {
    const Vec3 X = to_point(Vec2(px.data()[2 * i], px.data()[2 * i + 1]), v.data()[i]);
    for (int k = 0; k < 3; ++k) out.mutable_data()[3 * i + k] = X[k];
  }
  return out;
}

void bind_camera(py::module_& m) {
  py::class_<g::StereoCamera>(m, "StereoCamera", "Rectified pinhole stereo pair (KITTI P2/P3).")
      .def_static(
          "from_kitti",
          [](py::handle P2, py::handle P3, int w, int h, double disparity_offset) {
            try {
              return g::StereoCamera::from_kitti(as_mat34(P2, "P_left"), as_mat34(P3, "P_right"),
                                                 w, h, disparity_offset);
            } catch (const std::invalid_argument& e) {
              throw py::value_error(e.what());
            }
          },
          "P_left"_a, "P_right"_a, "width"_a = 0, "height"_a = 0, "disparity_offset"_a = 0.0,
          "Camera pair from the rectified 3x4 projections of the left and right images.\n\n"
          "disparity_offset (px): added to every measured disparity u_left - u_right before it\n"
          "becomes a depth (the right image's principal point is cx + disparity_offset); 0 trusts\n"
          "the calibration. Finite, within +-8 px.")
      .def(
          "with_disparity_offset",
          [](const g::StereoCamera& c, double offset) {
            if (!std::isfinite(offset) || std::abs(offset) > 8.0)
              throw py::value_error("StereoCamera.with_disparity_offset: offset must be finite "
                                    "and within +-8 px");
            g::StereoCamera out = c;
            out.disparity_offset = offset;
            return out;
          },
          "disparity_offset"_a,
          "A copy of this camera whose measured disparities get ``disparity_offset`` px added\n"
          "(see ``from_kitti``).")
      .def_readonly("disparity_offset", &g::StereoCamera::disparity_offset,
                    "px added to measured disparities (right principal point = cx + offset)")
      .def_readonly("fx", &g::StereoCamera::fx)
      .def_readonly("fy", &g::StereoCamera::fy)
      .def_readonly("cx", &g::StereoCamera::cx)
      .def_readonly("cy", &g::StereoCamera::cy)
      .def_readonly("baseline", &g::StereoCamera::baseline, "metres")
      .def_readonly("width", &g::StereoCamera::width)
      .def_readonly("height", &g::StereoCamera::height)
      .def_property_readonly("t_left", [](const g::StereoCamera& c) { return to_numpy(c.t_left); })
      .def_property_readonly("t_right", [](const g::StereoCamera& c) { return to_numpy(c.t_right); })
      .def_property_readonly("K", [](const g::StereoCamera& c) { return to_numpy(c.K()); })
      .def("project",
           [](const g::StereoCamera& c, py::handle X, bool right) {
             const DoubleArray pts = as_rows(X, "points", 3);
             DoubleArray out = new_array({pts.shape(0), 2});
             auto src = points_view(pts);
             const Vec3 offset = right ? c.t_right : c.t_left;
             for (py::ssize_t i = 0; i < pts.shape(0); ++i) {
               const Vec3 Xi = src.row(i).transpose();
               const Vec2 uv = (Xi + offset).z() > 0
                                   ? (right ? c.project_right(Xi) : c.project(Xi))
                                   : Vec2::Constant(std::numeric_limits<double>::quiet_NaN());
               out.mutable_data()[2 * i] = uv.x();
               out.mutable_data()[2 * i + 1] = uv.y();
             }
             return out;
           },
           "points"_a, "right"_a = false,
           "Pixels (N, 2) of points (N, 3) of frame c in the left (or right) image; NaN behind "
           "the camera.")
      .def("backproject",
           [](const g::StereoCamera& c, py::handle uv, py::handle depth) {
             return per_pixel(uv, depth, "depth", [&](const Vec2& px, double z) {
               return c.backproject(px, z);
             });
           },
           "uv"_a, "depth"_a, "Points (N, 3) in frame c at left pixels (N, 2) and depths (N,).")
      .def("triangulate",
           [](const g::StereoCamera& c, py::handle uv, py::handle disparity) {
             return per_pixel(uv, disparity, "disparity", [&](const Vec2& px, double d) {
               return c.triangulate(px, d);
             });
           },
           "uv_left"_a, "disparity"_a,
           "Points (N, 3) in frame c from left pixels and disparities u_l - u_r (NaN where <= 0).")
      .def("__repr__", [](const g::StereoCamera& c) {
        return "StereoCamera(fx=" + std::to_string(c.fx) + ", baseline=" +
               std::to_string(c.baseline) + ", disparity_offset=" +
               std::to_string(c.disparity_offset) + ", size=" + std::to_string(c.width) + "x" +
               std::to_string(c.height) + ")";
      });
}

void bind_plane(py::module_& m) {
  py::class_<g::PlaneFit>(m, "PlaneFit", "Result of fit_plane_ransac.")
      .def_property_readonly("plane", [](const g::PlaneFit& f) { return to_numpy(f.plane); },
                             "(4,) [n, d] with |n| = 1, n.X + d = 0, d >= 0")
      .def_property_readonly("inliers",
                             [](const g::PlaneFit& f) {
                               py::array_t<bool> out(static_cast<py::ssize_t>(f.inliers.size()));
                               for (size_t i = 0; i < f.inliers.size(); ++i)
                                 out.mutable_data()[i] = f.inliers[i] != 0;
                               return out;
                             })
      .def_readonly("num_inliers", &g::PlaneFit::num_inliers)
      .def_readonly("rms", &g::PlaneFit::rms, "metres");
  m.def("fit_plane_ransac",
        [](py::handle points, double thr, int iterations, std::uint64_t seed) {
          const DoubleArray pts = as_rows(points, "points", 3);
          try {
            Points3 P = points_view(pts);
            py::gil_scoped_release release;
            return g::fit_plane_ransac(P, {thr, iterations, seed});
          } catch (const std::invalid_argument& e) {
            throw py::value_error(e.what());
          }
        },
        "points"_a, "inlier_threshold"_a = 0.05, "iterations"_a = 200, "seed"_a = 0,
        R"doc(Plane through 3D points: RANSAC on 3-point samples, then an SVD refit on inliers.

Parameters
----------
points : (N, 3) array_like, N >= 3, finite
inlier_threshold : float
    Point-to-plane distance (m) counted as inlier.
iterations : int
    RANSAC samples.
seed : int
    Seed of the sampler (results are deterministic).

Returns
-------
PlaneFit
)doc");
}

}  // namespace

void bind_geometry(py::module_& m) {
  bind_lie(m);
  bind_links(m);
  bind_camera(m);
  bind_plane(m);
  bind_boxes(m);
}

}  // namespace twistslam::bindings
