// The fast PNG path (io/png_decoder.hpp): PNGs assembled here byte by byte, with every row
// filter of the specification, decode to the pixels they were made of and to what libpng
// (OpenCV) decodes; any file outside the plain case is declined and read_png_rgb8 still reads
// it through OpenCV; a damaged stream is declined, never decoded wrong.
#include <gtest/gtest.h>

#include <libdeflate.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "io/png_decoder.hpp"
#include "io/png_file.hpp"

using twistslam::io::decode_plain_rgb8_png;
using twistslam::io::read_png_rgb8;

namespace {

using Bytes = std::vector<std::uint8_t>;

void put_u32(Bytes* out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out->push_back(static_cast<std::uint8_t>(v >> shift));
}

void put_chunk(Bytes* out, const std::string& type, const Bytes& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  Bytes body(type.begin(), type.end());
  body.insert(body.end(), data.begin(), data.end());
  out->insert(out->end(), body.begin(), body.end());
  put_u32(out, libdeflate_crc32(0, body.data(), body.size()));
}

int predictor(int filter, int left, int up, int up_left) {
  switch (filter) {
    case 1: return left;
    case 2: return up;
    case 3: return (left + up) / 2;
    case 4: {  // Paeth, spec section 9.4
      const int p = left + up - up_left;
      const int a = std::abs(p - left), b = std::abs(p - up), c = std::abs(p - up_left);
      return a <= b && a <= c ? left : (b <= c ? up : up_left);
    }
    default: return 0;
  }
}

// Row r of the RGB image filtered with filter (r + first_filter) % 5, the filter byte first.
Bytes filtered_rows(const cv::Mat& rgb, int first_filter) {
  Bytes raw;
  const int n = rgb.cols * 3;
  for (int r = 0; r < rgb.rows; ++r) {
    const int filter = (r + first_filter) % 5;
    raw.push_back(static_cast<std::uint8_t>(filter));
    const std::uint8_t* row = rgb.ptr<std::uint8_t>(r);
    const std::uint8_t* above = r > 0 ? rgb.ptr<std::uint8_t>(r - 1) : nullptr;
    for (int i = 0; i < n; ++i) {
      const int left = i >= 3 ? row[i - 3] : 0, up = above ? above[i] : 0;
      const int up_left = above && i >= 3 ? above[i - 3] : 0;
      raw.push_back(static_cast<std::uint8_t>(row[i] - predictor(filter, left, up, up_left)));
    }
  }
  return raw;
}

Bytes zlib_stream(const Bytes& raw) {
  libdeflate_compressor* c = libdeflate_alloc_compressor(6);
  Bytes out(libdeflate_zlib_compress_bound(c, raw.size()));
  out.resize(libdeflate_zlib_compress(c, raw.data(), raw.size(), out.data(), out.size()));
  libdeflate_free_compressor(c);
  return out;
}

struct PngParts {
  int colour_type = 2, interlace = 0;
  std::vector<std::pair<std::string, Bytes>> before_data;  // chunks between IHDR and IDAT
  int idat_chunks = 2;
  std::vector<std::pair<std::string, Bytes>> between_data;  // chunks after the first IDAT
};

// A PNG file of the RGB image, its stream split over parts.idat_chunks IDAT chunks.
Bytes png_file(const cv::Mat& rgb, const Bytes& stream, const PngParts& parts = {}) {
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Bytes header;
  put_u32(&header, static_cast<std::uint32_t>(rgb.cols));
  put_u32(&header, static_cast<std::uint32_t>(rgb.rows));
  header.insert(header.end(), {8, static_cast<std::uint8_t>(parts.colour_type), 0, 0,
                               static_cast<std::uint8_t>(parts.interlace)});
  put_chunk(&png, "IHDR", header);
  for (const auto& [type, data] : parts.before_data) put_chunk(&png, type, data);
  const size_t step = stream.size() / parts.idat_chunks + 1;
  for (size_t at = 0; at < stream.size(); at += step) {
    put_chunk(&png, "IDAT", Bytes(stream.begin() + at, stream.begin() + std::min(stream.size(), at + step)));
    if (at == 0)
      for (const auto& [type, data] : parts.between_data) put_chunk(&png, type, data);
  }
  put_chunk(&png, "IEND", {});
  return png;
}

cv::Mat random_rgb(int rows, int cols, int seed) {
  cv::Mat rgb(rows, cols, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(rgb, cv::RNG::UNIFORM, 0, 256);
  // smooth half of it, so that the predictors' sums exceed 255 and wrap as well as not
  if (cols >= 2) {
    cv::Mat half = rgb(cv::Rect(0, 0, cols / 2, rows));
    cv::GaussianBlur(half, half, {5, 5}, 2.0);
  }
  return rgb;
}

cv::Mat opencv_rgb(const Bytes& png) {
  cv::Mat bgr = cv::imdecode(png, cv::IMREAD_COLOR), rgb;
  if (bgr.empty()) return bgr;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

std::string write_temp(const Bytes& png, const std::string& name) {
  const std::string path = testing::TempDir() + "twistslam_png_decoder_" + name;
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()),
                                              static_cast<std::streamsize>(png.size()));
  return path;
}

}  // namespace

