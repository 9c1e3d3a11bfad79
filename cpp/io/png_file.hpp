#pragma once
// Colour PNG files (8 bits per channel, no alpha: KITTI's and the simulator's camera images)
// decoded by OpenCV's libpng reader: 2.5-3 ms faster per 1242 x 375 image than Pillow's on this
// machine (8.4 vs 10.8 ms simulated, 10.7 vs 13.9 ms real KITTI), and free of the GIL. The
// pixels are the same: PNG is lossless. Other kinds of image stay with Pillow
// (twistslam.datasets.read_image decides from the file's header).
#include <opencv2/core.hpp>

#include <string>

namespace twistslam::io {

// The image at `path` as RGB (H, W, 3) CV_8UC3. Throws std::runtime_error naming the file when
// it cannot be read or decoded, or does not decode to 8-bit colour.
cv::Mat read_png_rgb8(const std::string& path);

}  // namespace twistslam::io
