#include "bindings/options_table.hpp"

namespace twistslam::bindings {

void apply_section(const py::dict& section, const std::string& name, const FieldTable& keys) {
  for (const auto& item : section) {
    const std::string key = py::str(item.first);
    const auto it = keys.find(key);
    if (it == keys.end()) {
      std::string valid;
      for (const auto& k : keys) valid += (valid.empty() ? "" : ", ") + k.first;
      throw py::value_error("options: unknown key '" + name + "." + key + "' (valid: " + valid + ")");
    }
    try {
      it->second.set(item.second);
    } catch (const py::cast_error&) {
      throw py::type_error("options: '" + name + "." + key + "' has the wrong type (" +
                           std::string(py::str(py::type::of(item.second))) + ")");
    }
  }
}

py::dict dump_section(const FieldTable& keys) {
  py::dict values;
  for (const auto& [key, field] : keys) values[py::str(key)] = field.get();
  return values;
}

}  // namespace twistslam::bindings
