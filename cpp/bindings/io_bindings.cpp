// Bindings of cpp/io: image files decoded in C++, the GIL released while they decode.
#include <pybind11/numpy.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include "bindings/numpy_checks.hpp"
#include "io/png_file.hpp"

namespace twistslam::bindings {

namespace {

py::array_t<std::uint8_t> read_png_rgb8(const std::string& path) {
  cv::Mat rgb;
  {
    py::gil_scoped_release release;
    try {
      rgb = io::read_png_rgb8(path);
    } catch (const std::runtime_error& e) {
      py::gil_scoped_acquire acquire;
      throw py::value_error(e.what());
    }
  }
  py::array_t<std::uint8_t> out({rgb.rows, rgb.cols, 3});
  for (int r = 0; r < rgb.rows; ++r)  // rows of a fresh cv::Mat are contiguous; copy row-wise anyway
    std::memcpy(out.mutable_data(r), rgb.ptr<std::uint8_t>(r), static_cast<size_t>(rgb.cols) * 3);
  return out;
}

}  // namespace

void bind_io(py::module_& m) {
  m.def("read_png_rgb8", &read_png_rgb8, py::arg("path"),
        R"doc(Decode an 8-bit colour PNG file with OpenCV (libpng), without the GIL.

Parameters
----------
path : str
    The file.

Returns
-------
numpy.ndarray
    (H, W, 3) uint8, RGB.

Raises
------
ValueError
    Naming the file, when it cannot be read or decoded or is not 8-bit colour. Use
    ``twistslam.datasets.read_image``, which checks the header first (size limit, kind).
)doc");
}

}  // namespace twistslam::bindings
