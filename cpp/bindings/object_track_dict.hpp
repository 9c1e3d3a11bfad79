#pragma once
// An objects::ObjectTrack as a dict of numpy arrays: the one conversion used by the tracker
// from detections (objects_bindings.cpp) and the visual object tracking (slam_bindings.cpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "objects/object_track.hpp"

namespace twistslam::bindings {
namespace py = pybind11;

// id, class_id, state, link, size, hits, confirmed_frame, mean_score, confidence, backcast,
// canonical, and per row (K = backcast frames, then frames): frames, T_w_o, T_w_o_detected,
// twist, detected, reported, score, range, frame_confidence, detected_size, detection_index,
// registered.
py::dict track_to_dict(const objects::ObjectTrack& t);

}  // namespace twistslam::bindings
