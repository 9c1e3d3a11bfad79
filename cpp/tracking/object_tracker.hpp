#pragma once
// Visual tracking of every object cluster inside the SLAM (paper sec. "Clusters creation"
// and "Dynamic object tracking", eq. 1-4), the third component beside camera tracking and
// local mapping. Per frame, after the camera pose is known:
//   1. each live cluster's points are searched around their optical-flow-predicted position
//      (or the motion model's projection when there is no flow) by descriptor;
//   2. the frame's panoptic instances are associated with clusters by the matched points
//      they share, then by mask overlap (objects/instance_association.hpp);
//   3. the twist is estimated by LM on Pi xi (eq. 4, objects/twist_estimation.hpp), the
//      cluster's points are projected with the new pose and re-matched, the twist estimated
//      again, and the pose updated by eq. 2;
//   4. unmatched stereo keypoints inside the associated mask join the cluster; instances of
//      object classes with no cluster start one (identity rotation at the centroid);
//   5. points rarely found are culled; a cluster without a valid twist for max_misses frames
//      ends its track.
// With 3D detections (LiDAR fusion, object_detection_fusion.cpp), each frame's boxes are
// associated with the clusters before step 3: a cluster's first box sets its canonical frame,
// later ones its size and the e_det terms of its window; a box keeps a cluster whose twist
// failed on its pose.
// The state is objects::ObjectTrack (one per cluster) + objects::ObjectCluster (its points).
#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "features/stereo_search.hpp"
#include "geometry/stereo_camera.hpp"
#include "lidar/scan_projection.hpp"
#include "objects/box_free_space.hpp"
#include "objects/instance_association.hpp"
#include "objects/object_cluster.hpp"
#include "objects/object_track.hpp"
#include "objects/twist_estimation.hpp"
#include "optim/visual_object_window.hpp"
#include "tracking/flow_refinement.hpp"
#include "tracking/frame.hpp"
#include "tracking/level_weights.hpp"
#include "objects/detection.hpp"
#include "tracking/object_bundle_terms.hpp"
#include "tracking/object_lidar_options.hpp"
#include "tracking/object_tracking_options.hpp"

namespace twistslam::tracking {

// What the final smoothing did (object_smoothing.cpp).
struct ObjectSmoothingReport {
  int num_tracks = 0;     // tracks refined (their T_w_o replaced, the online poses kept)
  int num_rejected = 0;   // tracks whose smoothed steps failed max_step_m: kept online
  int num_residuals = 0;  // over all refined tracks
};

struct ObjectTrackingReport {
  int num_tracked = 0;  // clusters with a valid twist this frame
  int num_new = 0;      // clusters started this frame
  int num_missed = 0;   // live clusters without a valid twist (predicted)
  int num_points = 0;   // matched inlier points over all clusters
};

// The heading (a unit vector in w along the box's length axis) that a parked car in the box
// T_w_box has by the traffic side's rule, seen from the camera T_w_c: zero when the rule is off
// (ObjectLidarOptions::road_side_heading 0), the box lies within road_side_min_lateral_m of
// the camera's path (its own lane: ahead or behind) or beyond road_side_max_lateral_m (off
// the camera's road), or its axis is more than
// road_side_max_angle_deg off the camera's travel (parked across).
Vec3 road_side_heading(const Mat4& T_w_c, const Mat4& T_w_box, const ObjectLidarOptions& options);

class ObjectTracker : public ObjectBundleTerms {
 public:
  ObjectTracker(const geometry::StereoCamera& camera, const ObjectTrackingOptions& options,
                const std::vector<float>& scale_factors, LevelWeights weights,
                const ObjectLidarOptions& lidar_options = ObjectLidarOptions());

