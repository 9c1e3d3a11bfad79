#pragma once
// Nested Python dicts -> C++ option structs through a table of typed fields: every key must be
// known (typos are errors, not silently ignored defaults); missing keys keep the C++ default.
// The same table serves parsing and the dump of the defaults.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <functional>
#include <map>
#include <string>

namespace twistslam::bindings {
namespace py = pybind11;

// Reads and writes one option field.
struct Field {
  std::function<void(const py::handle&)> set;
  std::function<py::object()> get;
};
using FieldTable = std::map<std::string, Field>;

template <typename T>
Field set(T* field) {
  return {[field](const py::handle& v) { *field = v.cast<T>(); }, [field] { return py::cast(*field); }};
}

// Field with its own conversion (e.g. an enum given by name).
inline Field custom(std::function<void(const py::handle&)> setter, std::function<py::object()> getter) {
  return {std::move(setter), std::move(getter)};
}

// Applies `section` (a dict) to the fields of `keys`; ValueError names an unknown key and
// lists the valid ones, TypeError a value of the wrong type. `name` prefixes the messages.
void apply_section(const py::dict& section, const std::string& name, const FieldTable& keys);

// {key: value} of every field.
py::dict dump_section(const FieldTable& keys);

}  // namespace twistslam::bindings
