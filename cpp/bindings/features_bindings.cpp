// Bindings of cpp/features: ORB extraction with grid bucketing and stereo matching.
// Images cross the boundary without a copy (uint8 arrays wrapped as cv::Mat); the GIL is
// released while C++ works on them.
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "bindings/numpy_checks.hpp"
#include "bindings/options_table.hpp"
#include "features/orb.hpp"
#include "features/stereo.hpp"
#include "features/stereo_option_ranges.hpp"
#include "geometry/stereo_camera.hpp"

namespace twistslam::bindings {
namespace f = twistslam::features;
namespace g = twistslam::geometry;
using namespace pybind11::literals;

namespace {

// A cv::Mat view of a numpy image plus the array that owns its memory.
struct ImageView {
  py::array owner;
  cv::Mat mat;
  bool color = false;  // (H, W, 3), RGB as twistslam's datasets deliver it
};

std::string dtype_and_shape(const py::array& a) {
  return std::string(py::str(a.dtype())) + " " + shape_string(a);
}

ImageView wrap_image(const py::handle& obj, const char* name) {
  const std::string want = std::string(name) + ": expected uint8 (H, W) or (H, W, 3), got ";
  if (obj.is_none()) throw py::value_error(want + "None");
  py::array arr = py::array::ensure(obj);
  if (!arr) throw py::value_error(want + std::string(py::str(py::type::of(obj))));
  const bool u8 = arr.dtype().kind() == 'u' && arr.dtype().itemsize() == 1;
  const bool shape_ok = arr.ndim() == 2 || (arr.ndim() == 3 && arr.shape(2) == 3);
  if (!u8 || !shape_ok) throw py::value_error(want + dtype_and_shape(arr));
  if (arr.shape(0) == 0 || arr.shape(1) == 0)
    throw py::value_error(std::string(name) + ": empty image " + shape_string(arr));
  const bool color = arr.ndim() == 3;
  const py::ssize_t px = color ? 3 : 1;
  // Rows may be padded (any positive row stride); pixels inside a row must be packed.
  const bool packed = arr.strides(1) == px && (!color || arr.strides(2) == 1) &&
                      arr.strides(0) >= arr.shape(1) * px;
  if (!packed) arr = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(arr);
  ImageView v;
  v.owner = arr;
  v.color = color;
  v.mat = cv::Mat(static_cast<int>(arr.shape(0)), static_cast<int>(arr.shape(1)),
                  color ? CV_8UC3 : CV_8UC1, const_cast<void*>(arr.data()),
                  static_cast<std::size_t>(arr.strides(0)));
  return v;
}

// Optional (H, W) bool / uint8 mask of the image size; nonzero = keypoints allowed.
ImageView wrap_mask(const py::handle& obj, const cv::Size& size) {
  ImageView v;
  if (obj.is_none()) return v;
  py::array arr = py::array::ensure(obj);
  const std::string expected = "mask: expected bool or uint8 (" + std::to_string(size.height) +
                               ", " + std::to_string(size.width) + "), got ";
  if (!arr) throw py::value_error(expected + std::string(py::str(py::type::of(obj))));
  const char kind = arr.dtype().kind();
  const bool ok_dtype = (kind == 'b' || kind == 'u') && arr.dtype().itemsize() == 1;
  if (!ok_dtype || arr.ndim() != 2 || arr.shape(0) != size.height || arr.shape(1) != size.width)
    throw py::value_error(expected + dtype_and_shape(arr));
  if (kind == 'b') arr = py::array::ensure(arr.attr("view")("uint8"));  // same bytes, 0 / 1
  arr = py::array_t<std::uint8_t, py::array::c_style>::ensure(arr);
  v.owner = arr;
  v.mat = cv::Mat(size, CV_8UC1, const_cast<void*>(arr.data()));
  return v;
}

// Applies `options` (a dict or None) then `kwargs` to the ORB (and stereo) options, through
// the tables of options_table.hpp: ranges from for_each_option, ValueError for an unknown
// dict key or a value out of range, TypeError for an unknown keyword or a wrong type.
void apply_options(const char* fn, const py::object& options, const py::kwargs& kwargs,
                   f::OrbOptions* orb, f::StereoOptions* stereo) {
  FieldTable fields = field_table(*orb);
  if (stereo) fields.merge(field_table(*stereo));
  if (!options.is_none()) {
    if (!py::isinstance<py::dict>(options))
      throw py::type_error(std::string(fn) + ": options must be a dict or None");
    apply_section(options.cast<py::dict>(), "", fields);
  }
  apply_keywords(kwargs, fn, fields);
  try {
    f::check_options(*orb);
    if (stereo && !(stereo->min_depth < stereo->max_depth))
      throw std::invalid_argument("min_depth must be below max_depth");
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string(fn) + ": " + e.what());
  }
}

template <typename T>
py::array_t<T> new_vector(std::size_t n) {
  return py::array_t<T>(static_cast<py::ssize_t>(n));
}

// keypoints (N, 2), octave, angle, response, size, descriptors (N, 32) of a Keypoints.
py::dict keypoints_dict(const f::Keypoints& k) {
  const std::size_t n = k.size();
  DoubleArray uv = new_array({static_cast<py::ssize_t>(n), 2});
  auto octave = new_vector<std::int32_t>(n);
  auto angle = new_vector<double>(n), response = new_vector<double>(n),
       size = new_vector<double>(n);
  py::array_t<std::uint8_t> desc({static_cast<py::ssize_t>(n), py::ssize_t{f::kDescriptorBytes}});
  for (std::size_t i = 0; i < n; ++i) {
    const cv::KeyPoint& p = k.keypoints[i];
    uv.mutable_data()[2 * i] = p.pt.x;
    uv.mutable_data()[2 * i + 1] = p.pt.y;
    octave.mutable_data()[i] = p.octave;
    angle.mutable_data()[i] = p.angle;
    response.mutable_data()[i] = p.response;
    size.mutable_data()[i] = p.size;
    std::memcpy(desc.mutable_data() + i * f::kDescriptorBytes, k.descriptors.ptr(static_cast<int>(i)),
                f::kDescriptorBytes);
  }
  return py::dict("keypoints"_a = uv, "octave"_a = octave, "angle"_a = angle,
                  "response"_a = response, "size"_a = size, "descriptors"_a = desc);
}

py::dict extract_orb(const py::handle& image, const py::object& options, const py::object& mask,
                     const py::kwargs& kwargs) {
  f::OrbOptions orb_options;
  apply_options("extract_orb", options, kwargs, &orb_options, nullptr);
  const ImageView img = wrap_image(image, "image");
  const ImageView m = wrap_mask(mask, img.mat.size());
  f::Keypoints k;
  {
    py::gil_scoped_release release;
    const f::OrbExtractor extractor(orb_options);
    k = extractor.extract(f::to_gray(img.mat, /*rgb=*/true), m.mat);
  }
  return keypoints_dict(k);
}

py::dict match_stereo(const py::handle& image_left, const py::handle& image_right,
                      const g::StereoCamera& camera, const py::object& options,
                      const py::object& mask, const py::kwargs& kwargs) {
  f::OrbOptions orb_options;
  f::StereoOptions stereo_options;
  apply_options("match_stereo", options, kwargs, &orb_options, &stereo_options);
  const ImageView left = wrap_image(image_left, "image_left");
  const ImageView right = wrap_image(image_right, "image_right");
  if (left.mat.size() != right.mat.size())
    throw py::value_error("match_stereo: image_left " + shape_string(left.owner) +
                          " and image_right " + shape_string(right.owner) + " differ in size");
  if (camera.width > 0 && camera.height > 0 &&
      (camera.width != left.mat.cols || camera.height != left.mat.rows))
    throw py::value_error("match_stereo: camera is for " + std::to_string(camera.width) + "x" +
                          std::to_string(camera.height) + " images, got " +
                          std::to_string(left.mat.cols) + "x" + std::to_string(left.mat.rows));
  const ImageView m = wrap_mask(mask, left.mat.size());
  f::StereoFeatures sf;
  {
    py::gil_scoped_release release;
    const f::OrbExtractor extractor(orb_options);
    const cv::Mat gl = f::to_gray(left.mat, true), gr = f::to_gray(right.mat, true);
    sf = f::extract_and_match(extractor, gl, gr, camera, stereo_options, m.mat);
  }
  py::dict out = keypoints_dict(sf.left);
  const std::size_t n = sf.left.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto u_right = new_vector<double>(n), depth = new_vector<double>(n);
  auto matched = new_vector<bool>(n);
  DoubleArray points = new_array({static_cast<py::ssize_t>(n), 3});
  for (std::size_t i = 0; i < n; ++i) {
    const bool ok = sf.matches.depth[i] > 0;
    matched.mutable_data()[i] = ok;
    u_right.mutable_data()[i] = ok ? sf.matches.u_right[i] : nan;
    depth.mutable_data()[i] = ok ? sf.matches.depth[i] : nan;
    Vec3 X = Vec3::Constant(nan);
    if (ok) {
      const cv::Point2f& p = sf.left.keypoints[i].pt;
      X = camera.triangulate(Vec2(p.x, p.y), p.x - sf.matches.u_right[i]);
    }
    for (int c = 0; c < 3; ++c) points.mutable_data()[3 * i + c] = X[c];
  }
  out["u_right"] = u_right;
  out["depth"] = depth;
  out["points_c"] = points;
  out["matched"] = matched;
  out["num_right_keypoints"] = sf.right.size();
  out["extract_ms"] = sf.extract_ms;
  out["match_ms"] = sf.match_ms;
  return out;
}

// The default ORB and stereo options in one field table (the tables' fields point into them).
struct DefaultOptions {
  f::OrbOptions orb;
  f::StereoOptions stereo;
  FieldTable fields() {
    FieldTable table = field_table(orb);
    table.merge(field_table(stereo));
    return table;
  }
};

py::dict default_options() {
  DefaultOptions defaults;
  py::dict out = dump_section(defaults.fields());
  // float fields as the decimal they were written as (1.2, not 1.2000000476837158)
  for (const auto& item : out)
    if (py::isinstance<py::float_>(item.second))
      out[item.first] = std::stod(std::to_string(item.second.cast<float>()));
  return out;
}

py::dict option_ranges() {
  DefaultOptions defaults;
  return dump_ranges(defaults.fields());
}

py::array_t<std::int32_t> hamming_distance(const py::handle& a_obj, const py::handle& b_obj) {
  auto rows = [](const py::handle& obj, const char* name) {
    py::array arr = py::array::ensure(obj);
    if (!arr || arr.dtype().kind() != 'u' || arr.dtype().itemsize() != 1 || arr.ndim() != 2 ||
        arr.shape(1) != f::kDescriptorBytes)
      throw py::value_error(std::string(name) + ": expected uint8 (N, 32), got " +
                            (arr ? dtype_and_shape(arr) : std::string("a non-array")));
    return py::array_t<std::uint8_t, py::array::c_style>::ensure(arr);
  };
  const auto a = rows(a_obj, "a"), b = rows(b_obj, "b");
  py::array_t<std::int32_t> out({a.shape(0), b.shape(0)});
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < a.shape(0); ++i)
      for (py::ssize_t j = 0; j < b.shape(0); ++j)
        out.mutable_data()[i * b.shape(0) + j] = f::descriptor_distance(
            a.data() + i * f::kDescriptorBytes, b.data() + j * f::kDescriptorBytes);
  }
  return out;
}

}  // namespace