TEST(PngDecoder, EveryRowFilterDecodesToItsPixelsAndToLibpngs) {
  for (const auto& [rows, cols] : std::vector<std::pair<int, int>>{{23, 37}, {1, 1}, {5, 2}, {64, 129}})
    for (int first_filter = 0; first_filter < 5; ++first_filter) {
      const cv::Mat rgb = random_rgb(rows, cols, rows * 31 + first_filter);
      PngParts parts;
      parts.before_data = {{"tEXt", Bytes{'a', 0, 'b'}}};  // metadata the decoder skips
      const Bytes png = png_file(rgb, zlib_stream(filtered_rows(rgb, first_filter)), parts);
      cv::Mat decoded;
      ASSERT_TRUE(decode_plain_rgb8_png(png.data(), png.size(), &decoded)) << rows << "x" << cols;
      EXPECT_TRUE(same(decoded, rgb)) << rows << "x" << cols << " filter " << first_filter;
      EXPECT_TRUE(same(decoded, opencv_rgb(png))) << rows << "x" << cols;
    }
}

TEST(PngDecoder, OpenCvsOwnFilesDecodeAsLibpngDoes) {
  const cv::Mat bgr = random_rgb(75, 121, 7);  // libpng's adaptive filters pick per row
  for (int level : {0, 1, 9}) {
    std::vector<std::uint8_t> png;
    ASSERT_TRUE(cv::imencode(".png", bgr, png, {cv::IMWRITE_PNG_COMPRESSION, level}));
    cv::Mat decoded;
    ASSERT_TRUE(decode_plain_rgb8_png(png.data(), png.size(), &decoded)) << level;
    EXPECT_TRUE(same(decoded, opencv_rgb(png))) << level;
  }
}

TEST(PngDecoder, FilesOutsideThePlainCaseAreDeclinedAndReadByOpenCv) {
  const cv::Mat rgb = random_rgb(16, 24, 3);
  const Bytes stream = zlib_stream(filtered_rows(rgb, 1));
  PngParts gamma;  // a chunk that may change pixels: libpng's business
  gamma.before_data = {{"gAMA", Bytes{0, 0, 0xb1, 0x8f}}};
  std::vector<std::uint8_t> grey;
  cv::Mat grey_image(16, 24, CV_8UC1, cv::Scalar(90));
  ASSERT_TRUE(cv::imencode(".png", grey_image, grey));
  for (const auto& [name, png] : std::vector<std::pair<std::string, Bytes>>{
           {"gamma", png_file(rgb, stream, gamma)}, {"grey", grey}}) {
    cv::Mat decoded;
    EXPECT_FALSE(decode_plain_rgb8_png(png.data(), png.size(), &decoded)) << name;
    EXPECT_TRUE(decoded.empty()) << name;
    const std::string path = write_temp(png, name + ".png");
    EXPECT_TRUE(same(read_png_rgb8(path), opencv_rgb(png))) << name;
    std::remove(path.c_str());
  }
}

