#include "tracking/options.hpp"

#include <stdexcept>
#include <string>

#include "options/option_range.hpp"

namespace twistslam::tracking {

void check_options(const SlamOptions& options) {
  SlamOptions copy = options;  // for_each_section visits mutable fields
  for_each_section(copy, [](const char* name, auto& section) {
    options::check_ranges(section, std::string(name) + ".");
  });
  const auto& s = options.stereo;
  if (!(s.min_depth < s.max_depth))
    throw std::invalid_argument("stereo.min_depth (" + options::format_number(s.min_depth) +
                                ") must be below stereo.max_depth (" +
                                options::format_number(s.max_depth) + ")");
  const auto& orb = options.orb;
  if (orb.min_fast_threshold > orb.fast_threshold)
    throw std::invalid_argument("orb.min_fast_threshold (" + std::to_string(orb.min_fast_threshold) +
                                ") must not exceed orb.fast_threshold (" +
                                std::to_string(orb.fast_threshold) + ")");
}

}  // namespace twistslam::tracking
