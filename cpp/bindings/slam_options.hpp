#pragma once
#include <pybind11/pybind11.h>

#include "tracking/options.hpp"

namespace twistslam::bindings {
namespace py = pybind11;
// Nested dict {section: {key: value}} -> options; ValueError for unknown sections or keys.
tracking::SlamOptions parse_slam_options(const py::dict& options);
// The C++ defaults in the same nested layout.
py::dict default_slam_options();
}  // namespace twistslam::bindings
