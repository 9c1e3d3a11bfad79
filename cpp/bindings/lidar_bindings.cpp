// Bindings of cpp/lidar: scan projection, LiDAR depth of keypoints, the KITTI scan
// correction and the disparity offset estimate. Options cross as a dict / keyword arguments
// checked against one field table (unknown keys and out-of-range values raise ValueError).
#include <pybind11/stl.h>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings/numpy_checks.hpp"
#include "bindings/options_table.hpp"
#include "lidar/disparity_offset.hpp"
#include "lidar/kitti_scan_correction.hpp"
#include "lidar/lidar_depth.hpp"
#include "lidar/scan_projection.hpp"

namespace twistslam::bindings {
namespace l = twistslam::lidar;
using namespace pybind11::literals;

namespace {

FieldTable depth_fields(l::LidarDepthOptions* o) {
  return {{"cell_size_px", set(&o->cell_size_px)},
          {"search_radius_px", set(&o->search_radius_px)},
          {"min_depth_m", set(&o->min_depth_m)},
          {"max_depth_m", set(&o->max_depth_m)},
          {"min_returns", set(&o->min_returns)},
          {"max_fit_residual", set(&o->max_fit_residual)},
          {"layer_gap", set(&o->layer_gap)}};
}

// options dict merged with keyword arguments (keywords win), validated: ValueError on a bad key
// or value.
l::LidarDepthOptions depth_options(const py::object& options, const py::kwargs& kwargs) {
  l::LidarDepthOptions o;
  const FieldTable fields = depth_fields(&o);
  if (!options.is_none()) {
    if (!py::isinstance<py::dict>(options))
      throw py::type_error("lidar options: expected a dict or None");
    apply_section(options.cast<py::dict>(), "lidar", fields);
  }
  apply_section(kwargs, "lidar", fields);
  try {
    l::validate(o);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  return o;
}

// (H, W) bool / uint8 mask (not None); 0 = dynamic class. Kept alive by the returned array.
py::array mask_array(const py::handle& obj, int width, int height) {
  py::array arr = py::array::ensure(obj);
  const std::string want = "mask: expected bool or uint8 (" + std::to_string(height) + ", " +
                           std::to_string(width) + ")";
  if (!arr) throw py::value_error(want + ", got " + std::string(py::str(py::type::of(obj))));
  const char kind = arr.dtype().kind();
  const bool dtype_ok = (kind == 'b' || kind == 'u') && arr.dtype().itemsize() == 1;
  if (!dtype_ok || arr.ndim() != 2 || arr.shape(0) != height || arr.shape(1) != width)
    throw py::value_error(want + ", got " + std::string(py::str(arr.dtype())) + " " +
                          shape_string(arr));
  if (kind == 'b') arr = py::array::ensure(arr.attr("view")("uint8"));
  return py::array_t<std::uint8_t, py::array::c_style>::ensure(arr);
}

l::ScanProjection project(const py::handle& points_c, const geometry::StereoCamera& camera,
                          const py::handle& mask, const py::object& options,
                          const py::kwargs& kwargs) {
  const l::LidarDepthOptions o = depth_options(options, kwargs);
  const DoubleArray a = as_double_array(points_c, "points_c");
  if (a.ndim() != 2 || a.shape(1) < 3)
    throw py::value_error("points_c: expected shape (N, 3) or (N, >=3) (extra columns such as "
                          "intensity are ignored), got " + shape_string(a));
  if (camera.width <= 0 || camera.height <= 0)
    throw py::value_error("project_scan: the camera has no image size (width / height 0)");
  // py::array() is an empty array, not a null handle: keep "no mask" as an empty cv::Mat.
  py::array m;
  cv::Mat mask_mat;
  if (!mask.is_none()) {
    m = mask_array(mask, camera.width, camera.height);
    mask_mat = cv::Mat(camera.height, camera.width, CV_8UC1, const_cast<void*>(m.data()));
  }
  // (N, 3) and (N, 4) float64 alike without a copy: Ref<const Points3> takes any row stride.
  using Strided = Eigen::Map<const Points3, 0, Eigen::OuterStride<>>;
  const Strided view(a.data(), a.shape(0), 3, Eigen::OuterStride<>(a.shape(1)));
  py::gil_scoped_release release;
  return l::project_scan(view, camera, o, mask_mat);
}

py::dict depth_at(const py::handle& keypoints, const l::ScanProjection& scan,
                  const py::object& options, const py::kwargs& kwargs) {
  const l::LidarDepthOptions o = depth_options(options, kwargs);
  const DoubleArray kp = as_rows(keypoints, "keypoints", 2);
  const auto n = static_cast<std::size_t>(kp.shape(0));
  std::vector<Vec2> uv(n);
  for (std::size_t i = 0; i < n; ++i) uv[i] = Vec2(kp.data()[2 * i], kp.data()[2 * i + 1]);
  std::vector<l::LidarDepth> out;
  {
    py::gil_scoped_release release;
    out = l::lidar_depth_at(uv, scan, o);
  }
  const auto rows = static_cast<py::ssize_t>(n);
  py::array_t<double> depth(rows), rms(rows);
  py::array_t<std::int32_t> count(rows);
  py::array_t<std::uint8_t> status(rows);
  py::array_t<bool> valid(rows);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < n; ++i) {
    depth.mutable_data()[i] = out[i].valid() ? out[i].depth : nan;
    rms.mutable_data()[i] = out[i].valid() ? out[i].rms_relative : nan;
    count.mutable_data()[i] = out[i].num_returns;
    status.mutable_data()[i] = static_cast<std::uint8_t>(out[i].status);
    valid.mutable_data()[i] = out[i].valid();
  }
  return py::dict("depth"_a = depth, "valid"_a = valid, "num_returns"_a = count,
                  "status"_a = status, "rms_relative"_a = rms);
}

DoubleArray correct_scan(const py::handle& points_velo, double angle_deg) {
  const DoubleArray a = as_double_array(points_velo, "points_velo");
  if (a.ndim() != 2 || a.shape(1) < 3)
    throw py::value_error("points_velo: expected shape (N, 3) or (N, >=3), got " +
                          shape_string(a));
  if (!std::isfinite(angle_deg)) throw py::value_error("correct_kitti_scan: angle_deg must be finite");
  const py::ssize_t n = a.shape(0), cols = a.shape(1);
  using Strided = Eigen::Map<const Points3, 0, Eigen::OuterStride<>>;
  const Points3 xyz = Strided(a.data(), n, 3, Eigen::OuterStride<>(cols));
  const Points3 corrected = l::correct_kitti_scan(xyz, angle_deg);
  DoubleArray out = new_array({n, cols});
  double* dst = out.mutable_data();
  std::copy(a.data(), a.data() + n * cols, dst);  // extra columns (intensity) unchanged
  for (py::ssize_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) dst[i * cols + c] = corrected(i, c);
  return out;
}

py::tuple scan_to_camera(const py::handle& points_velo, const py::handle& T_c_velo, double angle_deg) {
  using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
  py::array raw = py::array::ensure(points_velo);
  if (points_velo.is_none() || !raw || raw.ndim() != 2 || raw.shape(1) < 3)
    throw py::value_error("points_velo: expected shape (N, >=3), got " +
                          (raw ? shape_string(raw) : std::string("None")));
  const FloatArray a = FloatArray::ensure(raw);
  const Mat4 T = as_mat4(T_c_velo, "T_c_velo");
  const py::ssize_t n = a.shape(0), cols = a.shape(1);
  FloatArray velo({n, cols}), camera({n, cols});
  try {
    py::gil_scoped_release release;
    l::scan_to_camera(Eigen::Map<const l::ScanRows>(a.data(), n, cols), T, angle_deg,
                      Eigen::Map<l::ScanRows>(velo.mutable_data(), n, cols),
                      Eigen::Map<l::ScanRows>(camera.mutable_data(), n, cols));
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  return py::make_tuple(velo, camera);
}

std::vector<double> as_vector(const py::handle& obj, const char* name) {
  const DoubleArray a = as_double_array(obj, name);
  if (a.ndim() != 1)
    throw py::value_error(std::string(name) + ": expected shape (N,), got " + shape_string(a));
  return std::vector<double>(a.data(), a.data() + a.shape(0));
}

py::dict disparity_offset(const py::handle& disparities, const py::handle& depths,
                          double fx_baseline, int min_samples, double max_abs_residual_px) {
  l::DisparityOffsetOptions o;
  o.min_samples = min_samples;
  o.max_abs_residual_px = max_abs_residual_px;
  const std::vector<double> d = as_vector(disparities, "disparities");
  const std::vector<double> z = as_vector(depths, "lidar_depths");
  l::DisparityOffset r;
  try {
    r = l::estimate_disparity_offset(d, z, fx_baseline, o);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  return py::dict("valid"_a = r.valid, "offset_px"_a = r.offset_px, "mad_px"_a = r.mad_px,
                  "num_samples"_a = r.num_samples);
}

py::dict status_names() {
  py::dict out;
  for (std::uint8_t s = 0; s <= static_cast<std::uint8_t>(l::LidarDepthStatus::kPoorFit); ++s)
    out[py::int_(s)] = l::to_string(static_cast<l::LidarDepthStatus>(s));
  return out;
}

}  // namespace

void bind_lidar(py::module_& m) {
  py::class_<l::ScanProjection>(m, "ScanProjection",
                                "A scan projected into the left image, bucketed by pixel cell. "
                                "Build with project_scan; query with lidar_depth_at.")
      .def_property_readonly("num_returns", [](const l::ScanProjection& s) { return s.returns.size(); },
                             "Returns kept (in the image, in the depth range, not masked).")
      .def_readonly("num_non_finite", &l::ScanProjection::num_non_finite,
                    "Input points with a NaN / Inf coordinate (dropped).")
      .def_readonly("num_masked", &l::ScanProjection::num_masked,
                    "Returns in the image on mask == 0 pixels (dropped).")
      .def_readonly("width", &l::ScanProjection::width)
      .def_readonly("height", &l::ScanProjection::height)
      .def_property_readonly("uv", [](const l::ScanProjection& s) {
        DoubleArray out = new_array({static_cast<py::ssize_t>(s.returns.size()), 2});
        for (std::size_t i = 0; i < s.returns.size(); ++i) {
          out.mutable_data()[2 * i] = s.returns[i].u;
          out.mutable_data()[2 * i + 1] = s.returns[i].v;
        }
        return out;
      }, "(M, 2) float64 pixels of the kept returns (bucket order).")
      .def_property_readonly("depth", [](const l::ScanProjection& s) {
        py::array_t<double> out(static_cast<py::ssize_t>(s.returns.size()));
        for (std::size_t i = 0; i < s.returns.size(); ++i) out.mutable_data()[i] = s.returns[i].depth;
        return out;
      }, "(M,) float64 depths (m) along the left optical axis, same order as uv.")
      .def_property_readonly("index", [](const l::ScanProjection& s) {
        py::array_t<std::int64_t> out(static_cast<py::ssize_t>(s.returns.size()));
        for (std::size_t i = 0; i < s.returns.size(); ++i) out.mutable_data()[i] = s.returns[i].index;
        return out;
      }, "(M,) int64 row of each kept return in the input scan.");

  m.def("project_scan", &project, "points_c"_a, "camera"_a, "mask"_a = py::none(),
        "options"_a = py::none(), R"doc(Project a scan into the left image of ``camera``.

Parameters
----------
points_c : (N, 3) or (N, >=3) array
    Points in the rectified reference camera frame c (``Frame.points_c``; columns past the
    third, e.g. intensity, are ignored). NaN / Inf rows are dropped and counted.
camera : StereoCamera
    Needs its image size (width, height > 0).
mask : (H, W) bool or uint8, optional
    0 / False = a-priori dynamic class: returns on those pixels are never used (eq. 3).
options : dict, optional
    LiDAR depth options (see ``default_options``); keyword arguments override it.

Returns
-------
ScanProjection

Raises
------
ValueError
    Wrong shape / dtype, a camera without image size, unknown or out-of-range options.
)doc");
  m.def("lidar_depth_at", &depth_at, "keypoints"_a, "scan"_a, "options"_a = py::none(),
        R"doc(LiDAR depth of left-image keypoints from a local plane of the nearby returns.

Parameters
----------
keypoints : (K, 2) array
    Pixels (u, v) of the left image.
scan : ScanProjection
    From ``project_scan`` (pass the same options).
options : dict, optional
    LiDAR depth options; keyword arguments override it.

Returns
-------
dict
    ``depth`` (K,) float64 m along the left optical axis, NaN where invalid; ``valid`` (K,)
    bool; ``num_returns`` (K,) int32 returns within the radius; ``status`` (K,) uint8 (names
    in ``STATUS_NAMES``); ``rms_relative`` (K,) float64 relative RMS of the accepted fit.
)doc");
  m.def("correct_kitti_scan", &correct_scan, "points_velo"_a,
        "angle_deg"_a = l::kKittiVerticalAngleOffsetDeg,
        R"doc(Correct KITTI's HDL-64 vertical-angle error: rotate each point up by ``angle_deg``.

Parameters
----------
points_velo : (N, 3) or (N, >=3) array
    Raw Velodyne points (x forward, y left, z up); extra columns (intensity) are copied.
angle_deg : float
    Upward rotation about the axis p x z (default 0.205 deg, as KISS-ICP's KITTI reader).

Returns
-------
(N, C) float64 array, range and azimuth of every point kept.
)doc");
  m.def("scan_to_camera", &scan_to_camera, "points_velo"_a, "T_c_velo"_a, "angle_deg"_a = 0.0,
        R"doc(A KITTI scan corrected (``angle_deg``, as :func:`correct_kitti_scan`) and moved into
the camera frame, in one pass (what the dataset readers do with every scan).

Parameters
----------
points_velo : (N, C >= 3) array
    Velodyne points (x forward, y left, z up), converted to float32; extra columns
    (intensity) are carried along.
T_c_velo : (4, 4) array
    Velodyne -> rectified camera frame (``R_rect @ Tr_velo_cam``).
angle_deg : float
    Upward elevation correction (0: none, the simulator's exact scans).

Returns
-------
(points_velo, points_c): two (N, C) float32 arrays, the corrected scan and the same rows with
(x, y, z) = ``T_c_velo`` X.

Raises
------
ValueError
    On fewer than 3 columns, a non-finite angle or transform.
)doc");
  m.def("estimate_disparity_offset", &disparity_offset, "disparities"_a, "lidar_depths"_a,
        "fx_baseline"_a, "min_samples"_a = l::DisparityOffsetOptions{}.min_samples,
        "max_abs_residual_px"_a = l::DisparityOffsetOptions{}.max_abs_residual_px,
        R"doc(Median offset (px) between LiDAR-implied and measured stereo disparities.

Parameters
----------
disparities : (K,) array
    Measured u_left - u_right (px). Pairs with NaN / non-positive values are skipped.
lidar_depths : (K,) array
    LiDAR depth (m) of the same keypoints (NaN = none).
fx_baseline : float
    fx * baseline (px m).
min_samples : int
    Usable pairs needed for a valid estimate.
max_abs_residual_px : float
    Residuals fx b / z - d beyond this (px) are mismatches, left out.

Returns
-------
dict
    ``valid``, ``offset_px`` (median of fx b / z - d; 0 if not valid), ``mad_px``,
    ``num_samples``. Stereo depth with the offset: Z = fx b / (d + offset_px).
)doc");
  m.def("default_options", [] {
    l::LidarDepthOptions o;
    return dump_section(depth_fields(&o));
  }, "Every LiDAR depth option with its default value (units in docs/lidar.md).");
  m.attr("STATUS_NAMES") = status_names();
}

}  // namespace twistslam::bindings