  // frame: keypoints with class labels and the tracked camera pose frame.T_c_w;
  // instances: CV_32SC1 instance ids of the left image (0: none), empty: no masks this frame
  // (clusters are still tracked from their matches); flow: CV_32FC2 optical flow from the
  // previous frame to this one (NaN: none), or empty; up_w: the road normal in the world
  // frame (planar link). Throws std::invalid_argument on wrong sizes or types.
  // labels: empty or CV_32SC1 class ids per pixel and road_plane_w the road (n, d) in the
  // world (zero: none): with both, a vehicle instance with too few stereo points may start a
  // cluster at its ground-contact depth (ground_contact.hpp).
  // detections: the frame's 3D boxes (camera frame; class_id in the panoptic vocabulary).
  // scan: the frame's LiDAR points (frame c) or nullptr; object scans inside canonical boxes
  // are registered frame to frame by GICP (e_reg, object_scans.cpp).
  // gray_left / gray_right: empty or the frame's rectified 8-bit pair (CV_8UC1, image size):
  // the flow-located points' disparity (flow_observations_stereo).
  ObjectTrackingReport track(const Frame& frame, const cv::Mat& instances, const cv::Mat& flow,
                             const Vec3& up_w, const cv::Mat& labels = cv::Mat(),
                             const Vec4& road_plane_w = Vec4::Zero(),
                             const std::vector<objects::Detection>& detections = {},
                             const Points3* scan = nullptr, const cv::Mat& gray_left = cv::Mat(),
                             const cv::Mat& gray_right = cv::Mat());

  // The frame just tracked becomes a keyframe: its object observations are kept for the
  // local BA (e_dyna), the latest max_keyframes per point.
  void mark_keyframe(int frame_index, int max_keyframes);
  // ObjectBundleTerms (object_bundle.cpp): the live clusters' poses at the problem's
  // keyframes, their points seen from two of them, and the results taken back.
  void add_bundle_terms(const std::map<int, int>& slot_of_frame, int max_points,
                        optim::BAProblem* problem) override;
  void take_bundle_result(const optim::BAProblem& problem,
                          const optim::BundleAdjustmentReport& report) override;
  // The LiDAR terms of one object in the keyframe BA, between its poses (track rows `rows`):
  // the box prior (canonical tracks), e_det between the boxes of consecutive poses and e_reg
  // of the registrations chained between them, all in the cameras' frames (BAObjectMotion).
  void add_bundle_lidar_terms(const objects::ObjectTrack& track, const std::vector<int>& rows,
                              optim::BAObject* object) const;

  // The final smoothing, once the sequence ends (options.final_smoothing; the paper's global
  // BA of the object terms with the cameras fixed): per track, all its rows, every archived
  // observation of its points (retired ones too), e_const, e_link, e_head and the LiDAR terms
  // in one problem. T_c_w_of_frame: the refined camera pose of every tracked frame. Each
  // refined track keeps its online poses in T_w_o_online. A track with a frame missing from
  // T_c_w_of_frame, or fewer than 3 rows, is left as it is.
  ObjectSmoothingReport smooth_tracks(const std::map<int, Mat4>& T_c_w_of_frame);

  const std::vector<objects::ObjectTrack>& tracks() const { return tracks_; }
  const std::vector<objects::ObjectCluster>& clusters() const { return clusters_; }
  void reset();

