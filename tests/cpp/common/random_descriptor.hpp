#pragma once
// A uniformly random 256-bit ORB descriptor: two of them differ in ~128 bits, far beyond any
// matching threshold, so test scenes get unambiguous descriptor matches.
#include <cstdint>
#include <random>

#include "map/descriptor.hpp"

namespace twistslam::test_scenes {

inline map::Descriptor random_descriptor(std::mt19937& rng) {
  map::Descriptor d;
  std::uniform_int_distribution<int> byte(0, 255);
  for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng));
  return d;
}

}  // namespace twistslam::test_scenes
