#pragma once
// 256-bit binary (ORB) descriptor as a plain value type, so the map needs no OpenCV.
#include <array>
#include <bitset>
#include <cstdint>
#include <cstring>

namespace twistslam::map {

using Descriptor = std::array<std::uint8_t, 32>;

// Number of differing bits (Hamming distance) between two descriptors.
inline int hamming(const Descriptor& a, const Descriptor& b) {
  int bits = 0;
  for (int i = 0; i < 4; ++i) {
    std::uint64_t x, y;
    std::memcpy(&x, a.data() + 8 * i, 8);
    std::memcpy(&y, b.data() + 8 * i, 8);
    bits += static_cast<int>(std::bitset<64>(x ^ y).count());
  }
  return bits;
}

}  // namespace twistslam::map
