#include "bindings/detection_arrays.hpp"

#include <cstdint>
#include <string>

namespace twistslam::bindings {

namespace {
using BoolArray = py::array_t<bool, py::array::c_style | py::array::forcecast>;

// flags (N,) bool, or an empty array for None; TypeError / ValueError naming `name`
BoolArray optional_flags(const py::handle& flags, const char* name, py::ssize_t n) {
  if (flags.is_none()) return BoolArray();
  // booleans only: a cast would read any non-empty string or non-zero number as true
  const py::array raw = py::array::ensure(flags);
  if (!raw || raw.dtype().kind() != 'b')
    throw py::type_error(std::string(name) + ": expected a boolean array, got " +
                         (raw ? std::string(py::str(raw.dtype())) : std::string("no array")));
  BoolArray out = BoolArray::ensure(raw);
  if (out.ndim() != 1 || out.shape(0) != n)
    throw py::value_error(std::string(name) + ": expected (" + std::to_string(n) +
                          ",) like boxes, got " + shape_string(out));
  return out;
}
}  // namespace

std::vector<objects::Detection> detections_from_arrays(const py::handle& boxes,
                                                       const py::handle& scores,
                                                       const py::handle& class_ids,
                                                       const py::handle& planar,
                                                       const py::handle& open_ends,
                                                       const py::handle& point_extents,
                                                       const py::handle& headings_known) {
  const DoubleArray b = as_rows(boxes, "boxes", 7);
  const auto n = b.shape(0);
  const DoubleArray s = as_double_array(scores, "scores");
  const auto c = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(class_ids);
  if (!c) throw py::type_error("class_ids: expected an integer array");
  py::array_t<bool, py::array::c_style | py::array::forcecast> p;
  if (!planar.is_none()) {
    p = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(planar);
    if (!p) throw py::type_error("planar: expected a boolean array");
    if (p.ndim() != 1 || p.shape(0) != n)
      throw py::value_error("planar: expected (" + std::to_string(n) + ",) like boxes, got " +
                            shape_string(p));
  }
  if (s.ndim() != 1 || s.shape(0) != n || c.ndim() != 1 || c.shape(0) != n)
    throw py::value_error("scores, class_ids: expected (" + std::to_string(n) +
                          ",) arrays like boxes, got " + shape_string(s) + ", " + shape_string(c));
  py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> ends;
  if (!open_ends.is_none()) {
    ends = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(open_ends);
    if (!ends) throw py::type_error("open_ends: expected an integer array");
    if (ends.ndim() != 1 || ends.shape(0) != n)
      throw py::value_error("open_ends: expected (" + std::to_string(n) + ",) like boxes, got " +
                            shape_string(ends));
  }
  const BoolArray extents = optional_flags(point_extents, "point_extents", n);
  const BoolArray known = optional_flags(headings_known, "headings_known", n);
  std::vector<objects::Detection> dets(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    dets[i].box = geometry::Box3D::from_row(b.data() + 7 * i);
    dets[i].score = s.data()[i];
    dets[i].class_id = static_cast<int>(c.data()[i]);
    dets[i].planar = planar.is_none() ? true : p.data()[i];
    dets[i].point_extent = point_extents.is_none() ? false : extents.data()[i];
    // without the flags, a box knows its heading unless it is a point extent (mod pi)
    dets[i].heading_known = headings_known.is_none() ? !dets[i].point_extent : known.data()[i];
    if (!open_ends.is_none()) {
      const std::int64_t e = ends.data()[i];
      if (e < -1 || e > 1)
        throw py::value_error("open_ends[" + std::to_string(i) + "]: expected -1, 0 or 1, got " +
                              std::to_string(e));
      dets[i].open_end = static_cast<int>(e);
    }
  }
  return dets;
}

}  // namespace twistslam::bindings
