// Nested Python dict -> SlamOptions through the field tables of options_table.hpp, built from
// each section's for_each_option list (names and ranges defined once, in C++), then the
// core's own tracking::check_options (ranges again, and the checks across fields).
#include "bindings/slam_options.hpp"

#include <stdexcept>

#include "bindings/options_table.hpp"

namespace twistslam::bindings {
using namespace pybind11::literals;

namespace {
// Every option field of `o`, by section and key.
std::map<std::string, FieldTable> option_table(tracking::SlamOptions& o) {
  std::map<std::string, FieldTable> sections;
  tracking::for_each_section(o, [&sections](const char* name, auto& section) {
    sections[name] = field_table(section);
  });
  return sections;
}

std::string section_list(const std::map<std::string, FieldTable>& sections) {
  std::string valid;
  for (const auto& s : sections) valid += (valid.empty() ? "" : ", ") + s.first;
  return valid;
}
}  // namespace

py::dict default_slam_options() {
  tracking::SlamOptions o;
  py::dict out;
  for (const auto& [section, fields] : option_table(o)) out[py::str(section)] = dump_section(fields);
  return out;
}

py::dict slam_option_ranges() {
  tracking::SlamOptions o;
  py::dict out;
  for (const auto& [section, fields] : option_table(o)) out[py::str(section)] = dump_ranges(fields);
  return out;
}

tracking::SlamOptions parse_slam_options(const py::dict& options) {
  tracking::SlamOptions o;
  const auto sections = option_table(o);
  for (const auto& item : options) {
    const std::string name = py::str(item.first);
    const auto it = sections.find(name);
    if (it == sections.end())
      throw py::value_error("options: unknown section '" + name + "' (valid: " +
                            section_list(sections) + ")");
    if (!py::isinstance<py::dict>(item.second))
      throw py::type_error("options: section '" + name + "' must be a dict");
    apply_section(item.second.cast<py::dict>(), name, it->second);
  }
  try {
    tracking::check_options(o);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string("options: ") + e.what());
  }
  return o;
}

void bind_slam_options(py::module_& m) {
  m.def("check_options", [](const py::dict& options) { parse_slam_options(options); },
        "options"_a, R"doc(Check SLAM options exactly as ``System`` reads them.

Parameters
----------
options : dict
    Nested ``{section: {key: value}}``, as ``twistslam.Config.to_options()`` gives it;
    missing keys keep their defaults.

Raises
------
ValueError
    An unknown section or key, a value outside its range (see ``option_ranges``) or too large
    for the core, ``stereo.min_depth >= stereo.max_depth``, or
    ``orb.min_fast_threshold > orb.fast_threshold``; the message names the option.
TypeError
    A value of the wrong type (e.g. a float for an integer option).
)doc");
  m.def("option_ranges", &slam_option_ranges,
        "Valid range ``(lo, hi)`` (inclusive, the option's unit) of every numeric option, nested\n"
        "``{section: {key: (lo, hi)}}``; list options give the range of each element.");
}

}  // namespace twistslam::bindings
