#include "tracking/local_bundle_adjustment.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "optim/bundle_adjustment.hpp"

namespace twistslam::tracking {

bool prepare_local_ba(const map::Map& map, int keyframe_id, int gauge_keyframe,
                      const LocalBAOptions& options, const LevelWeights& weights,
                      ObjectBundleTerms* objects, LocalBAJob* job) {
  const int segment = map.keyframe(keyframe_id).segment;
  std::vector<int> window{keyframe_id};
  for (int kf : map.covisible_keyframes(keyframe_id, options.window - 1))
    if (map.keyframe(kf).segment == segment) window.push_back(kf);
  if (window.size() < 2) return false;  // a lone keyframe: nothing to adjust against

  *job = LocalBAJob();
  job->keyframe_id = keyframe_id;
  job->frame_index = map.keyframe(keyframe_id).frame_index;
  job->window = window;
  job->objects = objects;
  optim::BAProblem& problem = job->problem;
  std::unordered_map<int, int> kf_slot;
  for (int kf : window) {
    kf_slot[kf] = static_cast<int>(problem.keyframes.size());
    problem.keyframes.push_back({map.keyframe(kf).T_c_w, kf == gauge_keyframe});
  }
  std::vector<int> candidates;  // points of the window, each once
  {
    std::unordered_set<int> seen;
    for (int kf : window)
      for (int pid : map.keyframe(kf).point_ids)
        if (pid >= 0 && seen.insert(pid).second) candidates.push_back(pid);
  }
  // Fixed keyframes: others seeing the window's points, most shared first.
  std::unordered_map<int, int> shared;
  for (int pid : candidates)
    for (const auto& obs : map.point(pid).observations)
      if (!kf_slot.count(obs.first) && map.keyframe(obs.first).segment == segment) ++shared[obs.first];
  std::vector<std::pair<int, int>> ranked;
  for (const auto& [kf, n] : shared) ranked.emplace_back(n, kf);
  std::sort(ranked.rbegin(), ranked.rend());
  for (size_t k = 0; k < ranked.size() && static_cast<int>(k) < options.max_fixed; ++k) {
    kf_slot[ranked[k].second] = static_cast<int>(problem.keyframes.size());
    problem.keyframes.push_back({map.keyframe(ranked[k].second).T_c_w, true});
  }
  // Gauge: without a fixed keyframe the window would float; hold its oldest one.
  if (std::none_of(problem.keyframes.begin(), problem.keyframes.end(), [](const auto& k) { return k.fixed; })) {
    const int oldest = *std::min_element(window.begin(), window.end());
    problem.keyframes[kf_slot[oldest]].fixed = true;
  }

  // Points seen by at least two keyframes of the problem. A point seen once is exactly
  // determined by its own observation (stereo) or not at all (mono): its Schur complement
  // is zero, so it tells the poses nothing and only costs solver time (~half of the window's points).
  for (int pid : candidates) {
    const auto& observations = map.point(pid).observations;
    const long in_problem = std::count_if(observations.begin(), observations.end(),
                                          [&](const auto& obs) { return kf_slot.count(obs.first) > 0; });
    if (in_problem < 2) continue;
    const int slot = static_cast<int>(problem.points.size());
    problem.points.push_back({map.point(pid).X_w, false});
    job->point_ids.push_back(pid);
    for (const auto& [kf, kp] : observations) {
      const auto kf_it = kf_slot.find(kf);
      if (kf_it == kf_slot.end()) continue;
      const map::StereoKeypoints& k = map.keyframe(kf).keypoints;
      problem.observations.push_back({kf_it->second, slot, k.uv[kp], k.u_right[kp],
                                      weights.at(k.octave[kp])});
      job->obs_link.emplace_back(pid, kf);
    }
  }

  if (objects) {
    std::map<int, int> slot_of_frame;
    for (const auto& [kf, slot] : kf_slot) slot_of_frame[map.keyframe(kf).frame_index] = slot;
    objects->add_bundle_terms(slot_of_frame, options.dynamic_points_per_object, &problem);
  }
  job->keyframe_slots.assign(kf_slot.begin(), kf_slot.end());
  std::sort(job->keyframe_slots.begin(), job->keyframe_slots.end());  // one order, whatever the hash
  return true;
}

void solve_local_ba(const geometry::StereoCamera& camera, const LocalBAOptions& options, LocalBAJob* job) {
  const auto start = std::chrono::steady_clock::now();
  optim::BundleAdjustmentOptions ba;
  ba.max_iterations_first = options.iterations_first;
  ba.max_iterations_second = options.iterations_second;
  ba.huber_delta_stereo = options.huber_stereo;
  ba.huber_delta_mono = options.huber_mono;
  ba.num_threads = options.num_threads;
  ba.link_sigma_translation = options.dynamic_link_sigma_translation;
  ba.link_sigma_rotation = options.dynamic_link_sigma_rotation;
  ba.object_const = options.dynamic_const;
  job->report = optim::bundle_adjust(job->problem, camera, ba);
  job->solve_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void apply_local_ba(const LocalBAJob& job, map::Map& map) {
  const optim::BAProblem& problem = job.problem;
  const optim::BundleAdjustmentReport& report = job.report;
  if (job.objects && report.converged) job.objects->take_bundle_result(problem, report);

  for (const auto& [kf, slot] : job.keyframe_slots)
    if (!problem.keyframes[slot].fixed && map.has_keyframe(kf)) map.keyframe(kf).T_c_w = problem.keyframes[slot].T_c_w;
  for (size_t k = 0; k < job.point_ids.size(); ++k)
    if (map.has_point(job.point_ids[k])) map.point(job.point_ids[k]).X_w = problem.points[k].X_w;
  std::unordered_set<int> touched;
  for (size_t e = 0; e < job.obs_link.size(); ++e) {
    const auto& [pid, kf] = job.obs_link[e];
    if (e < report.outlier.size() && report.outlier[e] && map.has_point(pid)) {
      map.erase_observation(pid, kf);
      touched.insert(pid);
    }
  }
  for (int pid : touched)
    if (map.point(pid).observations.empty()) map.erase_point(pid);
  for (int kf : job.window)
    if (map.has_keyframe(kf)) map.update_covisibility(kf);
}

bool local_bundle_adjustment(map::Map& map, int keyframe_id, int gauge_keyframe,
                             const geometry::StereoCamera& camera, const LocalBAOptions& options,
                             const LevelWeights& weights, ObjectBundleTerms* objects) {
  LocalBAJob job;
  if (!prepare_local_ba(map, keyframe_id, gauge_keyframe, options, weights, objects, &job)) return false;
  solve_local_ba(camera, options, &job);
  apply_local_ba(job, map);
  return true;
}

}  // namespace twistslam::tracking
