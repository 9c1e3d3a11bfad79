#pragma once
// Mechanical-link projection operators Pi (TwistSLAM, docs/design.md "Mechanical link"):
// 6x6 projectors onto the twist sub-space a link allows. The object update is
// T_w_o(i+1) = exp(Pi xi) T_w_o(i) (paper eq. 2 and eq. 4).
#include "geometry/types.hpp"

namespace twistslam::geometry {

enum class LinkType { kFree, kPlanar };

// No constraint: Pi = I (6 DoF).
Mat6 projector_free();

// Object moving on a plane with unit normal n (world frame): translation keeps only its
// in-plane part, rotation only its part about n, Pi = blockdiag(I - n n^T, n n^T) (3 DoF).
// Throws std::invalid_argument for a zero or non-finite normal.
Mat6 projector_planar(const Vec3& normal);

// Number of degrees of freedom a projector keeps (its trace, as Pi is an orthogonal projector).
int projector_dof(const Mat6& Pi);

}  // namespace twistslam::geometry
