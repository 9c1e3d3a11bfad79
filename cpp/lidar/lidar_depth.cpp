#include "lidar/lidar_depth.hpp"

#include <algorithm>

#include "lidar/inverse_depth_plane.hpp"

namespace twistslam::lidar {

namespace {

// The keypoint is inside the support of `returns` if each of the four image quadrants around
// it holds a return: the plane is then interpolated, never extrapolated past the last scan
// line or the edge of an object.
bool surrounds_keypoint(const std::vector<PixelDepth>& returns) {
  unsigned quadrants = 0;
  for (const PixelDepth& r : returns) quadrants |= (r.du < 0 ? 1u : 2u) << (r.dv < 0 ? 0 : 2);
  return quadrants == 0b1111u;
}

std::vector<PixelDepth> gather(const Vec2& uv, const ScanProjection& scan, double radius) {
  std::vector<PixelDepth> near;
  const double r2 = radius * radius;
  scan.for_each_near(uv.x(), uv.y(), radius, [&](const ProjectedReturn& p) {
    const double du = p.u - uv.x(), dv = p.v - uv.y();
    if (du * du + dv * dv <= r2) near.push_back({du, dv, p.depth});
  });
  return near;
}

LidarDepth accept(const InverseDepthPlane& fit, LidarDepth out, LidarDepthStatus status) {
  out.depth = fit.depth;
  out.rms_relative = fit.rms_relative;
  out.status = status;
  return out;
}

}  // namespace

const char* to_string(LidarDepthStatus status) {
  switch (status) {
    case LidarDepthStatus::kPlane: return "plane";
    case LidarDepthStatus::kForeground: return "foreground";
    case LidarDepthStatus::kTooFewReturns: return "too_few_returns";
    case LidarDepthStatus::kOutsideSupport: return "outside_support";
    case LidarDepthStatus::kDepthEdge: return "depth_edge";
    case LidarDepthStatus::kPoorFit: return "poor_fit";
  }
  return "unknown";
}

LidarDepth lidar_depth_at(const Vec2& uv, const ScanProjection& scan,
                          const LidarDepthOptions& options) {
  LidarDepth out;
  if (!uv.allFinite()) return out;  // kTooFewReturns: nothing can be near a NaN pixel
  std::vector<PixelDepth> returns = gather(uv, scan, options.search_radius_px);
  out.num_returns = static_cast<int>(returns.size());
  const auto min_returns = static_cast<std::size_t>(options.min_returns);
  if (returns.size() < min_returns) return out;
  if (!surrounds_keypoint(returns)) {
    out.status = LidarDepthStatus::kOutsideSupport;
    return out;
  }
  // One surface (including slanted ones such as the road at grazing angles, whose scan lines
  // are 10-30 % apart in depth): the single fit explains every return.
  const InverseDepthPlane all = fit_inverse_depth_plane(returns);
  if (all.ok && all.rms_relative <= options.max_fit_residual)
    return accept(all, out, LidarDepthStatus::kPlane);

  // Otherwise split at the first depth gap: the near layer is everything before it.
  std::sort(returns.begin(), returns.end(),
            [](const PixelDepth& a, const PixelDepth& b) { return a.depth < b.depth; });
  std::size_t near_end = 0;
  for (std::size_t i = 0; i + 1 < returns.size() && near_end == 0; ++i)
    if (returns[i + 1].depth > returns[i].depth * (1.0 + options.layer_gap)) near_end = i + 1;
  out.status = LidarDepthStatus::kPoorFit;
  if (near_end == 0) return out;  // continuous depths, yet not one plane (vegetation, corners)
  returns.resize(near_end);
  if (returns.size() < min_returns || !surrounds_keypoint(returns)) {
    out.status = LidarDepthStatus::kDepthEdge;
    return out;
  }
  const InverseDepthPlane near = fit_inverse_depth_plane(returns);
  if (near.ok && near.rms_relative <= options.max_fit_residual)
    return accept(near, out, LidarDepthStatus::kForeground);
  return out;
}

std::vector<LidarDepth> lidar_depth_at(const std::vector<Vec2>& keypoints,
                                       const ScanProjection& scan,
                                       const LidarDepthOptions& options) {
  validate(options);
  std::vector<LidarDepth> out;
  out.reserve(keypoints.size());
  for (const Vec2& uv : keypoints) out.push_back(lidar_depth_at(uv, scan, options));
  return out;
}

}  // namespace twistslam::lidar