TEST(PngDecoder, DamagedStreamsAreDeclinedNeverDecodedWrong) {
  const cv::Mat rgb = random_rgb(20, 30, 5);
  const Bytes raw = filtered_rows(rgb, 2), stream = zlib_stream(raw);
  Bytes bad_filter = raw;
  bad_filter[0] = 5;  // no such filter
  Bytes flipped = png_file(rgb, stream);
  flipped[60] ^= 0x10;  // a bit of the first IDAT's data: its CRC no longer matches
  Bytes short_stream(stream.begin(), stream.end() - 8);  // the end and the Adler-32 cut
  Bytes no_end = png_file(rgb, stream);
  no_end.resize(no_end.size() - 12);  // the IEND chunk cut
  Bytes extra = filtered_rows(rgb, 2);
  extra.insert(extra.end(), rgb.cols * 3 + 1, 0);  // one row more than the header declares
  const Bytes fewer(raw.begin(), raw.end() - (rgb.cols * 3 + 1));  // a whole stream one row short
  PngParts split;  // IDAT chunks must be consecutive
  split.between_data = {{"tEXt", Bytes{'a', 0, 'b'}}};
  Bytes lying = png_file(rgb, stream);
  lying[16] = 0x7f;  // width 2^31 - ish with the header's CRC fixed below
  {
    const std::uint32_t crc = libdeflate_crc32(0, lying.data() + 12, 17);
    for (int k = 0; k < 4; ++k) lying[29 + k] = static_cast<std::uint8_t>(crc >> (24 - 8 * k));
  }
  for (const auto& [name, png] : std::vector<std::pair<std::string, Bytes>>{
           {"bad filter", png_file(rgb, zlib_stream(bad_filter))},
           {"flipped bit", flipped},
           {"short stream", png_file(rgb, short_stream)},
           {"no IEND", no_end},
           {"extra data", png_file(rgb, zlib_stream(extra))},
           {"a row short", png_file(rgb, zlib_stream(fewer))},
           {"split data", png_file(rgb, stream, split)},
           {"huge header", lying},
           {"not a png", Bytes{'G', 'I', 'F', '8'}}}) {
    cv::Mat decoded;
    EXPECT_FALSE(decode_plain_rgb8_png(png.data(), png.size(), &decoded)) << name;
    EXPECT_TRUE(decoded.empty()) << name;
  }
  // a damaged file read whole is OpenCV's to judge: an error naming it
  const std::string path = write_temp(flipped, "flipped.png");
  try {
    const cv::Mat decoded = read_png_rgb8(path);
    EXPECT_FALSE(same(decoded, rgb)) << "a flipped bit decoded to the original pixels";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
  }
  std::remove(path.c_str());
}

// Every byte of a plain PNG is under a chunk CRC (the signature under the decoder's own check):
// any one flipped byte, and any cut, is declined; never a crash (the sanitizer build runs this
// too) and never other pixels.
TEST(PngDecoder, NoFlippedByteOrCutDecodesToOtherPixels) {
  const cv::Mat rgb = random_rgb(12, 17, 11);
  PngParts parts;
  parts.before_data = {{"tEXt", Bytes{'k', 0, 'v'}}};
  const Bytes png = png_file(rgb, zlib_stream(filtered_rows(rgb, 4)), parts);
  cv::RNG rng(2026);
  int declined = 0;
  for (size_t at = 0; at < png.size(); ++at) {
    Bytes flipped = png;
    flipped[at] ^= static_cast<std::uint8_t>(1 + rng.uniform(0, 255));  // never a zero xor
    cv::Mat decoded;
    if (decode_plain_rgb8_png(flipped.data(), flipped.size(), &decoded))
      EXPECT_TRUE(same(decoded, rgb)) << "byte " << at;
    else
      ++declined;
  }
  EXPECT_EQ(declined, static_cast<int>(png.size())) << "a flip in a checked byte was accepted";
  for (size_t length = 0; length < png.size(); ++length) {
    cv::Mat decoded;
    EXPECT_FALSE(decode_plain_rgb8_png(png.data(), length, &decoded)) << "cut at " << length;
  }
}
