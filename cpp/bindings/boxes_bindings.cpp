// Bindings of cpp/geometry boxes: corners, projection to the image, 2D / bird-view / 3D IoU.
// Box arrays are (N, 7) rows [cx, cy, cz, l, w, h, ry] in the camera frame (geometric centre).
#include <functional>

#include "bindings/numpy_checks.hpp"
#include "geometry/box3d.hpp"
#include "geometry/box_overlap.hpp"

namespace twistslam::bindings {
namespace g = twistslam::geometry;
using namespace pybind11::literals;

namespace {

std::vector<g::Box3D> boxes_from(const DoubleArray& a) {
  std::vector<g::Box3D> boxes(a.shape(0));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) boxes[i] = g::Box3D::from_row(a.data() + 7 * i);
  return boxes;
}

// (N, M) matrix of a pairwise overlap; the GIL is released for the double loop.
template <typename Item>
DoubleArray pairwise(const std::vector<Item>& a, const std::vector<Item>& b,
                     const std::function<double(const Item&, const Item&)>& f) {
  DoubleArray out = new_array({static_cast<py::ssize_t>(a.size()), static_cast<py::ssize_t>(b.size())});
  double* dst = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (size_t i = 0; i < a.size(); ++i)
      for (size_t j = 0; j < b.size(); ++j) dst[i * b.size() + j] = f(a[i], b[j]);
  }
  return out;
}

constexpr const char* kIouDoc = R"doc(Pairwise IoU matrix.

Parameters
----------
boxes_a : (N, {cols}) array_like
boxes_b : (M, {cols}) array_like

Returns
-------
(N, M) ndarray
    IoU in [0, 1]; 0 for degenerate boxes.
)doc";

std::string iou_doc(const char* what, int cols) {
  std::string doc = std::string(what) + "\n\n" + kIouDoc;
  const std::string key = "{cols}";
  for (size_t p; (p = doc.find(key)) != std::string::npos;) doc.replace(p, key.size(), std::to_string(cols));
  return doc;
}

}  // namespace

void bind_boxes(py::module_& m) {
  m.def("box_corners",
        [](py::handle boxes) {
          const DoubleArray a = as_rows(boxes, "boxes", 7);
          DoubleArray out = new_array({a.shape(0), 8, 3});
          const auto bs = boxes_from(a);
          for (size_t i = 0; i < bs.size(); ++i) {
            const auto c = bs[i].corners();
            for (int k = 0; k < 8; ++k)
              for (int d = 0; d < 3; ++d) out.mutable_data()[(i * 8 + k) * 3 + d] = c[k][d];
          }
          return out;
        },
        "boxes"_a, R"doc(Corners of oriented boxes.

Parameters
----------
boxes : (N, 7) array_like
    Rows [cx, cy, cz, l, w, h, ry], geometric centre in the camera frame.

Returns
-------
(N, 8, 3) ndarray
    Corners 0-3 on the bottom face (larger y), 4-7 on the top face.
)doc");
  m.def("project_boxes",
        [](py::handle boxes, py::handle P, int width, int height) {
          const DoubleArray a = as_rows(boxes, "boxes", 7);
          const Mat34 proj = as_mat34(P, "P");
          DoubleArray out = new_array({a.shape(0), 4});
          const auto bs = boxes_from(a);
          for (size_t i = 0; i < bs.size(); ++i) {
            const Vec4 r = g::project_box(bs[i], proj, width, height);
            for (int k = 0; k < 4; ++k) out.mutable_data()[4 * i + k] = r[k];
          }
          return out;
        },
        "boxes"_a, "P"_a, "width"_a = 0, "height"_a = 0, R"doc(Image boxes of projected 3D boxes.

Parameters
----------
boxes : (N, 7) array_like
P : (3, 4) array_like
    Projection matrix of the image (KITTI P2 for the left colour camera).
width, height : int
    Image size; when both > 0 the boxes are clipped to the image.

Returns
-------
(N, 4) ndarray
    [x1, y1, x2, y2] bounds of the projected corners (edges cut at z = 0.1 m);
    NaN rows for boxes entirely behind the camera.
)doc");
  m.def("box_iou_2d",
        [](py::handle a, py::handle b) {
          const DoubleArray A = as_rows(a, "boxes_a", 4), B = as_rows(b, "boxes_b", 4);
          std::vector<Vec4> va(A.shape(0)), vb(B.shape(0));
          for (size_t i = 0; i < va.size(); ++i) va[i] = Eigen::Map<const Vec4>(A.data() + 4 * i);
          for (size_t i = 0; i < vb.size(); ++i) vb[i] = Eigen::Map<const Vec4>(B.data() + 4 * i);
          return pairwise<Vec4>(va, vb, &g::iou_2d);
        },
        "boxes_a"_a, "boxes_b"_a, iou_doc("IoU of image boxes [x1, y1, x2, y2].", 4).c_str());
  m.def("box_iou_bev",
        [](py::handle a, py::handle b) {
          return pairwise<g::Box3D>(boxes_from(as_rows(a, "boxes_a", 7)),
                                    boxes_from(as_rows(b, "boxes_b", 7)), &g::iou_bev);
        },
        "boxes_a"_a, "boxes_b"_a,
        iou_doc("Bird-view IoU: rotated rectangles in the x-z plane, exact polygon clipping.", 7)
            .c_str());
  m.def("box_iou_3d",
        [](py::handle a, py::handle b) {
          return pairwise<g::Box3D>(boxes_from(as_rows(a, "boxes_a", 7)),
                                    boxes_from(as_rows(b, "boxes_b", 7)), &g::iou_3d);
        },
        "boxes_a"_a, "boxes_b"_a,
        iou_doc("3D IoU: bird-view intersection times the vertical overlap over the union volume.", 7)
            .c_str());
  m.def("box_giou_bev",
        [](py::handle a, py::handle b) {
          return pairwise<g::Box3D>(boxes_from(as_rows(a, "boxes_a", 7)),
                                    boxes_from(as_rows(b, "boxes_b", 7)), &g::giou_bev);
        },
        "boxes_a"_a, "boxes_b"_a,
        "Bird-view generalized IoU: IoU - (hull - union) / hull, the hull being the convex hull\n"
        "of both rectangles. (N, M) values in [-1, 1]; -1 for degenerate boxes.");
  m.def("box_giou_3d",
        [](py::handle a, py::handle b) {
          return pairwise<g::Box3D>(boxes_from(as_rows(a, "boxes_a", 7)),
                                    boxes_from(as_rows(b, "boxes_b", 7)), &g::giou_3d);
        },
        "boxes_a"_a, "boxes_b"_a,
        "3D generalized IoU: the bird-view hull times the union of the vertical extents encloses\n"
        "both boxes. (N, M) values in [-1, 1]; -1 for degenerate boxes (the association cost of\n"
        "the object tracker is 1 - GIoU).");
}

}  // namespace twistslam::bindings
