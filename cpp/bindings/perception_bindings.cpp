// Bindings of cpp/perception: dense optical flow with OpenCV DIS, and panoptic labels from 3D
// boxes and LiDAR. Images are converted to C-contiguous uint8 once and wrapped as cv::Mat;
// the GIL is released while DIS and the masks run.
#include <pybind11/numpy.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings/numpy_checks.hpp"
#include "perception/box_masks.hpp"
#include "perception/dis_flow.hpp"
#include "perception/hull_fill.hpp"

namespace twistslam::bindings {
namespace p = twistslam::perception;
using namespace pybind11::literals;

namespace {

using ByteArray = py::array_t<std::uint8_t, py::array::c_style>;

// (H, W) or (H, W, 3) uint8 image; ValueError naming the argument otherwise (no silent
// conversion from float: a [0, 1] float image would become black).
ByteArray checked_image(const py::handle& obj, const char* name) {
  const std::string want = std::string(name) + ": expected uint8 (H, W) or (H, W, 3), got ";
  py::array arr = py::array::ensure(obj);
  if (obj.is_none() || !arr) throw py::value_error(want + std::string(py::str(py::type::of(obj))));
  const bool u8 = arr.dtype().kind() == 'u' && arr.dtype().itemsize() == 1;
  const bool shape_ok = arr.ndim() == 2 || (arr.ndim() == 3 && arr.shape(2) == 3);
  if (!u8 || !shape_ok) throw py::value_error(want + std::string(py::str(arr.dtype())) + " " + shape_string(arr));
  if (arr.shape(0) < 2 || arr.shape(1) < 2) throw py::value_error(std::string(name) + ": image too small " + shape_string(arr));
  return ByteArray::ensure(arr);
}

cv::Mat as_mat(const ByteArray& a) {
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), a.ndim() == 3 ? CV_8UC3 : CV_8UC1,
                 const_cast<std::uint8_t*>(a.data()));
}

