#include "objects/road_plane.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace twistslam::objects {

RoadPlaneEstimator::RoadPlaneEstimator(const RoadPlaneOptions& options)
    : options_(options), rng_(options.reservoir_seed) {
  const auto& o = options_;
  if (!o.prior_up.allFinite() || o.prior_up.norm() < 1e-9 || !std::isfinite(o.prior_height) ||
      o.max_points < 3 || o.min_points < 3 || o.min_inliers < 3 || !(o.min_inlier_ratio >= 0) ||
      !(o.refit_growth >= 0) || !(o.max_angle_from_prior_deg > 0) || !(o.fit.inlier_threshold > 0) ||
      o.fit.iterations < 1 || !(o.window_m >= 0))
    throw std::invalid_argument("RoadPlaneOptions: finite non-zero prior_up, counts >= 3, thresholds > 0, "
                                "window_m >= 0");
  options_.prior_up.normalize();
  reservoir_.resize(options_.max_points, 3);
  plane_ = prior_plane();
}

Vec4 RoadPlaneEstimator::prior_plane() const {
  const Vec3& n = options_.prior_up;  // the road is prior_height below the origin: n.X = -h
  return Vec4(n.x(), n.y(), n.z(), options_.prior_height);
}

void RoadPlaneEstimator::add_to_window(const Points3& points_w, const Vec3& camera_w) {
  if (!camera_w.allFinite()) throw std::invalid_argument("RoadPlaneEstimator: non-finite camera position");
  Batch batch{Points3(points_w.rows(), 3), camera_w};
  Eigen::Index n = 0;
  for (Eigen::Index i = 0; i < points_w.rows(); ++i)
    if (points_w.row(i).allFinite()) batch.points_w.row(n++) = points_w.row(i);
  seen_ += n;
  batch.points_w.conservativeResize(n, 3);
  window_.push_back(std::move(batch));
  while ((window_.front().camera_w - camera_w).norm() > options_.window_m) window_.pop_front();
  // the most recent max_points rows, newest batch first; older batches are dropped (a long
  // window over a slow drive would otherwise keep every keyframe's points)
  count_ = 0;
  std::size_t used = 0;
  for (auto b = window_.rbegin(); b != window_.rend() && count_ < options_.max_points; ++b, ++used) {
    const Eigen::Index take = std::min<Eigen::Index>(b->points_w.rows(), options_.max_points - count_);
    reservoir_.middleRows(count_, take) = b->points_w.bottomRows(take);
    count_ += take;
  }
  while (window_.size() > used) window_.pop_front();
  if (count_ >= options_.min_points) refit();
}

void RoadPlaneEstimator::add_points(const Points3& points_w, const Vec3& camera_w) {
  if (options_.window_m > 0) return add_to_window(points_w, camera_w);
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