void bind_features(py::module_& m) {
  m.def("extract_orb", &extract_orb, "image"_a, "options"_a = py::none(), "mask"_a = py::none(),
        R"doc(ORB keypoints spread over the image (scale pyramid, grid bucketing, quadtree).

Parameters
----------
image : (H, W) or (H, W, 3) uint8 ndarray
    Grey or RGB image (RGB as twistslam's datasets load it). Wrapped without a copy when the
    pixels of each row are packed.
options : dict, optional
    ORB options (see ``default_options()``): num_features (2000), scale_factor (1.2),
    num_levels (4), fast_threshold (20), min_fast_threshold (7), cell_size (35 px).
mask : (H, W) bool or uint8 ndarray, optional
    Zero / False where no keypoint may lie (e.g. a priori dynamic classes).
**kwargs
    The same options as keywords; they override ``options``.

Returns
-------
dict
    keypoints : (N, 2) float64, level-0 pixel (u, v) with pixel centres at integers
    octave : (N,) int32, pyramid level
    angle : (N,) float64, orientation in degrees [0, 360)
    response : (N,) float64, FAST score
    size : (N,) float64, 31 * scale_factor**octave (px)
    descriptors : (N, 32) uint8, rotated BRIEF

Raises
------
ValueError
    If the image is not uint8 (H, W) / (H, W, 3), is empty, the mask does not match, or an
    option key of ``options`` is unknown or a value out of range (see ``option_ranges``).
    A blank image gives N = 0.
TypeError
    An unknown keyword, or an option value of the wrong type (a float for an integer).
)doc");

  m.def("match_stereo", &match_stereo, "image_left"_a, "image_right"_a, "camera"_a,
        "options"_a = py::none(), "mask"_a = py::none(),
        R"doc(ORB keypoints of the left image with their stereo match, depth and 3D point.

Both images are processed in parallel, then each left keypoint is matched along its row in
the right image (Hamming distance), refined to sub-pixel by zero-mean SAD on its pyramid level
(right rows sampled at the vertical offset the camera pair predicts) and kept if its SAD is
not far above the frame's median.

Parameters
----------
image_left, image_right : (H, W) or (H, W, 3) uint8 ndarray
    Rectified left (camera 2) and right (camera 3) images of the same size, grey or RGB.
camera : twistslam.geometry.StereoCamera
    The rectified pair (``StereoCamera.from_kitti(P2, P3, W, H)``); its size, if set, must
    match the images.
options : dict, optional
    ORB options (see ``extract_orb``) and stereo options: max_hamming (75),
    row_radius (2 px), octave_tolerance (1), patch_radius (7 px, SAD half width),
    patch_half_height (2 px), refine_range (5 px),
    min_depth (0.5 m), max_depth (80 m), outlier_factor (2.1),
    right_features_factor (2: the right image gets twice as many keypoints as candidates).
mask : (H, W) bool or uint8 ndarray, optional
    Zero / False where no left keypoint may lie.
**kwargs
    The same options as keywords; they override ``options``.

Returns
-------
dict
    keypoints, octave, angle, response, size, descriptors : as ``extract_orb`` (left image)
    u_right : (N,) float64, column of the match in the right image, NaN if unmatched
    depth : (N,) float64, metres along the left optical axis (fx b / disparity), NaN if unmatched
    points_c : (N, 3) float64, points in the reference camera frame c, NaN rows if unmatched
    matched : (N,) bool
    num_right_keypoints : int
    extract_ms, match_ms : float, wall time of the two stages

Raises
------
ValueError
    On a bad image (dtype, shape, empty), images of different sizes, a camera of another
    image size, a bad mask, or an unknown ``options`` key or out-of-range value.
TypeError
    An unknown keyword, a camera that is not a StereoCamera, an option of the wrong type.
)doc");

  m.def("default_options", &default_options,
        R"doc(Default ORB and stereo options.

Returns
-------
dict
    Every option ``extract_orb`` and ``match_stereo`` accept, with its default value.
)doc");

  m.def("option_ranges", &option_ranges,
        R"doc(Valid range of every ORB and stereo option.

Returns
-------
dict
    ``{key: (lo, hi)}``, inclusive, in each option's unit; ``match_stereo`` also needs
    ``min_depth < max_depth`` and ``extract_orb`` ``min_fast_threshold <= fast_threshold``.
)doc");

  m.def("hamming_distance", &hamming_distance, "a"_a, "b"_a,
        R"doc(Hamming distances between two sets of ORB descriptors.

Parameters
----------
a : (N, 32) uint8 ndarray
b : (M, 32) uint8 ndarray

Returns
-------
(N, M) int32 ndarray
    Number of differing bits (0..256).
)doc");
}

}  // namespace twistslam::bindings
