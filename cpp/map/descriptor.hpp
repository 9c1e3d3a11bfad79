#pragma once
// 256-bit binary (ORB) descriptor as a plain value type, so the map needs no OpenCV.
#include <array>
#include <cstdint>

#include "features/hamming.hpp"

namespace twistslam::map {

using Descriptor = std::array<std::uint8_t, features::kDescriptorBytes>;

// Number of differing bits (Hamming distance) between two descriptors.
inline int hamming(const Descriptor& a, const Descriptor& b) {
  return features::descriptor_distance(a.data(), b.data());
}

}  // namespace twistslam::map
