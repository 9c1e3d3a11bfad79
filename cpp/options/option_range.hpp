#pragma once
// Range checks shared by every options struct of the core. Each struct lists its fields once,
// in a `for_each_option(options, visit)` function beside it, as
//   visit("key", options.field, lo, hi);
// (inclusive bounds in the field's unit). The same list serves the C++ checks
// (`RangeCheck`, below) and the Python bindings (bindings/options_table.hpp), so an option has
// one range whether the core is called from twistslam.Config or directly.
//
// Every numeric option has an upper bound too: a huge value is never meaningful, and an
// unbounded float that reaches a float-to-int conversion (a pixel radius, a disparity) is
// undefined behaviour.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace twistslam::options {

// Shortest decimal text that reads back as `value` ("0.7", "1e+30", "3000000000", "nan").
// Integral values below 1e16 are written without exponent ("100000", not "1e+05").
inline std::string format_number(double value) {
  char text[32];
  if (value == std::floor(value) && std::abs(value) < 1e16) {  // integral: no exponent
    std::snprintf(text, sizeof text, "%.0f", value);
    return text;
  }
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (!std::isfinite(value) || std::strtod(text, nullptr) == value) break;
  }
  return text;
}

// "name = value is out of range [lo, hi]"; the value is given as text so that callers can
// report it exactly as the user wrote it (e.g. an integer too large for any C++ type).
inline std::string out_of_range_message(const std::string& name, const std::string& value,
                                        double lo, double hi) {
  return name + " = " + value + " is out of range [" + format_number(lo) + ", " +
         format_number(hi) + "]";
}

// Throws std::invalid_argument naming `name` unless lo <= value <= hi (NaN never passes).
inline void check_range(const std::string& name, double value, double lo, double hi) {
  if (!(value >= lo && value <= hi))
    throw std::invalid_argument(out_of_range_message(name, format_number(value), lo, hi));
}

// Visitor of for_each_option that checks every field; `prefix` names the section ("orb.").
struct RangeCheck {
  std::string prefix;

  template <typename T>
  void operator()(const char* key, const T& value, double lo, double hi) const {
    check_range(prefix + key, static_cast<double>(value), lo, hi);
  }
  template <typename T>
  void operator()(const char* key, const std::vector<T>& values, double lo, double hi) const {
    for (std::size_t i = 0; i < values.size(); ++i)
      check_range(prefix + key + "[" + std::to_string(i) + "]", static_cast<double>(values[i]),
                  lo, hi);
  }
};

// Checks every field of `options` (a copy: for_each_option visits mutable fields).
template <typename Options>
void check_ranges(Options options, const std::string& prefix) {
  for_each_option(options, RangeCheck{prefix});
}

}  // namespace twistslam::options
