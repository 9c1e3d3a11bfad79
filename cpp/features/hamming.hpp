#pragma once
// Hamming distance of two 256-bit ORB descriptors: the one implementation, used by the
// extractor's stereo matching (features) and the map's projection matching (map::hamming).
// Free of OpenCV so that the map needs none.
#include <cstdint>
#include <cstring>

namespace twistslam::features {

inline constexpr int kDescriptorBytes = 32;

// Set bits of a 64-bit word by the parallel (SWAR) sum: the build targets baseline x86-64,
// where __builtin_popcountll is a call to libgcc's table-driven __popcountdi2 (0.4 % of the
// whole DIS loop's CPU in perf, one call per word); these dozen inline operations give the
// same count and vectorise over a descriptor's four words.
inline int popcount64(std::uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
}

// Number of differing bits of two 32-byte descriptors (0..256).
inline int descriptor_distance(const std::uint8_t* a, const std::uint8_t* b) {
  int d = 0;
  for (int k = 0; k < kDescriptorBytes; k += 8) {
    std::uint64_t x, y;  // memcpy: descriptors need not be 8-byte aligned
    std::memcpy(&x, a + k, 8);
    std::memcpy(&y, b + k, 8);
    d += popcount64(x ^ y);
  }
  return d;
}

}  // namespace twistslam::features