 private:
  struct Match {
    int point;
    int keypoint;
    int distance;  // Hamming bits
  };
  // a point located by the optical flow alone (no keypoint there)
  struct FlowObservation {
    int point;
    Vec2 uv;             // px, flow-predicted pixel in the current left image
    double u_right = -1;  // px, its SAD scan's right column; < 0: none (mono observation)
  };
  // Step 1: the cluster's points searched in the frame from their last observation (flow)
  // or the predicted pose; fills the association evidence.
  std::vector<Match> search_cluster(const objects::ObjectCluster& cluster, const Mat4& T_c_o,
                                    const Frame& frame, const cv::Mat& instances,
                                    const cv::Mat& flow,
                                    objects::ClusterInstanceEvidence* evidence) const;
  // Step 3, a cluster depth_m away (its predicted origin, camera z) beyond
  // flow_observations_min_depth_m with fewer keypoint matches than
  // flow_observations_below_matches (nearer: than flow_observations_near_below_matches),
  // without a canonical frame: its
  // unmatched points seen in the last frame at their flow-predicted pixels on its instance,
  // with a SAD scan's disparity where it finds one (object_flow_observations.cpp).
  std::vector<FlowObservation> flow_observations(const objects::ObjectCluster& cluster,
                                                 const std::vector<Match>& matches,
                                                 int instance, double depth_m,
                                                 bool canonical) const;
  // Step 3's second pass: points not matched yet, projected with the estimated pose.
  void refine_matches(const objects::ObjectCluster& cluster, const Mat4& T_c_o,
                      const Frame& frame, int instance, std::vector<Match>* matches) const;
  // Whether keypoint k may belong to a cluster associated with `instance` (-1: none).
  bool keypoint_allowed(int k, int instance) const;
  // Step 3 for one cluster; returns whether the twist was valid.
  // detection: index of the frame's box associated with it (-1: none).
  bool update_cluster(int c, const Frame& frame, std::vector<Match> matches, int instance,
                      const Mat4& T_w_o_pred, int detection);
  // LiDAR fusion (object_detection_fusion.cpp). The detection index per cluster of
  // `clusters` (at poses T_w_o, on instance masks `instances`, -1: none this frame), one to
  // one, among the boxes not used yet (-1: none).
  std::vector<int> associate_detections(const Frame& frame, const std::vector<int>& clusters,
                                        const std::vector<Mat4>& T_w_o,
                                        const std::vector<int>& instances);
  // A cluster given an instance by mask overlap alone (fewer than min_shared_points of its
  // matches on it) whose points projected on the mask lie mask_max_depth_ratio nearer or
  // farther than the mask's LiDAR returns: the mask is another car's (one passing in front);
  // the instance is taken from it (-1), free for a cluster of its own (object_occluders.cpp).
  void release_occluding_instances(const std::vector<int>& clusters, const std::vector<Mat4>& T_w_o,
                                   const Frame& frame,
                                   const std::vector<objects::ClusterInstanceEvidence>& evidence,
                                   std::vector<int>* instances) const;
  // The depths (m, camera frame) of the frame's LiDAR returns that project onto `instance`'s
  // mask (nullptr: no scan or no masks); one pass over the scan for every instance, the first
  // time a frame asks (object_occluders.cpp).
  const std::vector<double>* mask_lidar_depths(int instance) const;
  // The object instance most of box d's LiDAR returns project onto (0: too few returns on
  // object masks to tell, or no scan / masks); computed once per box and frame.
  int instance_of_box(int d);
  // Box d joins cluster c's last frame: canonical frame (first box), size, e_det.
  void attach_detection(int c, const Frame& frame, int d);
  // Before cluster c's first box: rows that turned faster than a car turns (a far cluster's
  // twist from a few points) keep their positions and take its last row's rotation.
  void level_cluster_turn(int c);
  // The object frame of cluster c becomes the box frame T_w_box at its last frame.
  void make_canonical(int c, const Mat4& T_w_box);
  // Once it has moved heading_from_motion_m, a canonical frame facing backwards turns.
  void check_heading_from_motion(int c);
  // A canonical track that has not moved that far (a parked or waiting car) faces the way
  // most of its boxes' headings do (one box, one vote; a box known mod pi votes with its road
  // side's heading, road_side_heading).
  void check_heading_from_votes(int c);
  // One view of a canonical vehicle's front: the hood-minus-trunk gap of its object scan
  // (points_w, world frame) when the scan spans its length (object_front_profile.cpp).
  void add_front_profile_view(int c, const Points3& points_w);
  // +1 / -1: its views put its front at +x / -x of its frame; 0: undecided or off.
  int front_from_profile_views(const objects::ObjectTrack& track) const;
  // Turns cluster c's canonical frame by pi about its y axis, with the boxes aligned to it.
  void turn_canonical_around(int c);
  // the canonical frame moved to the weighted mean offset of all the track's boxes
  void refine_canonical(int c);
  // LiDAR registration (object_scans.cpp): cluster c's object scan of this frame (points of
  // scan_ in its box at its last pose, world frame), GICP against its previous frame's scan:
  // the registered motion on its last row (e_reg of the window).
  void register_scan(int c, const Frame& frame);
  // Scans older than this frame's are never registered again: freed.
  void drop_stale_scans(int frame_index);
  // The unassigned object-class instance under the box centre's projection (-1: none).
  int free_instance_under(const geometry::Box3D& box) const;
  // Clusters from first_new on (started this frame) take the boxes still unused.
  void attach_new_cluster_detections(const Frame& frame, int first_new);
  // Two tracks on one car this frame (one's origin inside the other's canonical box): the one
  // with fewer boxes is not reported in this frame, and the other one is, its prediction if
  // its own twist failed (object_duplicates.cpp).
  void hide_duplicate_tracks(const Frame& frame);
  // A canonical track without a box this frame whose box the LiDAR sees through (returns
  // beyond it on rays crossing it, few inside) is not reported in it (object_free_space.cpp).
  void hide_see_through_tracks(const Frame& frame);
  // The rows it hid take the test again with their final poses (T_c_w_of_frame: the refined
  // cameras; a frame missing there keeps the row's own), on the returns kept with them;
  // reported again where the box is no longer seen through. Called by smooth_tracks.
  void retest_see_through(const std::map<int, Mat4>& T_c_w_of_frame);
  bool see_through(const objects::BoxRayCounts& counts) const;
  // how far (m) a hidden row's box may move before its kept returns no longer cover the test
  static constexpr double kSeeThroughRetestReachM = 3.0;
  // A track of small_object_class_ids without a box this frame, farther than
  // small_object_report_max_depth_m, is not reported in it (object_report_range.cpp).
  void hide_far_small_tracks(const Frame& frame);
  // A vehicle track without a canonical frame whose points lie nearer than the LiDAR returns
  // around them, by a median over its rows of more than lidar_check_max_ratio and
  // lidar_check_min_offset_m, is not reported in its rows without a box (object_lidar_check.cpp).
  void hide_lidar_contradicted_tracks(const Frame& frame);
  // `frame`, or a copy in *storage whose vehicle keypoints took the depth of the returns on
  // their own mask (lidar_objects.keypoint_lidar_depth; object_keypoint_lidar_depth.cpp)
  const Frame& with_instance_lidar_depth(const Frame& frame, Frame* storage);
  std::vector<std::uint8_t> keypoint_lidar_filled_;  // per keypoint of the frame: depth from the LiDAR
  // The verdict on a track's medians so far (false before lidar_check_min_rows checked rows).
  bool lidar_contradicts(const objects::ObjectTrack& track) const;
  // Its reported rows without a box are not reported (lidar_contradicted).
  static void hide_lidar_contradicted_rows(objects::ObjectTrack* track);
  // At the end, on all its rows: the rows hidden online are reported again where the whole
  // track's medians no longer contradict it. Called by smooth_tracks.
  void retest_lidar_contradiction();
  // The frame's far camera-only rows keep their instance's LiDAR returns (far_lidar_returns),
  // and at the end each such track's far rows move along their lines of sight to the returns'
  // depth: a vehicle's by one track-wide ratio, a free-link track's each by the running median
  // of its rows' ratios (lidar_objects.far_lidar_align_*; object_lidar_align.cpp).
  void keep_far_lidar_returns(const Frame& frame);
  void align_far_rows_to_lidar(const std::map<int, Mat4>& T_c_w_of_frame);
  // After the final smoothing: camera-only vehicle tracks' rows turn at most as far as they
  // travel allows (objects::bound_turn_by_travel, min_turn_radius_m; object_windows.cpp).
  void bound_camera_only_turns();
  // The frame's boxes no track took, kept for backfill_frames frames (object_backfill.cpp).
  void remember_unused_boxes(const Frame& frame);
  // A new canonical track c: the unused boxes of the frames before its first one that line up
  // with it (objects/box_chain.hpp) become its backcast rows (object_backfill.cpp).
  void backfill_from_boxes(int c);
  // Re-places track c's backcast rows by its first rows' motion (after the final smoothing).
  void place_backcast(int c);
  // Step 4: stereo keypoints of `instance` not claimed yet -> points of cluster c.
  void add_points(int c, const Frame& frame, int instance);
  // Stereo keypoints of `instance` no cluster claimed, in the world frame, but those farther
  // than instance_lidar_max_depth_error from the instance's LiDAR depth there
  // (instance_lidar_depth_near; kept where it gives none).
  std::vector<std::pair<int, Vec3>> free_instance_points(const Frame& frame, int instance) const;
  // The free stereo points of `instance` within max_point_spread_m of their median, and
  // their centroid (world frame); false with fewer than min_points. With ground_contact
  // (vehicles) and too few stereo points, the instance's keypoints without depth are placed
  // at its ground-contact depth instead (ground_contact.hpp); with fewer than
  // depth_fill_below_points and no contact, at their nearest stereo point's depth.
  // With a LiDAR scan, stereo points more than mask_max_depth_ratio nearer than the median of
  // the mask's returns are left out (in front of the surface the LiDAR sees: wrong matches),
  // and with too few stereo points the keypoints without depth take the LiDAR depth of their
  // mask (lidar_depth_points; ObjectLidarOptions::instance_lidar_depth; vehicles) before the
  // cues above.
  // *lidar_seeded (when given) tells whether the LiDAR completed the seed, *contact_seeded
  // whether the ground contact did.
  bool seed_points(const Frame& frame, int instance, int min_points, bool ground_contact,
                   std::vector<std::pair<int, Vec3>>* kept, Vec3* centroid,
                   bool* lidar_seeded = nullptr, bool* contact_seeded = nullptr) const;
  // The free keypoints of `instance` without a stereo depth, each at the depth the LiDAR
  // returns on the instance's own mask give it (a local plane through those near it,
  // lidar/lidar_depth.hpp; world frame); empty without a scan or when the returns' median
  // depth is beyond ObjectLidarOptions::instance_lidar_max_depth_m. A car behind a nearer one shows
  // a sliver whose stereo mostly fails (the right camera sees it hidden differently).
  std::vector<std::pair<int, Vec3>> lidar_depth_points(const Frame& frame, int instance) const;
  // The LiDAR returns on `instance`'s own mask within mask_max_depth_ratio of their median
  // depth, projected into the image (nullptr without a scan or masks), and the depth they give
  // the pixel uv (NaN where they give none: too few around it, an edge).
  const lidar::ScanProjection* instance_returns(int instance) const;
  double instance_lidar_depth(int instance, const Vec2& uv) const;
  // The median depth of those returns within a few pixels of uv (NaN with too few): where a
  // local plane needs returns all around, at a mask's edge too (a check, not a measurement).
  double instance_lidar_depth_near(int instance, const Vec2& uv) const;
  // The free keypoints of `instance` without a stereo depth, at its ground-contact depth
  // (world frame); empty when the mask shows no contact with the road.
  std::vector<std::pair<int, Vec3>> ground_contact_points(const Frame& frame, int instance) const;
  // Indices of the keypoints of `instance` without a stereo depth that no cluster claimed.
  std::vector<int> free_mono_keypoints(const Frame& frame, int instance) const;
  // The free keypoints of `instance` without a stereo depth, each at the depth of the nearest
  // of `stereo` (the instance's stereo points) in the image (stereo_depth_fill.hpp); empty
  // when those are too few or too far.
  std::vector<std::pair<int, Vec3>> depth_fill_points(const Frame& frame, int instance,
                                                      const std::vector<std::pair<int, Vec3>>& stereo) const;
  // Stereo points a new (or re-seeded) cluster of this link needs: the planar link's
  // 3-DoF twist is fixed by fewer points than a free 6-DoF one.
  int min_seed_points(geometry::LinkType link) const;
  // A new point of cluster c (index into clusters_) from keypoint k at X_o; claims k.
  void append_point(objects::ObjectCluster& cluster, int c, const Frame& frame, int k,
                    const Vec3& X_o);
  bool start_cluster(const Frame& frame, int instance, int class_id, const Vec3& up_w);
  // The free stereo points of `instance` join the cluster, placed with *T_w_o (the
  // prediction; a cluster without velocity moves to their centroid and drops its old points).
  // False when the instance has too few points. *contact_seeded (when given): the ground
  // contact placed some of them; *reborn (when given): the cluster was re-born at them.
  bool reseed(int c, const Frame& frame, int instance, Mat4* T_w_o, bool* contact_seeded = nullptr,
              bool* reborn = nullptr);
  void cull(objects::ObjectCluster& cluster) const;
  // e_dyna + e_const (+ e_head) over the cluster's last window_frames frames (eq. 9), camera
  // fixed.
  void refine_window(int c);
  // The object window of cluster c's rows [first, first + rows): camera poses from
  // camera_of, its poses, the observations its points made in those frames (their bounded
  // history, or with `whole_life` their archives and the retired points' too), the travel
  // axis and the LiDAR terms. used: per window point, the cluster point index, or -1 - k for
  // retired point k. False when a frame has no camera pose.
  bool build_window(int c, int first, int rows, const std::map<int, Mat4>& camera_of,
                    bool whole_life, optim::VisualObjectWindow* w, std::vector<int>* used) const;
  optim::VisualObjectWindowOptions window_options(const objects::ObjectTrack& track) const;
  // Takes a refined window back into rows [first, first + rows) (poses past the fixed ones,
  // twists, velocity, points); false, and nothing changed, when a step exceeds max_step_m.
  bool take_window(int c, int first, const optim::VisualObjectWindow& w, const std::vector<int>& used);
  // Points leave the cluster (culled, dropped by a re-seed): into `retired` with their
  // archives when the final smoothing is on and they were seen twice.
  void retire(objects::ObjectCluster& cluster, std::vector<objects::ObjectPoint>&& points) const;
  // The last step of a tracked vehicle joins its travel direction (non-holonomic prior).
  void add_travel_step(objects::ObjectTrack& track) const;
  // Moves the object frame's origin to the median of the cluster's confirmed points when it
  // lies farther than recenter_distance_m from it (every pose and point re-expressed).
  void recenter(int c);
  objects::TwistObservation observation(const objects::ObjectPoint& p, const Frame& frame,
                                        int keypoint) const;
  // Pyramid scale of an octave (level px -> image px), clamped to the pyramid; 1 without one.
  double level_scale(int octave) const;

