// The SLAM options' ranges (for_each_option, tracking::check_options): every numeric option
// has a finite range that holds its default, and values out of range are refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "options/option_range.hpp"
#include "tracking/options.hpp"

using namespace twistslam;
using twistslam::tracking::SlamOptions;

namespace {

// The message check_options throws for `options`, or "" when it accepts them.
std::string refusal(const SlamOptions& options) {
  try {
    tracking::check_options(options);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(SlamOptions, EveryOptionHasAFiniteRangeHoldingItsDefault) {
  SlamOptions o;
  int fields = 0;
  tracking::for_each_section(o, [&](const char* section, auto& options) {
    for_each_option(options, [&](const char* key, const auto& value, double lo, double hi) {
      ++fields;
      EXPECT_TRUE(std::isfinite(lo) && std::isfinite(hi) && lo <= hi) << section << "." << key;
      using T = std::decay_t<decltype(value)>;
      if constexpr (std::is_arithmetic_v<T>) {
        EXPECT_GE(static_cast<double>(value), lo) << section << "." << key;
        EXPECT_LE(static_cast<double>(value), hi) << section << "." << key;
      }
    });
  });
  EXPECT_GE(fields, 40);  // orb 6, stereo 10, tracking 11, keyframes 4, local_ba 7, map 3
  EXPECT_EQ(refusal(SlamOptions{}), "");
}

TEST(SlamOptions, OverflowingValuesAreRefusedByName) {
  SlamOptions o;
  o.stereo.row_radius = 1e6f;
  EXPECT_EQ(refusal(o), "stereo.row_radius = 1000000 is out of range [0, 64]");
  o = {};
  o.tracking.search_radius_px = std::numeric_limits<double>::infinity();
  EXPECT_EQ(refusal(o), "tracking.search_radius_px = inf is out of range [0, 2000]");
  o = {};
  o.tracking.chi2_mono = std::nan("");
  EXPECT_EQ(refusal(o), "tracking.chi2_mono = nan is out of range [0, 10000]");
  o = {};
  o.orb.num_features = std::numeric_limits<int>::max();
  EXPECT_EQ(refusal(o), "orb.num_features = 2147483647 is out of range [0, 100000]");
  o = {};
  o.tracking.dynamic_class_ids = {24, -1};
  EXPECT_EQ(refusal(o), "tracking.dynamic_class_ids[1] = -1 is out of range [0, 65535]");
}

TEST(SlamOptions, RulesAcrossFields) {
  SlamOptions o;
  o.stereo.min_depth = 90;
  EXPECT_EQ(refusal(o), "stereo.min_depth (90) must be below stereo.max_depth (80)");
  o = {};
  o.orb.min_fast_threshold = 30;
  EXPECT_EQ(refusal(o), "orb.min_fast_threshold (30) must not exceed orb.fast_threshold (20)");
}

TEST(OptionRange, NumbersAreWrittenShortAndExact) {
  EXPECT_EQ(options::format_number(0.7), "0.7");
  EXPECT_EQ(options::format_number(100000), "100000");
  EXPECT_EQ(options::format_number(3e9), "3000000000");
  EXPECT_EQ(options::format_number(1e30), "1e+30");
  EXPECT_EQ(options::format_number(-0.001), "-0.001");
  EXPECT_EQ(options::format_number(std::numeric_limits<double>::infinity()), "inf");
  const double third = 1.0 / 3.0;
  EXPECT_EQ(std::stod(options::format_number(third)), third);
}
