// twistslam._core: the C++ core, one submodule per C++ module. Python code uses it through
// the typed facades twistslam.geometry, .features, .optim, .slam and .objects.
#include <pybind11/stl.h>

#include "bindings/numpy_checks.hpp"
#include "core_info/build_info.hpp"

namespace twistslam::bindings {
void bind_geometry(py::module_& m);
void bind_features(py::module_& m);
void bind_optim(py::module_& m);
void bind_slam(py::module_& m);
void bind_slam_options(py::module_& m);
void bind_objects(py::module_& m);
void bind_lidar(py::module_& m);
void bind_perception(py::module_& m);
void bind_detection(py::module_& m);
void bind_registration(py::module_& m);
void bind_io(py::module_& m);
}

PYBIND11_MODULE(_core, m) {
  namespace py = pybind11;
  m.doc() = "twistslam C++ core (bound with pybind11). Use the typed facade in twistslam.*";
  m.def("build_info", &twistslam::build_info,
        "Versions of the libraries (Eigen, Ceres, OpenCV, PCL) the core was built against.");
  py::module_ geometry = m.def_submodule("geometry", "SE(3), links, stereo camera, planes, boxes");
  twistslam::bindings::bind_geometry(geometry);
  py::module_ features = m.def_submodule("features", "ORB extraction and stereo matching");
  twistslam::bindings::bind_features(features);
  py::module_ optim = m.def_submodule("optim", "pose-only optimisation and bundle adjustment");
  twistslam::bindings::bind_optim(optim);
  py::module_ slam = m.def_submodule("slam", "the stereo SLAM system");
  twistslam::bindings::bind_slam(slam);
  twistslam::bindings::bind_slam_options(slam);
  py::module_ objects = m.def_submodule("objects", "object tracks, association, the 3D tracker");
  twistslam::bindings::bind_objects(objects);
  py::module_ lidar = m.def_submodule("lidar", "LiDAR depth of keypoints, KITTI scan correction");
  twistslam::bindings::bind_lidar(lidar);
  py::module_ perception = m.def_submodule("perception", "dense optical flow (OpenCV DIS)");
  twistslam::bindings::bind_perception(perception);
  py::module_ detection = m.def_submodule("detection", "classical LiDAR 3D detection");
  twistslam::bindings::bind_detection(detection);
  py::module_ registration = m.def_submodule("registration", "generalized ICP of object scans");
  twistslam::bindings::bind_registration(registration);
  py::module_ io = m.def_submodule("io", "image files decoded in C++");
  twistslam::bindings::bind_io(io);
}