  geometry::StereoCamera camera_;
  ObjectTrackingOptions options_;
  ObjectLidarOptions lidar_options_;
  std::vector<float> scale_factors_;
  LevelWeights weights_;
  objects::TwistEstimationOptions lm_options_;

  std::vector<objects::ObjectTrack> tracks_;
  std::vector<objects::ObjectCluster> clusters_;  // clusters_[k] holds tracks_[k]'s points
  std::map<int, Mat4> T_c_w_of_frame_;  // camera poses of the recent frames (window)
  Vec3 up_w_ = Vec3(0, -1, 0);          // the road normal of the frame being tracked
  cv::Mat instances_, labels_, flow_;   // during track(): the caller's images (views)
  cv::Mat gray_left_, gray_right_;      // during track(): the stereo pair (views; may be empty)
  // the last frame's left image (a copy; flow_observations_lk_max_px) and its frame index
  cv::Mat previous_gray_left_;
  int previous_gray_frame_ = -1;
  // during track(): the pyramids of the previous and current left images, built on first use
  mutable LkPyramids lk_pyramids_;
  // the last frame's current pyramid (its frame index), the next frame's previous one: the
  // same image's pyramid, not built twice
  std::vector<cv::Mat> previous_lk_pyramid_;
  int previous_lk_frame_ = -1;
  features::StereoSearchOptions search_;  // the flow-located points' SAD scan
  double instance_border_px_ = 0;       // during track(): the keypoints' instance border rule
  Vec4 road_plane_w_ = Vec4::Zero();    // its road plane (zero: none)
  std::vector<objects::Detection> detections_;  // during track(): the frame's boxes (frame c)
  std::vector<char> detection_used_;            // ... associated with a cluster
  std::vector<int> detection_instance_;         // ... instance_of_box (-1: not computed yet)
  const Points3* scan_ = nullptr;               // during track(): the frame's LiDAR scan (c)
  // during track(): mask_lidar_depths' instance -> depths, filled on its first call
  mutable std::map<int, std::vector<double>> mask_lidar_depths_;
  mutable std::map<int, std::vector<Vec3>> mask_lidar_points_;  // the same returns (camera frame)
  // during track(): instance_returns' projections, built on first use
  mutable std::map<int, lidar::ScanProjection> instance_returns_;
  mutable bool mask_lidar_depths_ready_ = false;
  // the boxes no track took, per recent frame (oldest first), for backfill_from_boxes
  struct UnusedBox {
    Mat4 T_w_box = Mat4::Identity();
    int class_id = 0;
    double score = 0, range = 0;
  };
  struct UnusedBoxes {
    int frame = -1;
    std::vector<UnusedBox> boxes;
  };
  std::vector<UnusedBoxes> recent_unused_boxes_;
  struct ObjectScan;                            // object_scans.cpp
  std::map<int, std::shared_ptr<const ObjectScan>> last_scan_;  // track id -> its latest scan
  int next_id_ = 0;
  int last_frame_ = -1;
  // the current frame's depth_fill_below_points (the LiDAR fusion's own in a frame with boxes)
  int depth_fill_below_points_ = 0;
  // per keypoint of the current frame
  std::vector<int> instance_of_keypoint_;
  std::vector<int> claimed_by_;  // cluster index or -1
  std::unordered_set<int> assigned_instances_;  // instances associated with a cluster
  std::map<int, int> instance_class_;           // instance -> majority class of its keypoints
  // what add_bundle_terms put into the BA problem, for take_bundle_result
  struct BundleLink {
    int cluster = -1;
    int object = -1;                  // index into the problem's objects
    std::vector<int> rows;            // track row per object pose
  };
  std::vector<BundleLink> bundle_links_;
  struct BundleObservation {
    int cluster, point, frame;
  };
  std::vector<BundleObservation> bundle_observations_;  // per dynamic observation of the problem
};

}  // namespace twistslam::tracking
