// Nested Python dict -> SlamOptions. Every key must be known (typos are errors, not silently
// ignored defaults); missing keys keep the C++ default.
#include "bindings/slam_options.hpp"

#include "bindings/options_table.hpp"

namespace twistslam::bindings {

namespace {
// Every option field of `o`, by section and key.
std::map<std::string, std::map<std::string, Field>> option_table(tracking::SlamOptions& o) {
  return {
      {"orb",
       {{"num_features", set(&o.orb.num_features)}, {"scale_factor", set(&o.orb.scale_factor)},
        {"num_levels", set(&o.orb.num_levels)}, {"fast_threshold", set(&o.orb.fast_threshold)},
        {"min_fast_threshold", set(&o.orb.min_fast_threshold)}, {"cell_size", set(&o.orb.cell_size)}}},
      {"stereo",
       {{"max_hamming", set(&o.stereo.max_hamming)}, {"patch_radius", set(&o.stereo.patch_radius)},
        {"refine_range", set(&o.stereo.refine_range)}, {"min_depth", set(&o.stereo.min_depth)},
        {"max_depth", set(&o.stereo.max_depth)}, {"row_radius", set(&o.stereo.row_radius)},
        {"octave_tolerance", set(&o.stereo.octave_tolerance)},
        {"patch_half_height", set(&o.stereo.patch_half_height)},
        {"outlier_factor", set(&o.stereo.outlier_factor)},
        {"right_features_factor", set(&o.stereo.right_features_factor)}}},
      {"tracking",
       {{"min_inliers", set(&o.tracking.min_inliers)}, {"min_init_points", set(&o.tracking.min_init_points)},
        {"search_radius_px", set(&o.tracking.search_radius_px)},
        {"local_map_search_radius_px", set(&o.tracking.local_map_search_radius_px)},
        {"max_hamming", set(&o.tracking.max_hamming)}, {"ratio_test", set(&o.tracking.ratio_test)},
        {"pose_rounds", set(&o.tracking.pose_rounds)}, {"chi2_stereo", set(&o.tracking.chi2_stereo)},
        {"chi2_mono", set(&o.tracking.chi2_mono)},
        {"close_depth_baselines", set(&o.tracking.close_depth_baselines)},
        {"dynamic_class_ids", set(&o.tracking.dynamic_class_ids)}}},
      {"keyframes",
       {{"max_frames_between", set(&o.keyframes.max_frames_between)},
        {"min_tracked_ratio", set(&o.keyframes.min_tracked_ratio)},
        {"min_close_tracked", set(&o.keyframes.min_close_tracked)},
        {"min_new_close", set(&o.keyframes.min_new_close)}}},
      {"local_ba",
       {{"window", set(&o.local_ba.window)}, {"max_fixed", set(&o.local_ba.max_fixed)},
        {"iterations_first", set(&o.local_ba.iterations_first)},
        {"iterations_second", set(&o.local_ba.iterations_second)},
        {"huber_stereo", set(&o.local_ba.huber_stereo)}, {"huber_mono", set(&o.local_ba.huber_mono)},
        {"num_threads", set(&o.local_ba.num_threads)}}},
      {"map",
       {{"min_found_ratio", set(&o.map.min_found_ratio)},
        {"cull_after_keyframes", set(&o.map.cull_after_keyframes)}, {"max_points", set(&o.map.max_points)}}},
  };
}
}  // namespace

py::dict default_slam_options() {
  tracking::SlamOptions o;
  py::dict out;
  for (const auto& [section, fields] : option_table(o)) {
    out[py::str(section)] = dump_section(fields);
  }
  return out;
}

tracking::SlamOptions parse_slam_options(const py::dict& options) {
  tracking::SlamOptions o;
  const auto sections = option_table(o);
  for (const auto& item : options) {
    const std::string name = py::str(item.first);
    const auto it = sections.find(name);
    if (it == sections.end()) {
      std::string valid;
      for (const auto& s : sections) valid += (valid.empty() ? "" : ", ") + s.first;
      throw py::value_error("options: unknown section '" + name + "' (valid: " + valid + ")");
    }
    if (!py::isinstance<py::dict>(item.second))
      throw py::type_error("options: section '" + name + "' must be a dict");
    apply_section(item.second.cast<py::dict>(), name, it->second);
  }
  return o;
}

}  // namespace twistslam::bindings
