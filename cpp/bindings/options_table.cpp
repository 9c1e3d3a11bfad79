#include "bindings/options_table.hpp"

#include <cmath>

#include "options/option_range.hpp"

namespace twistslam::bindings {

namespace detail {

namespace {
std::string type_name(const py::handle& v) { return py::str(py::type::of(v).attr("__name__")); }

[[noreturn]] void out_of_range(const py::handle& value, double lo, double hi) {
  // the Python text of the value: exact for integers beyond any C++ type (2**70)
  throw OutOfRange{std::string(py::repr(value)), lo, hi};
}
}  // namespace

long long to_integer(const py::handle& value, double lo, double hi) {
  // bool is an int in Python, a float may have been meant as anything: neither is a count
  if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr()))
    throw py::type_error("expected an integer, got " + type_name(value));
  const py::int_ integer = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  if (!integer) throw py::error_already_set();
  int overflow = 0;
  const long long x = PyLong_AsLongLongAndOverflow(integer.ptr(), &overflow);
  if (overflow != 0 || !(static_cast<double>(x) >= lo && static_cast<double>(x) <= hi))
    out_of_range(integer, lo, hi);
  return x;
}

double to_real(const py::handle& value, double lo, double hi) {
  if (PyBool_Check(value.ptr()) || !PyNumber_Check(value.ptr()) || PyComplex_Check(value.ptr()))
    throw py::type_error("expected a number, got " + type_name(value));
  const double x = PyFloat_AsDouble(value.ptr());  // ints beyond a double raise OverflowError
  if (x == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    out_of_range(value, lo, hi);
  }
  if (!(x >= lo && x <= hi)) out_of_range(value, lo, hi);
  return x;
}

}  // namespace detail

namespace {
// Sets one key; the field's message gets "options: <name>.<key>" in front.
void apply_one(const std::string& name, const std::string& key, const Field& field,
               const py::handle& value) {
  const std::string where = "options: " + (name.empty() ? key : name + "." + key);
  try {
    field.set(value);
  } catch (const detail::OutOfRange& e) {
    throw py::value_error(options::out_of_range_message(where, e.value, e.lo, e.hi));
  } catch (const py::value_error& e) {
    throw py::value_error(where + ": " + e.what());
  } catch (const py::type_error& e) {
    throw py::type_error(where + ": " + e.what());
  } catch (const py::cast_error&) {
    throw py::type_error(where + " has the wrong type (" + std::string(py::str(py::type::of(value))) + ")");
  } catch (const std::invalid_argument& e) {  // a custom field's own conversion
    throw py::value_error(where + ": " + e.what());
  }
}

std::string key_list(const FieldTable& keys) {
  std::string valid;
  for (const auto& k : keys) valid += (valid.empty() ? "" : ", ") + k.first;
  return valid;
}
}  // namespace

void apply_section(const py::dict& section, const std::string& name, const FieldTable& keys) {
  for (const auto& item : section) {
    const std::string key = py::str(item.first);
    const auto it = keys.find(key);
    if (it == keys.end())
      throw py::value_error("options: unknown key '" + (name.empty() ? key : name + "." + key) +
                            "' (valid: " + key_list(keys) + ")");
    apply_one(name, key, it->second, item.second);
  }
}

void apply_keywords(const py::kwargs& kwargs, const std::string& function, const FieldTable& keys) {
  for (const auto& item : kwargs) {
    const std::string key = py::str(item.first);
    const auto it = keys.find(key);
    if (it == keys.end())
      throw py::type_error(function + "() got an unexpected keyword argument '" + key +
                           "' (options: " + key_list(keys) + ")");
    apply_one("", key, it->second, item.second);
  }
}

py::dict dump_section(const FieldTable& keys) {
  py::dict values;
  for (const auto& [key, field] : keys) values[py::str(key)] = field.get();
  return values;
}

py::dict dump_ranges(const FieldTable& keys) {
  py::dict ranges;
  for (const auto& [key, field] : keys)
    if (std::isfinite(field.lo) && std::isfinite(field.hi))
      ranges[py::str(key)] = field.integer ? py::tuple(py::make_tuple(static_cast<long long>(field.lo),
                                                                      static_cast<long long>(field.hi)))
                                           : py::tuple(py::make_tuple(field.lo, field.hi));
  return ranges;
}

}  // namespace twistslam::bindings
