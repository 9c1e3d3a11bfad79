#include "tracking/object_keypoints.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "features/right_occlusion.hpp"

namespace twistslam::tracking {
namespace {

features::OrbOptions mask_orb_options(const features::OrbOptions& main, const ObjectTrackingOptions& o) {
  features::OrbOptions m = main;
  m.num_features = o.extra_keypoints_max;
  m.num_levels = std::min(main.num_levels, o.extra_keypoint_levels);
  m.fast_threshold = std::max(o.extra_fast_threshold, 1);
  m.min_fast_threshold = std::min(main.min_fast_threshold, m.fast_threshold);
  m.cell_size = o.extra_cell_px;
  return m;
}

// Occupancy of existing keypoints on a grid of spacing-sized cells: a candidate is too close
// when a keypoint of its own or a neighbouring cell lies within the spacing.
class SpacingGrid {
 public:
  SpacingGrid(int width, int height, double spacing)
      : cell_(std::max(spacing, 1.0)), cols_(static_cast<int>(width / cell_) + 1),
        rows_(static_cast<int>(height / cell_) + 1), cells_(static_cast<size_t>(cols_) * rows_) {}
  void add(const cv::Point2f& p) {
    const int c = cx(p.x), r = cy(p.y);
    if (c >= 0 && r >= 0 && c < cols_ && r < rows_) cells_[static_cast<size_t>(r) * cols_ + c].push_back(p);
  }
  bool near(const cv::Point2f& p) const {
    for (int r = cy(p.y) - 1; r <= cy(p.y) + 1; ++r)
      for (int c = cx(p.x) - 1; c <= cx(p.x) + 1; ++c) {
        if (c < 0 || r < 0 || c >= cols_ || r >= rows_) continue;
        for (const cv::Point2f& q : cells_[static_cast<size_t>(r) * cols_ + c])
          if (std::hypot(p.x - q.x, p.y - q.y) < cell_) return true;
      }
    return false;
  }

 private:
  int cx(float x) const { return static_cast<int>(std::floor(x / cell_)); }
  int cy(float y) const { return static_cast<int>(std::floor(y / cell_)); }
  double cell_;
  int cols_, rows_;
  std::vector<std::vector<cv::Point2f>> cells_;
};

// The object mask's pixels on instances (ids > 0) of at least min_area_px pixels holding fewer
// than min_keypoints of `keypoints` (255; 0 elsewhere), and how many such instances there are.
cv::Mat deprived_instances_mask(const std::vector<cv::KeyPoint>& keypoints,
                                const cv::Mat& object_mask, const cv::Mat& instances,
                                int min_keypoints, int min_area_px, int* num_deprived) {
  std::unordered_map<int, int> count, area;
  for (const cv::KeyPoint& k : keypoints) {
    const cv::Point p(static_cast<int>(std::lround(k.pt.x)), static_cast<int>(std::lround(k.pt.y)));
    if (p.x < 0 || p.y < 0 || p.x >= instances.cols || p.y >= instances.rows) continue;
    if (object_mask.at<std::uint8_t>(p.y, p.x)) ++count[instances.at<int>(p.y, p.x)];
  }
  // areas counted by runs of one instance along a row (a hash lookup per pixel took 2-3 ms)
  const cv::Rect box = cv::boundingRect(object_mask);  // the mask's pixels lie in it
  for (int v = box.y; v < box.br().y; ++v) {
    const std::uint8_t* on = object_mask.ptr<std::uint8_t>(v);
    const int* inst = instances.ptr<int>(v);
    int run_id = 0, run_length = 0;
    for (int u = box.x; u < box.br().x; ++u) {
      const int id = on[u] && inst[u] > 0 ? inst[u] : 0;
      if (id == run_id) {
        ++run_length;
        continue;
      }
      if (run_id > 0) area[run_id] += run_length;
      run_id = id, run_length = 1;
    }
    if (run_id > 0) area[run_id] += run_length;
  }
  std::unordered_set<int> deprived;
  for (const auto& [instance, pixels] : area) {
    const auto it = count.find(instance);
    if (pixels >= min_area_px && (it == count.end() || it->second < min_keypoints))
      deprived.insert(instance);
  }
  cv::Mat mask(object_mask.size(), CV_8UC1, cv::Scalar(0));
  if (!deprived.empty())
    for (int v = box.y; v < box.br().y; ++v) {
      const std::uint8_t* on = object_mask.ptr<std::uint8_t>(v);
      const int* inst = instances.ptr<int>(v);
      std::uint8_t* m = mask.ptr<std::uint8_t>(v);
      int last_id = 0;
      bool last_deprived = false;
      for (int u = box.x; u < box.br().x; ++u) {
        if (!on[u]) continue;
        if (inst[u] != last_id) last_id = inst[u], last_deprived = deprived.count(last_id) > 0;
        if (last_deprived) m[u] = 255;
      }
    }
  *num_deprived = static_cast<int>(deprived.size());
  return mask;
}

}  // namespace

cv::Mat object_class_mask(const cv::Mat& instances, const cv::Mat& labels,
                          const std::vector<int>& object_class_ids) {
  if (instances.type() != CV_32SC1) throw std::invalid_argument("instances: expected int32 ids");
  if (!labels.empty() && (labels.type() != CV_32SC1 || labels.size() != instances.size()))
    throw std::invalid_argument("labels: expected int32 class ids of the instances' size");
  int max_id = 0;
  for (int id : object_class_ids) max_id = std::max(max_id, id);
  std::vector<std::uint8_t> is_object(static_cast<size_t>(max_id) + 1, 0);
  for (int id : object_class_ids)
    if (id >= 0) is_object[id] = 1;
  cv::Mat mask(instances.size(), CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < instances.rows; ++v) {
    const int* inst = instances.ptr<int>(v);
    const int* cls = labels.empty() ? nullptr : labels.ptr<int>(v);
    std::uint8_t* m = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < instances.cols; ++u) {
      if (inst[u] <= 0) continue;
      const int c = cls ? cls[u] : 0;
      m[u] = (!cls || (c >= 0 && c <= max_id && is_object[c])) ? 255 : 0;
    }
  }
  return mask;
}

