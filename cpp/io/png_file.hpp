#pragma once
// Colour PNG files (8 bits per channel, no alpha: KITTI's and the simulator's camera images),
// free of the GIL. A plain RGB PNG takes the fast path (io/png_decoder.hpp: libdeflate, 5.5 ms
// per 1242 x 375 image on this machine against 10.8 through OpenCV's libpng, the same pixels);
// every other file is decoded by OpenCV's libpng. Other kinds of image stay with Pillow
// (twistslam.datasets.read_image decides from the file's header).
#include <opencv2/core.hpp>

#include <string>

namespace twistslam::io {

// The image at `path` as RGB (H, W, 3) CV_8UC3. Throws std::runtime_error naming the file when
// it cannot be read or decoded, or does not decode to 8-bit colour.
cv::Mat read_png_rgb8(const std::string& path);

}  // namespace twistslam::io
