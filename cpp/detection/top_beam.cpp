#include "detection/top_beam.hpp"

#include <cmath>
#include <limits>
#include <algorithm>
#include <random>
#include <tuple>
#include <unordered_map>
#include <vector>

#include <Eigen/Dense>

namespace twistslam::detection {

namespace {
// m, ranges the envelope is taken over: nearer, the beam is above most objects' tops and few
// returns reach it; farther, it passes over buildings more often than it hits them.
constexpr double kMinRangeM = 6.0, kMaxRangeM = 40.0;
// Envelope bins: 2 m of range x 10 deg of azimuth (17 x 9-12 bins in the camera's field; 25-51
// of them were on the beam in real 0001 and the object frames).
constexpr double kRangeBinM = 2.0, kAzimuthBinDeg = 10.0;
// m above the camera centre: lower returns are not binned (no hypot / atan2 for the road and
// most of the cars). A valid beam is 0.3 m or more above the camera 20 m ahead (below), and
// the fitted ones 0.23-0.45 m up 6 m ahead: a return under -0.3 m cannot be on one.
constexpr double kMinUpM = -0.3;
// m, a bin on the beam: its highest return within this of the cone. The fitted beam's
// residual is 0.3-0.8 mm on real and simulated scans (7.6 mm on one real object frame); with
// 0.05 a wrong cone through the tops of several objects (simulated urban s0 frame 50: slope
// 0.057, residual 24 mm) outscored the beam in the camera's field.
constexpr double kOnBeamM = 0.02;
// m, no return lies above the highest beam: a candidate cone with more bins than
// kMaxAboveShare this far above it is not the top beam (a cone through car roofs, say)
constexpr double kAboveM = 0.1;
constexpr double kMaxAboveShare = 0.05;
// Candidate cones through 4 random envelope bins (a fixed seed: the same scan, the same fit),
// drawn among the bins within kDrawBelowM of the highest bin of their range (where the beam
// hits anything at a range, it is that range's highest return).
constexpr int kTrials = 400;
constexpr double kDrawBelowM = 0.3;
// A valid beam: enough bins on it, spread over the ranges, on a cone of positive elevation
// (b = tan(elevation); the HDL-64's top beam +2 deg: 0.033-0.037 in the camera frames of KITTI
// and the simulator) whose tilt against the camera is small (c, d: 0.010-0.012 there), and
// which runs above the sensor: 20 m ahead 0.57-0.83 m above the camera centre there, where a
// cone through a flat road or car roofs would lie 0.2-1.7 m below it.
constexpr int kMinBins = 8, kMinRangeBins = 6;
constexpr double kMinSlope = 0.01, kMaxSlope = 0.2, kMaxTilt = 0.03;
constexpr double kCheckRangeM = 20.0, kMinUpAtCheckM = 0.3;

struct Bin {
  double x, z, r, up;
  int range_bin;
};

Eigen::Vector4d features(const Bin& bin) { return {1.0, bin.r, bin.x, bin.z}; }

bool plausible(const Eigen::Vector4d& coef) {
  return coef.allFinite() && coef[1] >= kMinSlope && coef[1] <= kMaxSlope &&
         std::abs(coef[2]) <= kMaxTilt && std::abs(coef[3]) <= kMaxTilt &&
         coef[0] + kCheckRangeM * (coef[1] + coef[3]) >= kMinUpAtCheckM;
}

// Least squares of the bins flagged in `use`; false when too few or singular.
bool least_squares(const std::vector<Bin>& bins, const std::vector<char>& use, Eigen::Vector4d* coef) {
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  Eigen::Vector4d y = Eigen::Vector4d::Zero();
  int n = 0;
  for (std::size_t i = 0; i < bins.size(); ++i) {
    if (!use[i]) continue;
    const Eigen::Vector4d f = features(bins[i]);
    A += f * f.transpose();
    y += f * bins[i].up;
    ++n;
  }
  if (n < 4) return false;
  *coef = A.ldlt().solve(y);
  return coef->allFinite();
}
}  // namespace

double TopBeam::up_at(double x, double z) const { return a + b * std::hypot(x, z) + c * x + d * z; }

TopBeam fit_top_beam(const std::vector<ScenePoint>& points) {
  const int range_bins = static_cast<int>(std::ceil((kMaxRangeM - kMinRangeM) / kRangeBinM));
  std::unordered_map<int, Bin> highest;
  for (const ScenePoint& p : points) {
    if (p.up < kMinUpM) continue;
    const double r = std::hypot(p.x, p.z);
    if (!(r >= kMinRangeM && r < kMaxRangeM)) continue;
    const int rb = static_cast<int>((r - kMinRangeM) / kRangeBinM);
    const int ab = static_cast<int>(std::floor((std::atan2(p.x, p.z) * 180.0 / M_PI + 180.0) / kAzimuthBinDeg));
    const Bin bin{p.x, p.z, r, p.up, rb};
    auto [it, fresh] = highest.try_emplace(ab * range_bins + rb, bin);
    if (!fresh && p.up > it->second.up) it->second = bin;
  }
  std::vector<Bin> bins;
  bins.reserve(highest.size());
  for (const auto& [key, bin] : highest) bins.push_back(bin);
  TopBeam beam;
  if (static_cast<int>(bins.size()) < kMinBins) return beam;
  // sorted, so that the fixed-seed draws pick the same bins whatever the hash map's order
  std::sort(bins.begin(), bins.end(), [](const Bin& l, const Bin& r) {
    return std::tie(l.range_bin, l.x, l.z) < std::tie(r.range_bin, r.x, r.z);
  });

  const int max_above = std::max(1, static_cast<int>(kMaxAboveShare * bins.size()));
  auto score = [&](const Eigen::Vector4d& coef, std::vector<char>* on) {
    int inliers = 0, above = 0;
    for (std::size_t i = 0; i < bins.size(); ++i) {
      const double res = bins[i].up - features(bins[i]).dot(coef);
      const bool in = std::abs(res) <= kOnBeamM;
      if (on) (*on)[i] = in;
      inliers += in;
      above += res > kAboveM;
    }
    return above > max_above ? -1 : inliers;
  };
  // RANSAC: the cone through 4 bins of distinct ranges with the most bins on it and none
  // (or almost none) above it
  std::vector<double> range_top(range_bins, -std::numeric_limits<double>::infinity());
  for (const Bin& bin : bins) range_top[bin.range_bin] = std::max(range_top[bin.range_bin], bin.up);
  std::vector<int> drawable;
  for (std::size_t i = 0; i < bins.size(); ++i)
    if (bins[i].up >= range_top[bins[i].range_bin] - kDrawBelowM) drawable.push_back(static_cast<int>(i));
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(drawable.size()) - 1);
  Eigen::Vector4d best = Eigen::Vector4d::Zero();
  int best_score = -1;
  for (int t = 0; t < kTrials; ++t) {
    Eigen::Matrix4d A;
    Eigen::Vector4d y;
    int idx[4];
    bool distinct = true;
    for (int k = 0; k < 4; ++k) {
      idx[k] = drawable[pick(rng)];
      for (int j = 0; j < k; ++j) distinct &= bins[idx[j]].range_bin != bins[idx[k]].range_bin;
      A.row(k) = features(bins[idx[k]]).transpose();
      y[k] = bins[idx[k]].up;
    }
    if (!distinct) continue;
    const Eigen::Vector4d coef = A.fullPivLu().solve(y);
    if (!plausible(coef)) continue;
    const int s = score(coef, nullptr);
    if (s > best_score) best_score = s, best = coef;
  }
  if (best_score < kMinBins) return beam;
  // refine on the bins on the best cone, twice
  std::vector<char> on(bins.size(), 0);
  Eigen::Vector4d coef = best;
  for (int pass = 0; pass < 2; ++pass) {
    score(coef, &on);
    Eigen::Vector4d refined;
    if (!least_squares(bins, on, &refined) || !plausible(refined)) break;
    coef = refined;
  }
  const int s = score(coef, &on);
  double sum2 = 0;
  std::vector<char> range_seen(range_bins, 0);
  for (std::size_t i = 0; i < bins.size(); ++i) {
    if (!on[i]) continue;
    const double res = bins[i].up - features(bins[i]).dot(coef);
    sum2 += res * res;
    ++beam.num_bins;
    range_seen[bins[i].range_bin] = 1;
  }
  int ranges = 0;
  for (const char seen : range_seen) ranges += seen;
  beam.a = coef[0], beam.b = coef[1], beam.c = coef[2], beam.d = coef[3];
  beam.rms_m = std::sqrt(sum2 / std::max(1, beam.num_bins));
  beam.valid = s >= kMinBins && ranges >= kMinRangeBins && plausible(coef);
  return beam;
}

bool cut_by_top_beam(const std::vector<int>& members, const std::vector<ScenePoint>& points,
                     const TopBeam& beam, double margin_m) {
  if (!beam.valid || members.empty()) return false;
  int top = members.front();
  for (const int i : members)
    if (points[i].up > points[top].up) top = i;
  // on the beam, not above it: a return above the fitted beam means the fit is wrong there
  return std::abs(points[top].up - beam.up_at(points[top].x, points[top].z)) <= margin_m;
}

}  // namespace twistslam::detection