cv::Mat instances_of_classes(const cv::Mat& instances, const cv::Mat& labels,
                             const std::vector<int>& class_ids) {
  cv::Mat out = cv::Mat::zeros(instances.size(), CV_32SC1);
  instances.copyTo(out, object_class_mask(instances, labels, class_ids));
  return out;
}

void mark_occluder_classes(const cv::Mat& labels, const std::vector<int>& class_ids, cv::Mat* ids) {
  if (ids->type() != CV_32SC1 || labels.type() != CV_32SC1 || labels.size() != ids->size())
    throw std::invalid_argument("mark_occluder_classes: expected int32 labels and ids of one size");
  const std::unordered_set<int> occluders(class_ids.begin(), class_ids.end());
  if (occluders.empty()) return;
  for (int v = 0; v < ids->rows; ++v) {
    const int* cls = labels.ptr<int>(v);
    int* id = ids->ptr<int>(v);
    for (int u = 0; u < ids->cols; ++u)
      if (id[u] <= 0 && occluders.count(cls[u])) id[u] = kOccluderId;
  }
}

features::StereoSearchOptions object_stereo_search(const ObjectTrackingOptions& options) {
  features::StereoSearchOptions search;
  search.min_depth = static_cast<float>(options.extra_min_depth_m);
  search.max_depth = static_cast<float>(options.max_depth_m);
  search.max_cost = static_cast<float>(options.extra_max_sad_cost);
  search.uniqueness = static_cast<float>(options.extra_sad_uniqueness);
  features::check_options(search);
  return search;
}

ObjectKeypointExtractor::ObjectKeypointExtractor(const features::OrbOptions& main,
                                                 const ObjectTrackingOptions& options)
    : extractor_(mask_orb_options(main, options)),
      min_instance_keypoints_(options.extra_min_instance_keypoints),
      min_instance_area_px_(options.extra_min_instance_area_px),
      min_spacing_px_(options.extra_min_spacing_px),
      left_right_check_(options.left_right_check),
      left_right_tolerance_px_(static_cast<float>(options.left_right_tolerance_px)),
      instance_pixel_stereo_(options.instance_pixel_stereo),
      instance_pixel_min_fraction_(static_cast<float>(options.instance_pixel_min_fraction)),
      pulled_nearer_check_(options.pulled_nearer_check),
      pulled_nearer_min_depth_m_(static_cast<float>(options.pulled_nearer_min_depth_m)),
      pulled_nearer_max_px_(static_cast<float>(options.pulled_nearer_max_px)),
      right_occlusion_check_(options.right_occlusion_check),
      right_occlusion_margin_px_(static_cast<float>(options.right_occlusion_margin_px)),
      right_occlusion_min_keypoints_(options.right_occlusion_min_keypoints) {
  search_ = object_stereo_search(options);
}

