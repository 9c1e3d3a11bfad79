#include "io/png_decoder.hpp"

#include <libdeflate.h>

#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace twistslam::io {
namespace {

constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
constexpr int kChannels = 3;  // colour type 2: R, G, B

std::uint32_t big_endian(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// Ancillary chunks that carry no pixel transform OpenCV would apply (text, time, pixel size);
// any other chunk (gAMA, sBIT, tRNS, PLTE, iCCP, ...) sends the file to OpenCV.
bool is_metadata(const std::string& type) {
  return type == "tEXt" || type == "zTXt" || type == "iTXt" || type == "tIME" || type == "pHYs";
}

struct Header {
  std::uint32_t width = 0, height = 0;
};

// Reads the chunks, checking each CRC: the header, and the IDAT payloads joined in order.
bool read_chunks(const std::uint8_t* bytes, std::size_t size, Header* header,
                 std::vector<std::uint8_t>* compressed) {
  if (size < sizeof(kSignature) || std::memcmp(bytes, kSignature, sizeof(kSignature)) != 0) return false;
  std::size_t at = sizeof(kSignature);
  bool have_header = false, idat_done = false, in_idat = false;
  while (true) {
    if (size - at < 12) return false;  // length, type and CRC of the next chunk; no IEND
    const std::uint32_t length = big_endian(bytes + at);
    if (length > size - at - 12) return false;
    const std::uint8_t* type_and_data = bytes + at + 4;
    const std::string type(reinterpret_cast<const char*>(type_and_data), 4);
    const std::uint32_t crc = big_endian(type_and_data + 4 + length);
    if (libdeflate_crc32(0, type_and_data, 4 + length) != crc) return false;
    const std::uint8_t* data = type_and_data + 4;
    at += 12 + static_cast<std::size_t>(length);
    if (!have_header) {
      // IHDR first: width, height, bit depth 8, colour type 2, deflate, filter 0, no interlace
      if (type != "IHDR" || length != 13) return false;
      header->width = big_endian(data);
      header->height = big_endian(data + 4);
      if (header->width == 0 || header->height == 0 || data[8] != 8 || data[9] != 2 || data[10] != 0 ||
          data[11] != 0 || data[12] != 0)
        return false;
      have_header = true;
      continue;
    }
    if (type == "IDAT") {
      if (idat_done) return false;  // IDAT chunks must be consecutive
      in_idat = true;
      compressed->insert(compressed->end(), data, data + length);
      continue;
    }
    if (in_idat) idat_done = true, in_idat = false;
    if (type == "IEND") return idat_done && length == 0;
    if (!is_metadata(type)) return false;
  }
}

std::uint8_t paeth(int left, int up, int up_left) {
  const int p = left + up - up_left;
  const int dl = std::abs(p - left), du = std::abs(p - up), dul = std::abs(p - up_left);
  if (dl <= du && dl <= dul) return static_cast<std::uint8_t>(left);
  return static_cast<std::uint8_t>(du <= dul ? up : up_left);
}

// PNG filters (spec section 9.2) undone from one filtered row `in` into `out`, `up` being the
// previous unfiltered row (zeros above the first); false for an unknown filter type.
bool unfilter_row(std::uint8_t filter, const std::uint8_t* in, const std::uint8_t* up,
                  std::uint8_t* out, std::size_t n) {
  constexpr std::size_t b = kChannels;  // bytes per pixel: "left" is one pixel back
  switch (filter) {
    case 0:
      std::memcpy(out, in, n);
      return true;
    case 1:
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(in[i] + (i >= b ? out[i - b] : 0));
      return true;
    case 2:
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(in[i] + up[i]);
      return true;
    case 3:
      for (std::size_t i = 0; i < n; ++i)
        out[i] = static_cast<std::uint8_t>(in[i] + (((i >= b ? out[i - b] : 0) + up[i]) >> 1));
      return true;
    case 4:
      for (std::size_t i = 0; i < n; ++i)
        out[i] = static_cast<std::uint8_t>(
            in[i] + (i >= b ? paeth(out[i - b], up[i], up[i - b]) : paeth(0, up[i], 0)));
      return true;
    default:
      return false;
  }
}

}  // namespace

bool decode_plain_rgb8_png(const std::uint8_t* bytes, std::size_t size, cv::Mat* rgb) {
  Header header;
  std::vector<std::uint8_t> compressed;
  if (!read_chunks(bytes, size, &header, &compressed)) return false;
  // one filter byte and W RGB pixels per row; refuse sizes cv::Mat cannot hold
  constexpr std::uint64_t kMaxSide = std::numeric_limits<int>::max() / kChannels;
  if (header.width > kMaxSide || header.height > kMaxSide) return false;
  const std::size_t row_bytes = static_cast<std::size_t>(header.width) * kChannels;
  const std::uint64_t raw_size = static_cast<std::uint64_t>(header.height) * (row_bytes + 1);
  // a deflate stream expands at most ~1032 times: a larger declared image is a lie
  if (raw_size > static_cast<std::uint64_t>(compressed.size()) * 1032 + 64) return false;
  std::vector<std::uint8_t> raw(static_cast<std::size_t>(raw_size));
  std::unique_ptr<libdeflate_decompressor, decltype(&libdeflate_free_decompressor)> inflater(
      libdeflate_alloc_decompressor(), &libdeflate_free_decompressor);
  if (!inflater) return false;
  std::size_t produced = 0;
  // LIBDEFLATE_SUCCESS also means the Adler-32 checksum matched; a stream longer or shorter
  // than the image is declined (libpng would warn about it, OpenCV decides)
  if (libdeflate_zlib_decompress(inflater.get(), compressed.data(), compressed.size(), raw.data(),
                                 raw.size(), &produced) != LIBDEFLATE_SUCCESS ||
      produced != raw.size())
    return false;
  cv::Mat out(static_cast<int>(header.height), static_cast<int>(header.width), CV_8UC3);
  const std::vector<std::uint8_t> zeros(row_bytes, 0);
  for (int r = 0; r < out.rows; ++r) {
    const std::uint8_t* in = raw.data() + static_cast<std::size_t>(r) * (row_bytes + 1);
    const std::uint8_t* up = r > 0 ? out.ptr<std::uint8_t>(r - 1) : zeros.data();
    if (!unfilter_row(in[0], in + 1, up, out.ptr<std::uint8_t>(r), row_bytes)) return false;
  }
  *rgb = out;
  return true;
}

}  // namespace twistslam::io
