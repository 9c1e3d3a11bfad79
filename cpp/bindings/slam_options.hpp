#pragma once
#include <pybind11/pybind11.h>

#include "tracking/options.hpp"

namespace twistslam::bindings {
namespace py = pybind11;
// Nested dict {section: {key: value}} -> options; ValueError for unknown sections or keys and
// for values out of range (naming "section.key"), TypeError for values of the wrong type.
tracking::SlamOptions parse_slam_options(const py::dict& options);
// The C++ defaults in the same nested layout.
py::dict default_slam_options();
// {section: {key: (lo, hi)}} of every numeric option.
py::dict slam_option_ranges();
// Binds check_options and option_ranges into the `slam` submodule.
void bind_slam_options(py::module_& m);
}  // namespace twistslam::bindings