py::array_t<float> dis_flow(const py::handle& previous, const py::handle& current, const std::string& preset,
                            int finest_scale_level, int patch_size_px, int patch_stride_px,
                            int gradient_descent_iterations, int variational_refinement_iterations,
                            bool use_spatial_propagation) {
  const ByteArray a = checked_image(previous, "previous");
  const ByteArray b = checked_image(current, "current");
  if (a.shape(0) != b.shape(0) || a.shape(1) != b.shape(1))
    throw py::value_error("current: image size " + shape_string(b) + " differs from previous " + shape_string(a));
  p::DisFlowOptions o;
  cv::Mat flow;
  try {
    o.preset = p::dis_preset_from_name(preset);
    o.finest_scale_level = finest_scale_level;
    o.patch_size_px = patch_size_px;
    o.patch_stride_px = patch_stride_px;
    o.gradient_descent_iterations = gradient_descent_iterations;
    o.variational_refinement_iterations = variational_refinement_iterations;
    o.use_spatial_propagation = use_spatial_propagation;
    p::validate(o);
    py::gil_scoped_release release;
    flow = p::dis_flow(as_mat(a), as_mat(b), o);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  py::array_t<float> out({a.shape(0), a.shape(1), py::ssize_t{2}});
  for (int y = 0; y < flow.rows; ++y)
    std::memcpy(out.mutable_data(y), flow.ptr<float>(y), sizeof(float) * 2 * static_cast<std::size_t>(flow.cols));
  return out;
}

using IntArray = py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>;

// (K,) integer array of one value per box; ValueError naming the argument otherwise.
IntArray per_box_ints(const py::handle& obj, const char* name, py::ssize_t count) {
  py::array arr = py::array::ensure(obj);
  if (obj.is_none() || !arr || arr.ndim() != 1 || arr.shape(0) != count ||
      (count > 0 && arr.dtype().kind() != 'i' && arr.dtype().kind() != 'u'))
    throw py::value_error(std::string(name) + ": expected an integer array of shape (" +
                          std::to_string(count) + ",) (one per box), got " +
                          (arr ? std::string(py::str(arr.dtype())) + " " + shape_string(arr) : std::string("None")));
  return IntArray::ensure(arr);
}

std::vector<Vec2> image_points(const py::handle& obj, const char* name) {
  const DoubleArray a = as_rows(obj, name, 2);
  std::vector<Vec2> out(static_cast<size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) out[static_cast<size_t>(i)] = Vec2(a.at(i, 0), a.at(i, 1));
  return out;
}

Points3 scan_points(const py::handle& obj) {
  const DoubleArray a = as_rows(obj, "points", 3);
  return points_view(a);
}

py::array_t<std::int32_t> image_of(const std::vector<std::int32_t>& values, int height, int width) {
  py::array_t<std::int32_t> out({static_cast<py::ssize_t>(height), static_cast<py::ssize_t>(width)});
  std::memcpy(out.mutable_data(), values.data(), sizeof(std::int32_t) * values.size());
  return out;
}

p::BoxMaskOptions mask_options(double low_point_below_camera_m, double plane_fit_threshold_m,
                               double ground_band_m, double hull_ground_clearance_m,
                               double road_cell_m, int road_dilation_cells,
                               double road_max_range_m, int min_box_points) {
  p::BoxMaskOptions o;
  o.low_point_below_camera_m = low_point_below_camera_m;
  o.plane_fit_threshold_m = plane_fit_threshold_m;
  o.ground_band_m = ground_band_m;
  o.hull_ground_clearance_m = hull_ground_clearance_m;
  o.road_cell_m = road_cell_m;
  o.road_dilation_cells = road_dilation_cells;
  o.road_max_range_m = road_max_range_m;
  o.min_box_points = min_box_points;
  return o;
}

py::tuple masks_from_boxes(const py::handle& points, const py::handle& boxes,
                           const py::handle& class_ids, const py::handle& instance_ids,
                           const py::handle& P, int height, int width, std::int32_t unknown_id,
                           std::int32_t road_id, double low_point_below_camera_m,
                           double plane_fit_threshold_m, double ground_band_m,
                           double hull_ground_clearance_m, double road_cell_m,
                           int road_dilation_cells, double road_max_range_m, int min_box_points) {
  const Points3 X = scan_points(points);
  const DoubleArray b = as_rows(boxes, "boxes", 7);
  const IntArray cls = per_box_ints(class_ids, "class_ids", b.shape(0));
  const IntArray ids = per_box_ints(instance_ids, "instance_ids", b.shape(0));
  const Mat34 projection = as_mat34(P, "P");
  std::vector<p::MaskBox> mask_boxes(static_cast<size_t>(b.shape(0)));
  for (py::ssize_t k = 0; k < b.shape(0); ++k) {
    p::MaskBox& m = mask_boxes[static_cast<size_t>(k)];
    m.centre = Vec3(b.at(k, 0), b.at(k, 1), b.at(k, 2));
    m.length = b.at(k, 3);
    m.width = b.at(k, 4);
    m.height = b.at(k, 5);
    m.yaw = b.at(k, 6);
    m.class_id = cls.at(k);
    m.instance_id = ids.at(k);
  }
  const p::BoxMaskOptions o = mask_options(low_point_below_camera_m, plane_fit_threshold_m, ground_band_m,
                                           hull_ground_clearance_m, road_cell_m, road_dilation_cells,
                                           road_max_range_m, min_box_points);
  p::BoxMasks masks;
  try {
    py::gil_scoped_release release;
    masks = p::masks_from_boxes(X, mask_boxes, projection, height, width, o, unknown_id, road_id);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  py::object plane = py::none();
  if (masks.plane) plane = to_numpy(*masks.plane);
  return py::make_tuple(image_of(masks.class_id, height, width), image_of(masks.instance_id, height, width), plane);
}

}  // namespace

void bind_perception(py::module_& m) {
  m.def("dis_flow", &dis_flow, "previous"_a, "current"_a, py::kw_only(), "preset"_a = "medium",
        "finest_scale_level"_a = -1, "patch_size_px"_a = -1, "patch_stride_px"_a = -1,
        "gradient_descent_iterations"_a = -1, "variational_refinement_iterations"_a = -1,
        "use_spatial_propagation"_a = true,
        R"doc(Dense optical flow from ``previous`` to ``current`` with OpenCV DIS.

Parameters
----------
previous, current : (H, W) or (H, W, 3) uint8 arrays
    Grey or RGB images of the same size.
preset : {"ultrafast", "fast", "medium"}
    OpenCV's speed / accuracy preset; the options below override it (-1 keeps its value).
finest_scale_level : int
    Finest pyramid level searched, 0 = full resolution (-1 or 0..10).
patch_size_px, patch_stride_px : int
    Side of the matched patches and distance between their centres, in pixels.
gradient_descent_iterations, variational_refinement_iterations : int
    Iterations per patch and level; variational refinement 0 disables the smoothing.
use_spatial_propagation : bool
    Propagate good patch flows to their neighbours.

Returns
-------
(H, W, 2) float32 array of (u, v) in pixels: previous[y, x] ~ current[y + v, x + u].

Raises
------
ValueError
    On a wrong dtype / shape, differing sizes or an option out of range.
)doc");

  m.def("masks_from_boxes", &masks_from_boxes, "points"_a, "boxes"_a, "class_ids"_a, "instance_ids"_a,
        "P"_a, "height"_a, "width"_a, py::kw_only(), "unknown_id"_a = 0, "road_id"_a = 7,
        "low_point_below_camera_m"_a = 1.0, "plane_fit_threshold_m"_a = 0.1, "ground_band_m"_a = 0.1,
        "hull_ground_clearance_m"_a = 0.1, "road_cell_m"_a = 0.5, "road_dilation_cells"_a = 1,
        "road_max_range_m"_a = 40.0, "min_box_points"_a = 3,
        R"doc(Panoptic labels of one image from its LiDAR points and 3D boxes (no weights).

Each box's points above the ground are projected with ``P`` and their convex hull filled,
far boxes first; road pixels are those whose ray meets the fitted ground plane in a bird's-eye
cell holding a ground point. See ``twistslam.perception.BoxMaskConfig`` for the options.

Parameters
----------
points : (N, 3) array
    LiDAR points in the rectified camera frame (m); rows with NaN / Inf are ignored.
boxes : (K, 7) array
    ``[cx, cy, cz, l, w, h, ry]`` per box, geometric centre in the camera frame.
class_ids, instance_ids : (K,) integer arrays
    Values written under each box's mask.
P : (3, 4) array
    Projection of the left image.
height, width : int
    Image size in pixels.
unknown_id, road_id : int
    Class of the pixels no box covers, and of road pixels.

Returns
-------
(class_id, instance_id, plane): two (height, width) int32 arrays (instance 0 where no box) and
the ground plane ``[nx, ny, nz, d]`` (normal up, towards -y) or None with fewer than 3 low points.

Raises
------
ValueError
    On a wrong shape or dtype, a non-positive image size or an option out of range.
)doc");

  m.def(
      "ground_plane",
      [](const py::handle& points, double low_point_below_camera_m, double plane_fit_threshold_m) -> py::object {
        const Points3 X = scan_points(points);
        p::BoxMaskOptions o;
        o.low_point_below_camera_m = low_point_below_camera_m;
        o.plane_fit_threshold_m = plane_fit_threshold_m;
        std::optional<Vec4> plane;
        try {
          p::validate(o);
          py::gil_scoped_release release;
          plane = p::ground_plane(X, o);
        } catch (const std::invalid_argument& e) {
          throw py::value_error(e.what());
        }
        return plane ? py::object(to_numpy(*plane)) : py::object(py::none());
      },
      "points"_a, py::kw_only(), "low_point_below_camera_m"_a = 1.0, "plane_fit_threshold_m"_a = 0.1,
      R"doc(The ground plane of a scan: RANSAC through the points lower than the camera by more
than ``low_point_below_camera_m`` (camera frame, y down), refined by least squares.

Parameters
----------
points : (N, 3) array
    LiDAR points in the camera frame (m); rows with NaN / Inf are ignored.
low_point_below_camera_m, plane_fit_threshold_m : float
    Candidate height (m below the camera) and RANSAC inlier distance (m).

Returns
-------
(4,) array ``[nx, ny, nz, d]`` with ``n . X + d = 0`` and n pointing up (ny < 0), or None with
fewer than 3 candidates.
)doc");

  m.def(
      "convex_hull",
      [](const py::handle& points) {
        std::vector<Vec2> hull = p::convex_hull(image_points(points, "points"));
        DoubleArray out = new_array({static_cast<py::ssize_t>(hull.size()), 2});
        for (size_t i = 0; i < hull.size(); ++i) {
          out.mutable_at(static_cast<py::ssize_t>(i), 0) = hull[i].x();
          out.mutable_at(static_cast<py::ssize_t>(i), 1) = hull[i].y();
        }
        return out;
      },
      "points"_a,
      R"doc(Convex hull of 2D points (Andrew's monotone chain).

Parameters
----------
points : (N, 2) array
    Finite points.

Returns
-------
(K, 2) array of hull vertices with a positive signed area (counter-clockwise in x right, y
up); duplicates and collinear points dropped; fewer than 3 distinct points come back sorted.
)doc");

  m.def(
      "convex_hull_mask",
      [](const py::handle& points, int height, int width) {
        if (height <= 0 || width <= 0) throw py::value_error("convex_hull_mask: height and width must be positive");
        const std::vector<Vec2> uv = image_points(points, "points");
        py::array_t<bool> out({static_cast<py::ssize_t>(height), static_cast<py::ssize_t>(width)});
        std::fill(out.mutable_data(), out.mutable_data() + out.size(), false);
        for (const p::PixelSpan& s : p::convex_hull_pixels(uv, height, width))
          std::fill(out.mutable_data(s.v, s.u0), out.mutable_data(s.v, s.u1) + 1, true);
        return out;
      },
      "points"_a, "height"_a, "width"_a,
      R"doc(Pixels covered by the convex hull of image points, and the pixels holding a point.

Parameters
----------
points : (N, 2) array
    Image points (u, v) in pixels; pixel (u, v) covers ``[u, u+1) x [v, v+1)``.
height, width : int
    Image size.

Returns
-------
(height, width) bool array: pixels whose centre lies in the hull (or on its edge), and the
pixels holding a point. Fewer than 3 distinct points or a non-finite point: all False.
)doc");
}

}  // namespace twistslam::bindings
