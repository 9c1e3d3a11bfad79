// twistslam._core: the C++ core. One submodule per C++ module (geometry now; features,
// tracking, lidar, shape and optim as they land).
#include <pybind11/stl.h>

#include "bindings/numpy_checks.hpp"
#include "core_info/build_info.hpp"

namespace twistslam::bindings {
void bind_geometry(py::module_& m);
}

PYBIND11_MODULE(_core, m) {
  namespace py = pybind11;
  m.doc() = "twistslam C++ core (bound with pybind11). Use the typed facade in twistslam.*";
  m.def("build_info", &twistslam::build_info,
        "Versions of the libraries (Eigen, Ceres, OpenCV, PCL) the core was built against.");
  py::module_ geometry = m.def_submodule("geometry", "SE(3), links, stereo camera, planes, boxes");
  twistslam::bindings::bind_geometry(geometry);
}
