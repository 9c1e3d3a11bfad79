#include "bindings/object_track_dict.hpp"

#include <vector>

#include "bindings/numpy_checks.hpp"

namespace twistslam::bindings {
using namespace pybind11::literals;
namespace o = twistslam::objects;

// One track as numpy arrays (K = its backcast frames, then its frames).
py::dict track_to_dict(const o::ObjectTrack& t) {
  std::vector<const o::TrackFrame*> rows;
  rows.reserve(t.backcast.size() + t.frames.size());
  for (const auto& f : t.backcast) rows.push_back(&f);
  for (const auto& f : t.frames) rows.push_back(&f);
  const auto K = static_cast<py::ssize_t>(rows.size());
  DoubleArray poses = new_array({K, 4, 4}), detected_poses = new_array({K, 4, 4});
  // the poses before the final smoothing (a backcast row re-placed by it: its own online pose)
  DoubleArray online_poses = new_array({K, 4, 4});
  const bool smoothed = t.T_w_o_online.size() == t.frames.size() && !t.frames.empty();
  const auto B = static_cast<py::ssize_t>(t.backcast.size());
  const bool backcast_replaced = static_cast<py::ssize_t>(t.backcast_online.size()) == B;
  DoubleArray twists = new_array({K, 6}), scores = new_array({K}), sizes = new_array({K, 3});
  DoubleArray ranges = new_array({K}), confidences = new_array({K});
  py::array_t<std::int64_t> frames(K), det_index(K);
  py::array_t<bool> detected(K), reported(K), registered(K);
  for (py::ssize_t k = 0; k < K; ++k) {
    const auto& f = *rows[k];
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        poses.mutable_data()[k * 16 + r * 4 + c] = f.T_w_o(r, c);
        detected_poses.mutable_data()[k * 16 + r * 4 + c] = f.T_w_o_detected(r, c);
        online_poses.mutable_data()[k * 16 + r * 4 + c] =
            smoothed && k >= B                ? t.T_w_o_online[k - B](r, c)
            : smoothed && backcast_replaced ? t.backcast_online[k](r, c)
                                              : f.T_w_o(r, c);
      }
    for (int i = 0; i < 6; ++i) twists.mutable_data()[k * 6 + i] = f.xi[i];
    for (int i = 0; i < 3; ++i) sizes.mutable_data()[k * 3 + i] = f.detected_size[i];
    scores.mutable_data()[k] = f.score;
    ranges.mutable_data()[k] = f.range;
    confidences.mutable_data()[k] = f.confidence;
    frames.mutable_data()[k] = f.frame;
    det_index.mutable_data()[k] = f.detection_index;
    detected.mutable_data()[k] = f.detected;
    reported.mutable_data()[k] = f.reported;
    registered.mutable_data()[k] = f.registered;
  }
  return py::dict("id"_a = t.id, "class_id"_a = t.class_id, "state"_a = o::to_string(t.state),
                  "link"_a = t.link == geometry::LinkType::kPlanar ? "planar" : "free",
                  "size"_a = to_numpy(t.size), "hits"_a = t.hits, "confirmed_frame"_a = t.confirmed_frame,
                  "mean_score"_a = t.mean_score(), "confidence"_a = t.confidence(),
                  "backcast"_a = static_cast<int>(t.backcast.size()), "frames"_a = frames,
                  "T_w_o"_a = poses, "T_w_o_detected"_a = detected_poses, "twist"_a = twists,
                  "detected"_a = detected, "reported"_a = reported, "score"_a = scores,
                  "range"_a = ranges, "frame_confidence"_a = confidences,
                  "detected_size"_a = sizes, "detection_index"_a = det_index,
                  "canonical"_a = t.canonical, "registered"_a = registered,
                  "T_w_o_online"_a = online_poses, "smoothed"_a = smoothed);
}

}  // namespace twistslam::bindings
