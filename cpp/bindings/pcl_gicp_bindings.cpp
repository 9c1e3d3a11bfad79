// PCL's GeneralizedIterativeClosestPoint behind one function, for benchmarks/bench_gicp.py only
// (the peer row beside ours in the same process). PCL headers stay in this file: they are slow
// to compile and nothing else needs them.
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>

#include "bindings/numpy_checks.hpp"

namespace twistslam::bindings {
using namespace pybind11::literals;

namespace {

pcl::PointCloud<pcl::PointXYZ>::Ptr to_cloud(const DoubleArray& a) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  const auto view = points_view(a);
  cloud->reserve(view.rows());
  for (Eigen::Index i = 0; i < view.rows(); ++i)
    if (view.row(i).allFinite())
      cloud->push_back(pcl::PointXYZ(static_cast<float>(view(i, 0)),
                                     static_cast<float>(view(i, 1)),
                                     static_cast<float>(view(i, 2))));
  return cloud;
}

py::tuple pcl_gicp(const py::handle& source, const py::handle& target, const py::object& T_init,
                   double max_correspondence_distance_m, int max_iterations, int num_neighbors,
                   double transformation_epsilon, double rotation_epsilon) {
  const DoubleArray s = as_rows(source, "source", 3);
  const DoubleArray t = as_rows(target, "target", 3);
  const Mat4 T0 = T_init.is_none() ? Mat4::Identity() : as_rigid_transform(T_init, "T_init");
  Mat4 T = T0;
  bool converged = false;
  {
    py::gil_scoped_release release;
    const auto source_cloud = to_cloud(s);
    const auto target_cloud = to_cloud(t);
    if (static_cast<int>(source_cloud->size()) > num_neighbors &&
        static_cast<int>(target_cloud->size()) > num_neighbors) {
      pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> reg;
      reg.setInputSource(source_cloud);
      reg.setInputTarget(target_cloud);
      reg.setMaxCorrespondenceDistance(max_correspondence_distance_m);
      reg.setMaximumIterations(max_iterations);
      reg.setCorrespondenceRandomness(num_neighbors);
      reg.setTransformationEpsilon(transformation_epsilon);
      reg.setRotationEpsilon(rotation_epsilon);
      pcl::PointCloud<pcl::PointXYZ> aligned;
      reg.align(aligned, T0.cast<float>());
      converged = reg.hasConverged();
      T = reg.getFinalTransformation().cast<double>();
    }
  }
  return py::make_tuple(to_numpy(T), converged);
}

}  // namespace

void bind_pcl_gicp(py::module_& m) {
  m.def("_pcl_gicp", &pcl_gicp, "source"_a, "target"_a, "T_init"_a = py::none(),
        "max_correspondence_distance_m"_a = 1.0, "max_iterations"_a = 30, "num_neighbors"_a = 20,
        "transformation_epsilon"_a = 1e-3, "rotation_epsilon"_a = 1e-3, R"doc(
PCL's generalized ICP (pcl::GeneralizedIterativeClosestPoint, float points), for the bench only.

Parameters
----------
source, target : (N, 3) arrays
    Point clouds (m); NaN rows dropped.
T_init : (4, 4) array or None
    Initial guess of T_target_source.
max_correspondence_distance_m, max_iterations, num_neighbors
    As in our GICP (num_neighbors is PCL's correspondence randomness: k of the covariances).
transformation_epsilon, rotation_epsilon
    PCL's convergence thresholds: the largest change of a translation entry (m) and of a
    rotation matrix entry (~rad) between iterations.

Returns
-------
tuple
    ((4, 4) T_target_source, converged).
)doc");
}

}  // namespace twistslam::bindings
