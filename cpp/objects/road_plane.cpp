#include "objects/road_plane.hpp"

#include <cmath>
#include <stdexcept>

namespace twistslam::objects {

RoadPlaneEstimator::RoadPlaneEstimator(const RoadPlaneOptions& options)
    : options_(options), rng_(options.reservoir_seed) {
  const auto& o = options_;
  if (!o.prior_up.allFinite() || o.prior_up.norm() < 1e-9 || !std::isfinite(o.prior_height) ||
      o.max_points < 3 || o.min_points < 3 || o.min_inliers < 3 || !(o.min_inlier_ratio >= 0) ||
      !(o.refit_growth >= 0) || !(o.max_angle_from_prior_deg > 0) || !(o.fit.inlier_threshold > 0) ||
      o.fit.iterations < 1)
    throw std::invalid_argument("RoadPlaneOptions: finite non-zero prior_up, counts >= 3, thresholds > 0");
  options_.prior_up.normalize();
  reservoir_.resize(options_.max_points, 3);
  plane_ = prior_plane();
}

Vec4 RoadPlaneEstimator::prior_plane() const {
  const Vec3& n = options_.prior_up;  // the road is prior_height below the origin: n.X = -h
  return Vec4(n.x(), n.y(), n.z(), options_.prior_height);
}

void RoadPlaneEstimator::add_points(const Points3& points_w) {
  const Eigen::Index cap = options_.max_points;
  for (Eigen::Index i = 0; i < points_w.rows(); ++i) {
    if (!points_w.row(i).allFinite()) continue;
    ++seen_;
    if (count_ < cap) {  // fill first, then reservoir sampling (algorithm R)
      reservoir_.row(count_++) = points_w.row(i);
    } else {
      const std::int64_t k = std::uniform_int_distribution<std::int64_t>(0, seen_ - 1)(rng_);
      if (k < cap) reservoir_.row(k) = points_w.row(i);
    }
  }
  const bool grown = seen_ >= seen_at_last_fit_ * (1.0 + options_.refit_growth) &&
                     seen_ > seen_at_last_fit_;
  if (count_ >= options_.min_points && (num_fits_ == 0 || grown)) refit();
}

void RoadPlaneEstimator::refit() {
  valid_ = false;
  plane_ = prior_plane();
  last_inliers_ = 0;
  if (count_ < options_.min_points) return;
  ++num_fits_;
  seen_at_last_fit_ = seen_;
  const Points3 points = reservoir_.topRows(count_);
  const geometry::PlaneFit fit = geometry::fit_plane_ransac(points, options_.fit);
  last_inliers_ = fit.num_inliers;
  if (fit.num_inliers < options_.min_inliers ||
      fit.num_inliers < options_.min_inlier_ratio * count_)
    return;
  Vec4 p = fit.plane;
  if (p.head<3>().dot(options_.prior_up) < 0) p = -p;  // orient the normal up
  const double cos_angle = p.head<3>().dot(options_.prior_up);
  if (cos_angle < std::cos(options_.max_angle_from_prior_deg * M_PI / 180.0)) return;
  plane_ = p;
  valid_ = true;
}

}  // namespace twistslam::objects
