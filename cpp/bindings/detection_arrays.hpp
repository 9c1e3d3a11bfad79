#pragma once
// numpy arrays of one frame's 3D detections -> objects::Detection, shared by the detections
// tracker (objects_bindings.cpp) and the SLAM's LiDAR fusion (slam_bindings.cpp).
#include <vector>

#include "bindings/numpy_checks.hpp"
#include "objects/detection.hpp"

namespace twistslam::bindings {

// boxes (N, 7) [cx, cy, cz, l, w, h, ry], scores (N,), class_ids (N,) int, planar (N,) bool
// or None (all true), open_ends (N,) int in {-1, 0, 1} or None (all 0), point_extents (N,) bool
// or None (all false), headings_known (N,) bool or None (true where not a point extent).
// ValueError naming the argument for a wrong shape or value.
std::vector<objects::Detection> detections_from_arrays(const py::handle& boxes,
                                                       const py::handle& scores,
                                                       const py::handle& class_ids,
                                                       const py::handle& planar,
                                                       const py::handle& open_ends = py::none(),
                                                       const py::handle& point_extents = py::none(),
                                                       const py::handle& headings_known = py::none());

}  // namespace twistslam::bindings
