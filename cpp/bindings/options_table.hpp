#pragma once
// Python values -> C++ option structs through a table of typed fields: the one conversion
// path of every option dict or **options keyword set that enters the core (SLAM, features,
// optim, objects). Every key must be known (typos are errors, not silently ignored defaults);
// missing keys keep the C++ default. A value of the wrong type is a TypeError, one outside
// the field's range (or too large for its C++ type) a ValueError naming "section.key"; no
// value is narrowed before it is checked. The same table serves parsing and the dump of the
// defaults and ranges.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

namespace twistslam::bindings {
namespace py = pybind11;

// Reads and writes one option field. `set` throws py::type_error, py::value_error or
// detail::OutOfRange without the field's name (apply_section adds "section.key").
struct Field {
  std::function<void(const py::handle&)> set;
  std::function<py::object()> get;
  double lo = -std::numeric_limits<double>::infinity();  // valid range, for the dump
  double hi = std::numeric_limits<double>::infinity();
  bool integer = false;  // an integer field (or list of them): its range dumps as ints
};
using FieldTable = std::map<std::string, Field>;

namespace detail {
// A value outside its field's range, as Python wrote it; apply_section names the field.
struct OutOfRange {
  std::string value;
  double lo, hi;
};
// Integer value of a Python int (numpy integers too; not bool, not float), range-checked as
// such: values beyond long long are reported, not wrapped. Throws as Field::set does.
long long to_integer(const py::handle& value, double lo, double hi);
// Float value of a Python number, range-checked before any narrowing to float.
double to_real(const py::handle& value, double lo, double hi);
// Value of one element of a list option.
template <typename T>
T to_value(const py::handle& value, double lo, double hi) {
  if constexpr (std::is_same_v<T, bool>) {
    return value.cast<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    return static_cast<T>(to_integer(value, lo, hi));
  } else if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(to_real(value, lo, hi));
  } else {
    return value.cast<T>();
  }
}
template <typename T>
struct Limits {  // default range of a field given without one: what its C++ type holds (bools: none)
  static constexpr bool kNumber = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;
  static double lo() {
    if constexpr (kNumber && std::is_integral_v<T>) return static_cast<double>(std::numeric_limits<T>::lowest());
    return -std::numeric_limits<double>::infinity();
  }
  static double hi() {
    if constexpr (kNumber && std::is_integral_v<T>) return static_cast<double>(std::numeric_limits<T>::max());
    return std::numeric_limits<double>::infinity();
  }
};
}  // namespace detail

// Field of a number, bool, string or list of those in [lo, hi] (each element of a list).
template <typename T>
Field set(T* field, double lo, double hi) {
  Field f;
  f.lo = lo;
  f.hi = hi;
  f.integer = (std::is_integral_v<T> && !std::is_same_v<T, bool>) || std::is_same_v<T, std::vector<int>>;
  f.get = [field] { return py::cast(*field); };
  f.set = [field, lo, hi](const py::handle& v) {
    if constexpr (std::is_same_v<T, std::vector<int>> || std::is_same_v<T, std::vector<double>>) {
      if (!py::isinstance<py::list>(v) && !py::isinstance<py::tuple>(v))
        throw py::type_error("expected a list, got " + std::string(py::str(py::type::of(v))));
      T values;
      for (const py::handle& item : v)
        values.push_back(detail::to_value<typename T::value_type>(item, lo, hi));
      *field = std::move(values);
    } else {
      *field = detail::to_value<T>(v, lo, hi);
    }
  };
  return f;
}

// Field in the full range of its C++ type (NaN is still refused for floats).
template <typename T>
Field set(T* field) {
  using Element = std::conditional_t<std::is_same_v<T, std::vector<int>>, int, T>;
  return set(field, detail::Limits<Element>::lo(), detail::Limits<Element>::hi());
}

// Field with its own conversion (e.g. an enum given by name).
inline Field custom(std::function<void(const py::handle&)> setter, std::function<py::object()> getter) {
  return {std::move(setter), std::move(getter)};
}

// The fields of an options struct that has a for_each_option(options, visit) list (see
// options/option_range.hpp), each with its range. `options` must outlive the table.
template <typename Options>
FieldTable field_table(Options& options) {
  FieldTable table;
  for_each_option(options, [&table](const char* key, auto& field, double lo, double hi) {
    table[key] = set(&field, lo, hi);
  });
  return table;
}

// Applies `section` (a dict) to the fields of `keys`; ValueError names an unknown key and
// lists the valid ones, TypeError a value of the wrong type, ValueError one out of range.
// Messages read "options: <name>.<key> ..." (`name` empty: "options: <key> ...").
void apply_section(const py::dict& section, const std::string& name, const FieldTable& keys);

// Applies keyword arguments of function `function`: an unknown name is a TypeError as Python
// gives it ("f() got an unexpected keyword argument 'x'"), values as in apply_section.
void apply_keywords(const py::kwargs& kwargs, const std::string& function, const FieldTable& keys);

// {key: value} of every field.
py::dict dump_section(const FieldTable& keys);

// {key: (lo, hi)} of every field with a finite range.
py::dict dump_ranges(const FieldTable& keys);

}  // namespace twistslam::bindings
