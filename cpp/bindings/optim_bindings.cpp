// Bindings of cpp/optim (filled by the optim module).
#include "bindings/numpy_checks.hpp"

namespace twistslam::bindings {
void bind_optim(py::module_& m) { (void)m; }
}  // namespace twistslam::bindings
