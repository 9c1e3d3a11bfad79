#pragma once
// Depth of a vehicle from where it touches the road, for an instance whose stereo gives too
// few points (not in the paper). The right camera sees other occluders than the left: a car
// queued behind a nearer one, or an oncoming car at 35-50 m, may show 17-37 keypoints in its
// left mask and only 1-4 stereo depths, fewer than a cluster needs. Its mask's lower edge,
// where the pixel just below is road, lies on the road plane: each such column's bottom pixel
// back-projected onto the plane gives a depth, and their median is the depth of the car's
// nearest face (rear or front for a car ahead, the near side for a crossing one). The
// keypoints inside the mask are placed at that depth -- a vertical face, as monocular 3D
// detectors assume -- and tracked as mono points (eq. 4 reprojection only).
// A mask whose lower edge is hidden (behind a nearer car) has no road below it and gives no
// depth, rather than the occluder's top edge, which would place it metres too far.
#include <opencv2/core/mat.hpp>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::tracking {

struct GroundContact {
  bool valid = false;
  double depth = 0;  // m, camera z of the contact points' median
  int columns = 0;       // mask columns whose bottom pixel has road below it
  int mask_columns = 0;  // columns the mask spans, those hidden behind another instance aside
  int hidden_columns = 0;  // columns whose lower edge rests on another instance (an occluder)
};

// contact_height_m: the rays meet a plane this far above the road (towards the camera): a
// car's lowest pixel between its wheels is its body, above the road.
// instances, labels: CV_32SC1 of the camera's image size (instance ids, class ids); plane_w:
// the road (n, d) with n . X_w + d = 0, T_w_c the camera pose. Road below means within
// `max_gap_px` rows under the mask's lowest pixel of that column (mask edges are not exact).
// Valid with at least min_columns such columns whose rays meet the plane in front of the
// camera (at most max_depth_m), and at least min_fraction of the mask's columns whose lower
// edge is not hidden behind another instance: a car whose lower edge rests on the sidewalk,
// a kerb or an unlabelled occluder at most columns shows road below only at a few, where its
// contact is not the road's. Columns hidden behind another instance (a nearer car of a queue)
// say nothing of the visible ones: crowded seed 3's car 16, queued behind car 15, shows road
// below 21 of the 29 columns it does not rest on a car at, and 21 of all its 64 columns.
GroundContact ground_contact_depth(const cv::Mat& instances, const cv::Mat& labels,
                                   int instance, int road_class_id,
                                   const geometry::StereoCamera& camera, const Mat4& T_w_c,
                                   const Vec4& plane_w, int min_columns, double min_fraction,
                                   double max_depth_m, int max_gap_px = 2,
                                   double depth_quantile = 0.5, double contact_height_m = 0.0);

}  // namespace twistslam::tracking
