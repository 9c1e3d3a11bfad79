#pragma once
// Hamming distance of two 256-bit ORB descriptors: the one implementation, used by the
// extractor's stereo matching (features) and the map's projection matching (map::hamming).
// Free of OpenCV so that the map needs none.
#include <cstdint>
#include <cstring>

namespace twistslam::features {

inline constexpr int kDescriptorBytes = 32;

// Number of differing bits of two 32-byte descriptors (0..256).
inline int descriptor_distance(const std::uint8_t* a, const std::uint8_t* b) {
  int d = 0;
  for (int k = 0; k < kDescriptorBytes; k += 8) {
    std::uint64_t x, y;  // memcpy: descriptors need not be 8-byte aligned
    std::memcpy(&x, a + k, 8);
    std::memcpy(&y, b + k, 8);
    d += __builtin_popcountll(x ^ y);
  }
  return d;
}

}  // namespace twistslam::features
