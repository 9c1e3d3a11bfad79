// Bindings of cpp/perception: dense optical flow with OpenCV DIS. Images are converted to
// C-contiguous uint8 once and wrapped as cv::Mat; the GIL is released while DIS runs.
#include <pybind11/numpy.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include "bindings/numpy_checks.hpp"
#include "perception/dis_flow.hpp"

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
}

}  // namespace twistslam::bindings
