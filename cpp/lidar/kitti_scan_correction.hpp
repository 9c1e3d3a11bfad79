#pragma once
// KITTI's HDL-64 scans carry a known vertical-angle calibration error: every beam points
// about 0.205 deg lower than the driver assumes. Rotating each point up by that angle about
// the horizontal axis p x z (z = up in the Velodyne frame) restores the elevation; the same
// correction is applied by KISS-ICP's KITTI reader. Measured on KITTI 0001: without it road
// depths at 25-80 m disagree with stereo by 3-8 % more than depths above the road do.
#include "geometry/types.hpp"

namespace twistslam::lidar {

constexpr double kKittiVerticalAngleOffsetDeg = 0.205;  // deg, upward

// Points in the Velodyne frame (x forward, y left, z up), before Tr_velo_cam. Each point p is
// rotated by angle_deg about the unit axis (p x e_z) / |p x e_z| (Rodrigues, eq. of so3_exp);
// its range is kept. Points on the z axis (no horizontal direction) and non-finite points are
// returned unchanged.
Points3 correct_kitti_scan(const Eigen::Ref<const Points3>& points_velo,
                           double angle_deg = kKittiVerticalAngleOffsetDeg);

// A scan as read from a KITTI .bin: rows (x, y, z, extra columns such as intensity), float.
using ScanRows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The reader's one pass over a scan: the elevation correction and the transform into the
// (rectified) camera frame, extra columns carried along, written into `velo` (the corrected
// scan, as correct_kitti_scan) and `camera` ((x, y, z) = T_c_velo X), each of the input's
// shape. Computed in double, stored in float. std::invalid_argument for fewer than 3 columns,
// an output of another shape, a non-finite angle or transform.
void scan_to_camera(const Eigen::Ref<const ScanRows>& points_velo, const Mat4& T_c_velo,
                    double angle_deg, Eigen::Ref<ScanRows> velo, Eigen::Ref<ScanRows> camera);

}  // namespace twistslam::lidar
