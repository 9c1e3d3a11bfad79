// Bindings of cpp/features (filled by the features module).
#include "bindings/numpy_checks.hpp"

namespace twistslam::bindings {
void bind_features(py::module_& m) { (void)m; }
}  // namespace twistslam::bindings