ObjectKeypointReport ObjectKeypointExtractor::extract(const cv::Mat& gray_left,
                                                      const cv::Mat& object_mask,
                                                      const geometry::StereoCamera& camera,
                                                      features::StereoFeatures* f,
                                                      const cv::Mat& instances,
                                                      const cv::Mat& support_instances) const {
  ObjectKeypointReport report;
  if (object_mask.empty() || cv::countNonZero(object_mask) == 0) return report;
  features::Keypoints& left = f->left;
  const int n_old = static_cast<int>(left.size());
  if (static_cast<int>(f->matches.depth.size()) != n_old)
    throw std::invalid_argument("ObjectKeypointExtractor: matches do not belong to the keypoints");

  if (!instances.empty() && (instances.type() != CV_32SC1 || instances.size() != object_mask.size()))
    throw std::invalid_argument("ObjectKeypointExtractor: instances must be int32 ids of the mask's size");
  SpacingGrid grid(gray_left.cols, gray_left.rows, min_spacing_px_);
  for (const cv::KeyPoint& k : left.keypoints) grid.add(k.pt);
  std::vector<cv::Mat> rows;
  auto append = [&](const features::Keypoints& extra) {
    for (int j = 0; j < static_cast<int>(extra.size()); ++j) {
      const cv::KeyPoint& k = extra.keypoints[j];
      if (grid.near(k.pt)) continue;
      grid.add(k.pt);
      left.keypoints.push_back(k);
      rows.push_back(extra.descriptors.row(j));
    }
  };
  // the main pass's pyramid of this very image (its level 0 shares the pixels) when it kept
  // it: the same levels, not rebuilt
  const bool own_pyramid = !left.pyramid.empty() && left.pyramid[0].data == gray_left.data &&
                           left.pyramid[0].size() == gray_left.size();
  const auto extract = [&](const features::OrbExtractor& extractor, const cv::Mat& mask) {
    return own_pyramid ? extractor.extract_on_pyramid(left.pyramid, mask)
                       : extractor.extract(gray_left, mask);
  };
  const features::Keypoints extra = extract(extractor_, object_mask);
  append(extra);
  if (!instances.empty() && min_instance_keypoints_ > 0) {
    // the pass's budget is spread over the masks' area, so near cars take most of it; a
    // vehicle left short gets its own share in a second pass over the short masks (not one
    // under the area floor: a far car's SAD depths there were wrong, docs/visual_objects.md)
    const cv::Mat deprived = deprived_instances_mask(left.keypoints, object_mask, instances,
                                                     min_instance_keypoints_, min_instance_area_px_,
                                                     &report.num_deprived);
    if (report.num_deprived > 0) {
      features::OrbOptions o = extractor_.options();
      o.num_features = std::min(report.num_deprived * min_instance_keypoints_, 100000);
      append(extract(features::OrbExtractor(o), deprived));
    }
  }
  report.num_added = static_cast<int>(rows.size());
  if (!rows.empty()) {
    cv::Mat added;
    cv::vconcat(rows, added);
    if (left.descriptors.empty()) left.descriptors = added;
    else cv::vconcat(left.descriptors, added, left.descriptors);
  }
  f->matches.u_right.resize(left.size(), -1.0f);
  f->matches.depth.resize(left.size(), -1.0f);

  // every object keypoint: the new ones and the main pass's
  std::vector<int> on_objects, without_depth;
  for (int i = 0; i < static_cast<int>(left.size()); ++i) {
    // std::lround as FrameBuilder and ObjectTracker read a keypoint's pixel (cvRound rounds half to even)
    const cv::Point p(static_cast<int>(std::lround(left.keypoints[i].pt.x)), static_cast<int>(std::lround(left.keypoints[i].pt.y)));
    if (p.x < 0 || p.y < 0 || p.x >= object_mask.cols || p.y >= object_mask.rows) continue;
    if (!object_mask.at<std::uint8_t>(p.y, p.x)) continue;
    on_objects.push_back(i);
    if (!(f->matches.depth[i] > 0)) without_depth.push_back(i);
  }
  if (on_objects.empty()) return report;
  const std::vector<cv::Mat>& pyr_left = left.pyramid.empty() ? extra.pyramid : left.pyramid;
  if (f->right.pyramid.empty())
    throw std::invalid_argument("ObjectKeypointExtractor: the right pyramid was not kept");
  report.num_new_depth = features::search_stereo(left, pyr_left, f->right.pyramid, camera, search_,
                                                 without_depth, &f->matches);
  if (instance_pixel_stereo_ && !support_instances.empty()) {
    const features::InstanceSupportReport support = features::depth_on_instance_pixels(
        left, pyr_left, f->right.pyramid, camera, search_, on_objects, support_instances,
        instance_pixel_min_fraction_, &f->matches);
    report.num_instance_rescanned = support.num_rescanned;
    report.num_instance_dropped = support.num_dropped;
  }
  if (pulled_nearer_check_ && !instances.empty())
    report.num_pulled_nearer_dropped =
        features::drop_matches_pulled_nearer(left, pyr_left, f->right.pyramid, camera, search_,
                                             on_objects, instances, instance_pixel_min_fraction_,
                                             pulled_nearer_min_depth_m_, pulled_nearer_max_px_,
                                             &f->matches)
            .num_dropped;
  if (right_occlusion_check_ && !instances.empty())
    report.num_right_occluded_dropped =
        features::drop_matches_occluded_in_right(left, on_objects, instances,
                                                 right_occlusion_margin_px_,
                                                 right_occlusion_min_keypoints_, &f->matches)
            .num_dropped;
  if (left_right_check_)
    report.num_left_right_removed =
        features::check_left_right(left, pyr_left, f->right.pyramid, camera, search_, on_objects,
                                   left_right_tolerance_px_, &f->matches);
  return report;
}

}  // namespace twistslam::tracking
