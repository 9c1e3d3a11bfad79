#pragma once
// Zero-mean SAD block matching along a rectified row, shared by the descriptor-guided stereo
// matcher (stereo.cpp: sub-pixel refinement around a descriptor match) and the descriptor-free
// search of object keypoints (stereo_search.cpp: a scan over the whole disparity range).
// Windows are (2 half_width + 1) x (2 half_height + 1) level pixels. Both take an optional
// support: which pixels of the left window (row-major, 1 = used) belong to the keypoint's
// object. The zero-mean SAD is then summed over those pixels only (window means included): a
// window on an object's edge otherwise also matches the background, whose texture can outweigh
// the object's (a pedestrian beside a tree trunk took the trunk's disparity).
#include <opencv2/core.hpp>

#include <cstdint>

namespace twistslam::features {

inline constexpr int kMaxSadHalfWidth = 15, kMaxSadHalfHeight = 15, kMaxSadRange = 32;

// Sub-pixel offset of the minimum of a V-shaped cost sampled at -1, 0, +1 (c0 smallest).
// Zero-mean SAD grows linearly with the shift away from its minimum, so two lines of opposite
// slope through the three samples locate it without the bias a parabola has on a V.
float vertex_offset(float cm, float c0, float cp);

struct SadRefined {
  float u_level = 0;  // column in the right level image (level px)
  float cost = 0;     // best zero-mean SAD / left window contrast
  bool ok = false;
};

// Zero-mean SAD of the left window around (xl, y) against right windows centred on
// (xr0 + d, y + dy), d in [-range, range] (range <= kMaxSadRange); dy is the sub-pixel
// vertical offset the pair's geometry predicts, sampled by linear interpolation between rows.
// The minimum must lie strictly inside the range; a V fit through it and its neighbours gives
// the sub-pixel column. Not ok where a window leaves an image.
SadRefined refine_sad(const cv::Mat& L, const cv::Mat& R, int xl, int y, int xr0, float dy,
                      int half_width, int half_height, int range,
                      const std::uint8_t* support = nullptr);

struct SadScan {
  int best_column = -1;     // right level column of the smallest cost (-1: no window fits)
  float best_cost = 0;      // zero-mean SAD / left window contrast at best_column
  float second_cost = 0;    // smallest other local minimum >= 2 columns away (inf: none)
};

// Zero-mean SAD of the left window around (xl, y) against the right windows centred on
// (x, y), x in [x_first, x_last] (integer rows: the scan only needs the minimum to the pixel;
// refine_sad adds the sub-pixel column and the row offset). Columns whose window leaves the
// right image are skipped.
SadScan scan_sad(const cv::Mat& L, const cv::Mat& R, int xl, int y, int x_first, int x_last,
                 int half_width, int half_height, const std::uint8_t* support = nullptr);

}  // namespace twistslam::features
