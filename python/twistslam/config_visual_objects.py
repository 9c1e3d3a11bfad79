"""The ``visual_objects`` section of :class:`twistslam.Config`: visual tracking of every object
cluster inside the SLAM (paper sec. "Clusters creation" and "Dynamic object tracking", eq. 1-4;
C++ ``tracking::ObjectTrackingOptions``, cpp/tracking/object_tracker.hpp).

It runs when the run has a segmentation source (``twistslam.run(..., segmentation=...)``):
instances of ``object_class_ids`` become clusters with a pose per frame and a twist under their
mechanical link, searched around their optical-flow-predicted positions. Values were chosen on
simulated ``urban`` seed 0 (docs/visual_objects.md has the figures).
"""

from __future__ import annotations

from dataclasses import dataclass

from ._settings import param

#: Cityscapes ids of the a-priori dynamic classes: person, rider, car, truck, bus, caravan,
#: trailer, train, motorcycle, bicycle
OBJECT_CLASSES = [24, 25, 26, 27, 28, 29, 30, 31, 32, 33]
#: classes that move on the road: the planar link (TwistSLAM's vehicles)
PLANAR_CLASSES = [26, 27, 28, 29, 30, 31, 32, 33]


@dataclass
class VisualObjectsConfig:
    """Object clusters tracked by their keypoints (eq. 4) in the SLAM."""

    enabled: bool = param(True, "track object clusters whenever the run has instance masks")
    object_class_ids: list[int] = param(
        list(OBJECT_CLASSES), "panoptic classes whose instances become object clusters "
        "(a-priori dynamic; 'unknown' stays static, as in the paper)")
    planar_class_ids: list[int] = param(
        list(PLANAR_CLASSES), "object classes on the planar link (3 DoF on the road); "
        "the others get the free link (6 DoF); [] makes every link free (ablation)")
    road_class_id: int = param(7, "class of the road cluster that gives the planar normal; "
                               "-1: none (the first camera's up)")
    road_max_depth_m: float = param(
        25.0, "keyframe road keypoints beyond this do not join the road plane fit: at 25 m "
        "a 0.25 px disparity error is 0.4 m of depth, 4x the fit's 0.1 m inlier band", "m")
    road_lidar_points: bool = param(
        False, "the frame's LiDAR returns on road pixels join each keyframe's road plane fit "
        "(paper sec. 'Injecting LiDAR scans'). Off: the stereo road keypoints already give the "
        "plane within the road's own unevenness. Plane normal / offset error against the "
        "simulator's road, off -> on: urban s0 0.039 -> 0.043 deg, -2.9 -> -3.7 cm; urban s1 "
        "0.103 -> 0.060 deg, -0.5 -> +0.8 cm; crowded s0 0.045 -> 0.027 deg, -1.5 -> -0.9 cm "
        "(RANSAC inliers 62 -> 97 %). Object RPE_r (det-reg, urban + crowded s0-2) 0.403 -> "
        "0.432 deg/m; real 0001 object RPE_R 3.88 -> 3.57 deg/m, one more false positive box")
    road_lidar_max_depth_m: float = param(
        25.0, "road returns beyond this depth do not join the fit: the stretch the road "
        "keypoints describe (road_max_depth_m); 40 m moved the simulator's plane by <= 0.1 cm",
        "m", lo=0.5, hi=10000.0)
    road_lidar_border_px: int = param(
        3, "a road return joins only when every pixel within this distance of its pixel is "
        "road: the class images carry no score, and labels fail at the mask's boundary. Real "
        "0001 (road from the LiDAR grid, cars from boxes), returns > 0.3 m off the frame's "
        "LiDAR ground plane: 1.8 % at 0 px, 1.2 % at 1, 0.95 % at 3, 0.85 % at 5 (8 % and "
        "12 % of the road returns lost at 3 and 5); the simulator's exact masks need 1",
        "px", lo=0, hi=100)
    road_lidar_max_points: int = param(
        300, "road returns per keyframe, one per block of the scan's candidates: the plane's "
        "5000-point reservoir holds 78 % (urban, ~90 road keypoints per keyframe) to 91 % (crowded, ~30) LiDAR; "
        "1000 moved the simulator's plane by <= 0.1 cm and <= 0.006 deg", "points", lo=0, hi=100000)
    road_plane_window_m: float = param(
        25.0, "the road plane (the planar link's normal) from the road points of the keyframes "
        "within this distance of the newest one's camera, re-fitted at each keyframe (0: one "
        "plane from a reservoir over every keyframe's points). A drive is not one plane: on a "
        "400-frame urban sequence (seed 3, a 0.35 deg grade after 180 m) the whole-map plane "
        "held the lead car's track level while the car climbed, its yaw 7 deg and height 0.5 m "
        "off (classical detector). Keyframe windows of ~13 / 24 / 48 m: that car's aligned ATE "
        "0.179 -> 0.093 / 0.099 / 0.135 m; 25 m (the stretch road_max_depth_m describes ahead): "
        "0.109 m, yaw 7.0 -> 1.1 deg, the sequence's 3D MOTP 80.7 -> 83.7 %, ghosts 2 -> 0 "
        "(50 m: 0.127 m, 2.1 deg). The 32 100-frame sequences: files 150 -> 150 cars, ghosts "
        "2 -> 3; DIS 150 -> 151, 2 -> 4 (far parked cars at 50 m); classical 152, 2 -> 2, yaw "
        "1.34 -> 0.44 deg; real 0001 unchanged (docs/visual_objects.md)", "m", lo=0.0, hi=1e9)
    flow_radius_px: float = param(
        4.0, "search window around the flow-predicted keypoint: DIS flow's error on the "
        "simulator is 0.5 px median, 4 px keeps its tail", "px")
    projection_radius_px: float = param(
        12.0, "search window around the motion-model projection when a point has no flow "
        "(first seen two frames ago, or no flow source)", "px")
    refine_radius_px: float = param(
        3.0, "second pass: window around the projection with the estimated twist", "px")
    max_hamming: int = param(50, "ORB-SLAM2's matching threshold; cars show few, similar "
                             "corners, the twist LM's Huber loss takes the rest", "bits")
    flow_max_hamming: int = param(
        80, "descriptor distance accepted around the flow prediction: the flow has located "
        "the point; object corners change with viewpoint and only 59 % of the flow-predicted "
        "keypoints are within 50 bits (85 % within 80; simulator, urban seed 0)", "bits",
        lo=0, hi=256)
    min_new_cluster_points: int = param(
        10, "stereo keypoints inside a new instance mask needed to start a cluster of a "
        "free-link class (6-DoF twist)", "points")
    min_new_planar_cluster_points: int = param(
        6, "... of a planar-link class (vehicles): the 3-DoF twist needs fewer points. Far "
        "oncoming cars (35-50 m) get 6-9 stereo points, the part of them the right camera "
        "also sees; 6 instead of 10: urban seed 2 cars tracked >= 90 % 1/4 -> 4/4", "points")
    ground_contact: bool = param(
        True, "a vehicle instance with too few stereo points starts its cluster at the depth "
        "where its mask meets the road plane (the right camera sees other occluders: far "
        "oncoming and queued cars show 1-4 stereo depths among 17-37 keypoints); not in the "
        "paper")
    instance_border_px: float = param(
        3.0, "a keypoint within this distance of another instance's pixel (times its pyramid "
        "level's scale) joins neither instance: at an occlusion its corner and stereo depth "
        "are the nearer object's (not in the paper). 3 px, FAST's circle radius, measured on "
        "six simulated sequences against 0 / 2 / 4: means RPE_r 0.229 -> 0.180 deg/m, aligned "
        "ATE 0.092 -> 0.065 m, ghost tracks 4 -> 1 from 0; 2 and 4 were worse on urban seeds "
        "0-1 (ghosts 3 and 2, ATE up to 0.22 m); 0: off. Frames with 3D boxes use "
        "lidar_objects.instance_border_px", "px", lo=0.0, hi=50.0)
    min_contact_columns: int = param(
        5, "mask columns whose lowest pixel has road right below it, for a ground-contact "
        "depth", "columns", lo=1)
    min_contact_fraction: float = param(
        0.5, "... and at least this fraction of the mask's columns whose lower edge is not "
        "hidden behind another instance: a car whose lower edge mostly rests on the sidewalk "
        "or an unlabelled occluder has no road contact there (urban seeds 7 and 9: parked "
        "cars at 42-51 m with sidewalk below 10 of 14 and 7 of 9 columns, seeded by 0.3 into "
        "tracks drifting 3-9 m off)", "fraction",
        lo=0.0, hi=1.0)
    contact_depth_quantile: float = param(
        0.5, "the quantile of the contact columns' depths that places the car. Between its "
        "wheels a car's lowest pixel is its body, 0.13-0.32 m above the road on the "
        "simulator, so the median landed 8 and 13 % beyond the near face of urban s0 car 12 and "
        "urban s8 car 23 (45 and 53 m); 0.15 (the "
        "wheels' columns) placed the cars nearer (16 sequences, camera alone: aligned ATE "
        "0.066 -> 0.063 m, RPE_r 0.162 -> 0.170 deg/m) but seeded more ghosts on 4 unseen "
        "ones (2 -> 4, urban s9 0 -> 3)", "fraction", lo=0.0, hi=1.0)
    min_contact_cluster_points: int = param(
        4, "keypoints a new vehicle cluster placed by its ground contact needs (instead of "
        "min_new_planar_cluster_points, which it can only lower): the contact gives their "
        "depth, and a far car's small mask beside a nearer car keeps few keypoints off the "
        "instance border (urban s0's oncoming car 12 at 38-44 m: 1-5, so 6 left it untracked "
        "in 3 of 22 frames; until min_inliers points match, each frame re-seeds it at its "
        "contact). Camera alone, 16 simulated sequences at 6 -> 4: cars tracked >= 90 % 73 -> "
        "74 of 74, ghosts 1 -> 1, RPE_r 0.162 -> 0.165 deg/m, aligned ATE 0.066 -> 0.069 m; "
        "8 unseen ones: 41 of 41 and 2 ghosts both, RPE_r 0.175 -> 0.186, ATE 0.091 -> 0.093 "
        "(urban s10's car 10 born earlier, from fewer points)", "points", lo=3)
    contact_height_m: float = param(
        0.0, "the ground contact's rays meet a plane this far above the road: between its "
        "wheels a car's lowest pixel is its body (0.13-0.32 m up on the simulator), whose ray "
        "meets the road 1.65 / (1.65 - h) times too far. 0.15 placed the contact cars nearer "
        "(16 sequences, camera alone: RPE_r 0.165 -> 0.158 deg/m, aligned ATE 0.069 -> 0.061 m, "
        "74 of 74 cars both) but seeded ghosts, as contact_depth_quantile 0.15 did: 1 -> 2, and "
        "2 -> 3 on 4 unseen ones (urban s9 0 -> 2)", "m", lo=0.0, hi=2.0)
    depth_fill_below_points: int = param(
        12, "a vehicle instance with fewer stereo points (and no ground contact) starts its "
        "cluster with its keypoints without stereo as well, each at the depth of its nearest "
        "stereo keypoint in the image (tracking/stereo_depth_fill.hpp; not in the paper): the "
        "right camera often misses a car queued beside or behind a nearer one, and a cluster "
        "of its 6 stereo points failed frame after frame. Ten simulated sequences, camera "
        "alone (files): cars >= 90 % tracked 44 -> 46 of 49 (crowded s3 cars 17 and 81), "
        "ghosts 4 -> 4, RPE_r 0.182 -> 0.189 deg/m, aligned ATE 0.073 -> 0.071 m; 20 changed "
        "nothing; 0: off", "points", lo=0)
    depth_fill_min_points: int = param(
        3, "... stereo depths the mask must hold for that (2 tracked no more cars)", "points",
        lo=1)
    depth_fill_max_depth_m: float = param(
        30.0, "... and their median must lie within this: a far car's few disparities are "
        "metres off (1.2 m at 30 m for 0.5 px); with 40 m one more ghost (urban s4), without a "
        "limit (and one depth per mask) urban s4 had two more", "m", lo=0.5)
    depth_fill_min_stereo_share: float = param(
        0.15, "... and make up at least this share of the mask's free keypoints: with fewer, "
        "the stereo failed wholesale (real 0001: a car passing at 4-6 m on the image border, 3 "
        "stereo depths among 253 keypoints, was placed 1.6 m too far)", "fraction", lo=0.0,
        hi=1.0)
    min_shared_points: int = param(
        5, "matched points an instance must share with a cluster to be associated", "points")
    min_mask_overlap: float = param(
        0.5, "else: fraction of the cluster's projected points inside the instance mask")
    min_inliers: int = param(6, "inliers of the twist LM for a valid frame (3 fix a rigid "
                             "motion; 6 leave a margin against a wrong minimal fit)", "points")
    flow_observations_below_matches: int = param(
        1000, "a cluster with fewer keypoint matches than this also takes its unmatched points "
        "seen in the last frame at their flow-predicted pixels (on its instance, "
        "instance_border_px from its edge) as observations of the twist LM, so that a point "
        "lives on where its keypoint is not found again (1000, above max_points: every "
        "cluster beyond flow_observations_min_depth_m). A far car shows few repeatable "
        "keypoints (urban s12's turning car at 45-55 m: 3-7 of 20-30 matched, a ghost), and "
        "a lead car's rear-face points lived 2-3 frames, so its object frame slid along its "
        "body window after window (unseen urban s14's lead car at 24-37 m: 3.4 m short in depth "
        "by frame 81, while its points' disparities matched the true ones within 0.1 px). "
        "Every cluster beyond 20 m with the stereo scan and Lucas-Kanade below, against the "
        "ninth session's 6 matches beyond 40 m (mono), on 22 simulated sequences (urban 0-8 "
        "10-13, crowded 0-8, 107 cars): files 106 -> 105 cars, ghosts 1 -> 2, RPE_t 0.0430 -> "
        "0.0419 m/m, RPE_r 0.180 -> 0.161 deg/m, aligned ATE 0.099 -> 0.092 m; DIS 106 -> 105, "
        "ghosts 2 -> 2, RPE_r 0.188 -> 0.163, ATE 0.095 -> 0.091; on unseen urban 14, 15 "
        "(9 cars): files 8 -> 9 cars, ATE 0.291 -> 0.121 m, RPE_r 1.15 -> 0.27 deg/m; DIS 8 "
        "-> 9 cars, ghosts 1 -> 0, ATE 0.248 -> 0.169 m. At every depth: ATE 0.13 -> 0.26 m on "
        "the first urban seeds (approaching lead cars). Not for tracks with a canonical (box) "
        "frame: the boxes place them (the classical row's urban s8 gained a ghost with them); "
        "0: off", "matches", lo=0)
    flow_observations_min_depth_m: float = param(
        20.0, "flow_observations_below_matches applies only to clusters whose predicted origin "
        "lies at least this far (camera z): nearer, keypoints are plenty and repeat, and the "
        "flow points at every depth doubled the aligned ATE of the first urban seeds (0.13 -> "
        "0.26 m). With mono observations (no stereo scan) it was 40 m: far oncoming cars at "
        "35-45 m stalled on them", "m", lo=0.0, hi=10000.0)
    flow_observations_near_below_matches: int = param(
        6, "nearer than flow_observations_min_depth_m, a cluster with fewer keypoint matches "
        "than this takes the flow-located points too (0: off). 6 = min_inliers: only frames "
        "the twist LM would fail. Measured on 32 simulated sequences, both flows: cars >= 90 "
        "% 148 -> 150 (files) and 149 -> 150 (DIS) of 152 (crowded s12's car 77, half hidden "
        "at 17 m with 2-8 matches a frame: 0.76 -> 0.98 of its frames), ghosts unchanged, "
        "the 22 tuning sequences' RPE_r 0.160 -> 0.175 deg/m (files). 10: the same number "
        "of cars (149 / 151, crowded s1's car 17 lost with the files), RPE_r 0.156 / 0.241 "
        "over the 32 against 0.168 / 0.254; 6 changes only frames that would fail and loses "
        "no car anywhere (docs/visual_objects.md)",
        "matches", lo=0)
    flow_observations_stereo: bool = param(
        True, "each flow-located point also gets the disparity of a SAD scan at its pixel over "
        "its instance's pixels of the window (the extra keypoints' scan bounds), when the scan "
        "finds one: a stereo observation sees the motion along the line of sight that a mono "
        "one misses. Alone (6 matches beyond 40 m, no Lucas-Kanade) on the 22 sequences: files "
        "ghosts 0 -> 1, DIS 1 -> 3 (at 45-50 m the scan's depth is a metre off either way); "
        "with every cluster beyond 20 m and Lucas-Kanade: flow_observations_below_matches")
    flow_observations_lk_max_px: float = param(
        1.0, "> 0: each flow-located pixel is refined by pyramidal Lucas-Kanade on the left "
        "images (11 px window, one level), from the point's last pixel and started at the "
        "flow's pixel, and kept only when it lands within this many pixels of it: a point "
        "located by the flow frame after frame chains the flow's error (DIS is a few tenths of "
        "a pixel off on a car), so its observations slide along the body. Unseen urban s14's "
        "lead car with DIS and flow points beyond 20 m: aligned ATE 1.59 m without, 0.17 m "
        "with; without it, DIS lost urban s14's car and raised the unseen seeds' ATE 0.25 -> "
        "0.39 m; 0: the flow's pixel as it is", "px", lo=0.0, hi=1000.0)
    max_step_m: float = param(
        5.0, "an object pose moving farther than this in one frame is rejected: the twist LM "
        "then fails, and the window keeps its input poses. 5 m is 180 km/h at KITTI's 10 Hz. "
        "Without e_const (ablation), urban seed 0 had a far car's window throw two reported "
        "poses 3-5 km away", "m")
    max_misses: int = param(5, "frames without a valid twist before the track ends "
                            "(predicted meanwhile)", "frames")
    reseed_after_misses: int = param(
        1, "failed frames after which a cluster whose instance is still associated takes "
        "that instance's stereo points as its new points (same track); 0: never (the track "
        "fails until it dies and the instance starts a new one)", "frames")
    untracked_report_max_depth_m: float = param(
        45.0, "a cluster never tracked since its birth (no valid twist) reports a re-seeded row "
        "only when its origin is this near (camera z): such a row is one frame's stereo "
        "points, and beyond ~45 m their depth error at 0.5 px (2.6 m) passes a car's half "
        "length. Far oncoming cars' clusters that re-seeded frame after frame 3-4 m off were "
        "ghosts (urban s2 at 56 m). Ten simulated sequences, camera alone: ghosts 4 -> 3 "
        "(files), 5 -> 4 (DIS), the same 46 of 49 cars; reporting no such row at all (any "
        "range) gave 2 ghosts but lost urban s2's cars 0 and 9 at 37-43 m (44 cars)", "m",
        lo=0.0)
    untracked_contact_report_max_depth_m: float = param(
        45.0, "... and such a row placed by the cluster's ground contact only this near: the "
        "contact lands 8-15 % beyond a car's near face (its lowest pixels are its body, above "
        "the road), which the box centre half a car length behind makes up for only near. "
        "45 (as any re-seeded row) is off; measured on 22 simulated sequences + 4 unseen: 35 m "
        "and 40 m each removed urban s8's ghost (files) but lost 1-2 cars per flow (urban s0 "
        "DIS, urban s10 both) and unseen urban s15's car 14", "m", lo=0.0)
    untracked_reseed_max_jump_m: float = param(
        3.5, "... and only when it lies within this (per frame apart) of the cluster's previous "
        "row (0: no test): consecutive one-frame placements of one car that far apart put it on "
        "different surfaces (urban s8's ghost: ground-contact re-seeds at 42, 38, 37, 41 m of a "
        "car at 36 m; unseen urban s17's: 43.7, 43.9, 39.1, 36.2 m of a car at 37-39 m). 28 "
        "simulated sequences x 2 flows: ghosts 4 -> 1 (urban s8 files, urban s17 both flows "
        "gone), cars >= 90 % 261 -> 259 of 264 (urban s10's car 9, 0.92 -> 0.89, both flows), "
        "errors the same to 0.001; 2.0 m also lost urban s0's car 12 (DIS) and unseen urban "
        "s15's car 16 (both)", "m", lo=0.0, hi=10000.0)
    reseed_trusted_velocity_twists: int = param(
        2, "a cluster whose twist fails keeps its points at its predicted pose when re-seeded "
        "only when its velocity rests on at least this many valid twists; else it is re-born "
        "at the new points (origin at their centroid, velocity zero, its re-seeds reported as "
        "a never-tracked cluster's). 1: only a cluster without any twist is re-born. A far "
        "car's first twist measures its birth points' depth error as motion: urban s28's "
        "parked car at 37 m, born 5.5 m deep, moved 3 m a frame towards the camera, and its "
        "re-seeds at the prediction carried that on (a ghost). 19 simulated sequences "
        "(urban 0-3 19 23-28, crowded 0-3 15-18) x 2 flows, with the two gates below: ghosts "
        "3 / 2 -> 2 / 2 (files / DIS; urban s28's gone), the same cars, errors within 0.001; "
        "freezing the rows before a re-birth out of the windows cost RPE_r 0.125 -> 0.194 "
        "deg/m", "twists",
        lo=1, hi=100000)
    reseed_reborn_min_offset_m: float = param(
        2.0, "... and whose new points' median lies farther than this from its old points' "
        "median at the predicted pose (the prediction missed the car; a car's visible part "
        "moves its median by less). Without it or the depth bound below the 19 sequences had "
        "3 / 4 ghosts (urban s0's pedestrian in both flows, urban s19's far car with DIS)", "m",
        lo=0.0, hi=10000.0)
    reseed_reborn_min_depth_m: float = param(
        15.0, "... and only when its predicted origin lies at least this far (camera z). "
        "Nearer, the medians of a car's parts differ by metres where the image cuts it: with "
        "no such bound real KITTI 0001's car 0, leaving the image at 4-6 m, was re-born and "
        "lost (3D MOTA 100 -> 87.5 %); at 15 m the image's edge lies 12.7 m to the side. On 24 "
        "simulated sequences 15 m against 25 m: crowded s16's queued car 13 (files), whose "
        "one-twist velocity failed at 15-20 m, 0.82 -> 1.00 of its frames, every other car, "
        "ghost and error the same, real 0001 identical", "m", lo=0.0, hi=10000.0)
    reborn_barrier_max_depth_m: float = param(
        25.0, "rows before a re-birth (a re-seed that dropped the cluster's points) whose row "
        "lies nearer than this (camera z) stay out of the windows, the final smoothing and the "
        "keyframe BA when there are reborn_barrier_min_rows of them or more: nothing but "
        "e_const links them to the new points, and the windows carried them back along the "
        "new points' motion (crowded s16's queued car, re-seeded on it at 15-20 m for 8 frames, "
        "went 4 m off after one wrong twist in its last frame: a ghost in both flows). Farther, "
        "a re-born row's stereo depth is metres off and the windows place it. On 24 sequences "
        "(files / DIS): ghosts 2 / 2 -> 1 / 1, cars 116 / 116 of 117 both, RPE_t +0.0003 / "
        "+0.0002 m/m, RPE_r +0.002 / +0.002 deg/m; real 0001 identical. 0: no barrier", "m",
        lo=0.0, hi=10000.0)
    reborn_barrier_min_rows: int = param(
        3, "rows a re-birth must have before it for the barrier. With 1 (any re-birth) on the 24 "
        "sequences crowded s1's car 17 with DIS fell to 0.89 of its frames: only its "
        "(unreported) birth row left the windows, and the run took another course from there",
        "rows", lo=1, hi=100000)
    small_object_class_ids: list[int] = param(
        [24, 25], "classes whose camera-only rows are reported only within "
        "small_object_report_max_depth_m (Cityscapes person, rider); []: none")
    small_object_report_max_depth_m: float = param(
        35.0, "small_object_class_ids: a row without a LiDAR box of its own is reported only "
        "this near (camera z). A person is ~0.6 m deep and thinner than the SAD window; at 35 m "
        "a 0.25 px disparity error moves it ~0.8 m. On 16 simulated sequences (urban, crowded "
        "seeds 0-7, camera alone, exact segmentation) 0-2.6 % of the pedestrian rows reported "
        "within 35 m were off every object by over 1 m, 36-46 % of those at 35-50 m (urban s4 "
        "and s7: a ghost track each); the car rows' share stays under 2 % to 45 m, 5-8 % to 60 m",
        "m", lo=0.0)
    max_point_spread_m: float = param(
        4.0, "new points farther than this from the cluster's median point are dropped "
        "(a car is <= 5.2 m long; masks bleed onto the background)", "m")
    window_max_point_move_depth_ratio: float = param(
        0.5, "a sliding window (or the final smoothing) that would move a point farther than "
        "this fraction of its depth from where it joined the cluster does not move it, and the "
        "point is culled: a stereo depth is good to a few percent, and such points (free along "
        "their rays, or on a surface behind the object) ran to hundreds of metres (camera-only "
        "boxes 49-1600 m long on crowded seeds). Measured on 16 simulated sequences (seeds "
        "0-7): cars 69 -> 70 of 74, ghosts 5 -> 4, RPE_r 0.161 -> 0.148 deg/m; a limit per "
        "window let points creep away by steps, and holding the points seen in the left image "
        "only lost urban seed 7's lead car. Not for tracks with a canonical (box) frame: the "
        "boxes place them, and the classical row's RPE_r went 0.147 -> 0.156 deg/m",
        "fraction of depth")
    max_depth_m: float = param(
        60.0, "stereo points beyond this never join a cluster: at 60 m a KITTI disparity of "
        "6.5 px puts 1 px of error at 9 m of depth", "m")
    max_points: int = param(600, "points per cluster (the least found are culled first)",
                            "points")
    min_found_ratio: float = param(
        0.25, "points matched in fewer of the frames predicting them are culled (as map points)")
    cull_after_visible: int = param(5, "... once predicted in this many frames", "frames")
    lm_iterations: int = param(10, "Levenberg-Marquardt iterations per pass of eq. 4")
    window_frames: int = param(
        8, "frames of the sliding window that refines the cluster's poses and points with "
        "e_dyna + e_const (eq. 9) + e_head after each frame; < 3: off. 8 instead of 5: urban "
        "seeds 0-2 RPE_t 0.09/0.05/0.06 -> 0.04/0.04/0.05 m/m, objects 1.0-1.1 -> 1.3-1.5 "
        "ms per object per frame", "frames", lo=0, hi=100)
    use_const: bool = param(True, "e_const in the window (ablation: False)")
    const_sigma_translation: float = param(
        0.05, "change of the translational twist between frames: 5 m/s^2 at 10 Hz (hard braking)",
        "m/frame")
    const_sigma_rotation: float = param(
        0.005, "change of the rotational twist between frames (0.3 deg/frame)", "rad/frame")
    rest_sigma_translation: float = param(
        0.0, "> 0: e_rest, a prior of no motion on each step of a camera-only track's windows "
        "and final smoothing (translation only): a far parked car with a handful of points "
        "took a 14 km/h velocity from two noisy re-seeds (urban seed 19's ghost track 8; 1.0 "
        "m/frame stills it). Off: on 32 simulated sequences 1.0 cost more than it gave, files "
        "/ DIS flow cars >= 90 % 150 -> 147 / 151 -> 146 of 152, ghosts 3 -> 4 / 4 -> 4, "
        "aligned ATE 0.090 -> 0.104 / 0.093 -> 0.103 m: it slows far moving cars whose depth "
        "motion the stereo hardly sees (urban s14's car 0, s2's car 9); 0: off",
        "m/frame", lo=0.0, hi=100.0)
    const_rotation_reference_step_m: float = param(
        1.0, "below this step per frame the rotation sigma of e_const shrinks in proportion "
        "(a vehicle's yaw rate is speed x curvature and curvature changes along the path: a "
        "crawling car's yaw rate hardly changes); 0: one sigma at every speed. Oracle boxes, "
        "six simulated sequences, RPE_r 0.252 deg/m at 0, 0.205 at 1 m, 0.214 at 2 m (urban "
        "seed 2 lost a car)", "m/frame")
    const_rotation_min_fraction: float = param(
        0.1, "the shrunk sigma's floor, as a fraction of const_sigma_rotation (a car at rest); "
        "not tuned: the crawling cars of the simulator's queues (0.15-0.25 m/frame) stay above it",
        "fraction")
    window_iterations: int = param(5, "Ceres iterations of the window (from a close start)")
    window_function_tolerance: float = param(
        1e-3, "the window stops once an iteration changes its cost by less than this fraction "
        "of it. With Ceres' default 1e-6 the window ran its 5 iterations almost always (mean "
        "4.98, urban s0); with 1e-3, 3.3 and ~40 % less CPU (2.3 -> 1.4 ms per window). Ten "
        "sequences (urban and crowded seeds 0-4, files flow), mean object RPE_t / RPE_r / "
        "aligned ATE: 1e-6 0.042 m/m / 0.200 deg/m / 0.078 m; 1e-3 0.040 / 0.182 / 0.073; "
        "the same 44 of 49 cars and 4 ghosts. The last iterations fitted the keypoints' noise "
        "that e_const and the link had smoothed. With the final smoothing as loose too: 1e-4 "
        "0.182 deg/m / 0.076 m, 1e-3 0.178 / 0.075, 1e-2 0.164 / 0.079 (ATE no better): the "
        "final smoothing keeps Ceres' default", "fraction", lo=0.0, hi=1.0)
    recenter_distance_m: float = param(
        0.5, "the object frame's origin moves to the median of the cluster's confirmed points "
        "when farther than this: a cluster born at 40 m sits metres off in depth until its "
        "points are refined closer (0: never)", "m")
    recenter_max_spread_m: float = param(
        6.0, "... unless the confirmed points spread wider than this between their 10 % and 90 % "
        "quantiles along an object axis while the origin lies beyond recenter_spread_min_depth_m "
        "(0: no limit): a far track whose depth motion lagged placed its later points metres "
        "ahead of its origin, and their median moved every row, the first ones too (urban s7's "
        "lead car at 44-60 m: spreads of 8-10.5 m, 6.7 m off at frame 0, a ghost; its recentres "
        "at 36-45 m spread 1.9-4.6 m). 7.5 m gave the same on urban 7, 8 and 12", "m")
    recenter_spread_min_depth_m: float = param(
        25.0, "... the bound applies only beyond this depth of the origin: near, the stereo "
        "holds the points and a messy cluster's median is still its best centre (ungated, "
        "crowded s7's car 12 at 15 m, spreads 5-10 m: aligned ATE 0.089 -> 0.245 m; crowded "
        "s1's car 17 0.02 -> 0.98 coverage; the crowded cars all lie within 20 m)", "m")
    recenter_with_retired_points: bool = param(
        True, "the re-centring's median also counts the confirmed points the track culled "
        "(kept only with final_smoothing): the median then converges instead of following "
        "whichever points are live. 22 simulated sequences (urban 0-8 10-13, crowded 0-8, files "
        "and DIS flow), off -> on: cars >= 90 % 104 -> 106 of 107 in both rows (crowded s1's "
        "car 17, crowded s8's car 15), ghosts 1 -> 1 and 2 -> 2, aligned ATE 0.097 -> 0.090 m "
        "(files); the LiDAR rows (urban 0 2 8) identical, real 0001 within 1 mm")
    recenter_on_stereo_points: bool = param(
        True, "beyond recenter_spread_min_depth_m, the re-centring's median and spread over the "
        "confirmed points seen in stereo at least once (when min_inliers of them are): a far car "
        "seeded at its ground contact holds mono points at a guessed depth (urban s11's parked "
        "car 22: 21 % too far at 44 m), the stereo points it gains later disagree with them, "
        "the spread of all bars the re-centring and its origin stayed 9 m behind the car (a "
        "ghost, the car lost). 22 simulated sequences, off -> on: files unchanged (105 of 107 "
        "cars, 2 ghosts), DIS cars 105 -> 106, ghosts 2 -> 1, RPE_r 0.163 -> 0.164 deg/m, "
        "aligned ATE 0.091 -> 0.094 m (the car gained counts); unseen urban 14 15, crowded 9 10 "
        "unchanged. At every depth it lost crowded s1's car 17 (near, the guessed points fill "
        "the faces the stereo misses)")
    min_turn_radius_m: float = param(
        5.0, "after the final smoothing a camera-only vehicle track's rows turn at most (distance "
        "its origin travelled) / this, row to row (0: off): a car turns only as it drives, on a "
        "radius of at least ~5 m (a small car's turning circle; the value is that physical bound, "
        "not fitted). Urban s23's slow car 17 at 50-23 m drives straight while its cluster's "
        "frame spun -1.5 deg a frame for 30 frames (RPE_r 5.2 deg/m): the twist of a far car "
        "seen end-on hardly observes a yaw rate and e_const keeps a constant one. 37 simulated "
        "sequences (urban 0-8 10-19 23-25, crowded 0-12 15-16), files / DIS: RPE_r 0.229 -> "
        "0.211 / 0.269 -> 0.251 deg/m, RPE_t and aligned ATE slightly lower, the same cars and "
        "ghosts, no car worse (3 m and 8 m, offline: 0.206 / 0.185 with the files)",
        "m", lo=0.0, hi=1000.0)
    path_turn_chord_m: float = param(
        5.0, "after the turn bound, a camera-only vehicle track's path direction at each end is "
        "the chord over its first / last this much travel (reported rows; the chords may not "
        "overlap, so a track needs twice this path): a car heads where its path goes, and a "
        "far side-on cluster's frame that turns with its bearing while the car drives straight "
        "(urban s23's car 17) is caught by comparing the two. 5 m: the chord's direction error "
        "from a far track's depth scatter (~1 m at 45 m) stays near 10 deg", "m", lo=0.0, hi=1000.0)
    path_turn_max_straight_deg: float = param(
        15.0, "the two chords within this angle: the car drove straight (a turn at a junction "
        "turns its path by 45-90 deg; the far turning cars of urban s24-s26 by 47-90 deg, their "
        "chords by >= 10 deg or too short to compare)", "deg", lo=0.0, hi=180.0)
    path_turn_min_excess_deg: float = param(
        20.0, "... and its rows turned at least this much more than its path: every row takes "
        "the middle reported row's rotation (0: off). 19 simulated sequences (urban 0-3 19 "
        "23-28, crowded 0-3 15-18), files / DIS: only urban s23's car 17 levelled (its rows -51 "
        "deg, its path +6 deg), RPE_r 3.95 -> 0.00 deg/m, means 0.175 -> 0.125 / 0.197 -> 0.148 "
        "deg/m, cars and ghosts unchanged (docs/visual_objects.md)", "deg", lo=0.0, hi=360.0)
    recenter_min_stereo_fraction: float = param(
        0.2, "no re-centring while at most this fraction of the confirmed points were ever seen "
        "in stereo (0: off): the rest hold guessed depths (the ground contact, their few stereo "
        "neighbours'), scattered by metres and drifting in the windows, and their median jumped "
        "between depth groups (crowded s6's car 15, queued behind two nearer cars and hidden "
        "from the right camera: 1-4 m moves per frame, the track 5 m short, 0.04 of its "
        "frames). 32 simulated sequences: files 150 -> 151 of 152 cars, DIS 151 -> 152, ghosts "
        "1 / 0 unchanged, aligned ATE 0.067 -> 0.065 / 0.072 -> 0.071 m; the classical row and "
        "five unseen seeds unchanged; five more: the same cars and ghosts, one failing queued "
        "car matched to its neighbour's track (docs/visual_objects.md). 0.4 raised crowded "
        "s7's aligned ATE 0.061 -> 0.092 m",
        "fraction", lo=0.0, hi=1.0)
    final_smoothing: bool = param(
        True, "when the run ends, every track is refined once more in one problem: all its rows, "
        "every observation of its points (culled ones too), e_const, e_link, e_head and the "
        "LiDAR terms, camera poses fixed at the refined trajectory (the paper's global BA of the "
        "object terms; the sliding window sees 8 frames and freezes the rows it leaves, with "
        "a far car's birth transient in them). result.objects keeps the online poses as "
        "T_w_o_online; the time is after_loop_ms. Six simulated sequences, online -> smoothed: "
        "camera only RPE_r 0.256 -> 0.229 deg/m, aligned ATE 0.136 -> 0.092 m (urban 0.19-0.27 "
        "-> 0.12-0.15); oracle boxes RPE_r 0.205 -> 0.146, canonical ATE 0.089 -> 0.094")
    smoothing_iterations: int = param(
        10, "Ceres iterations of the final smoothing per track, from the online poses: 5 left "
        "crowded s0's oracle-box RPE_r at 0.172 deg/m against 0.143 with 10", "iterations")
    smoothing_frame_observations: int = param(
        30, "the final smoothing takes a track's points longest-seen first, each while one of "
        "the frames it saw has fewer observations than this (0: every point). A crowded car "
        "tracked 100 frames has ~2000 points and 18k observations, most short-lived: with 30, "
        "100-200 points and 3-5k observations, 2x faster and better (crowded s0 oracle boxes "
        "RPE_r 0.204 -> 0.143 deg/m, aligned ATE 0.047 -> 0.017 m)", "observations")
    smoothing_max_median_move_m: float = param(
        1.0, "a track without a canonical frame (no 3D box) whose final smoothing moves its "
        "reported rows by a median of more than this from their online poses keeps its "
        "online poses (0: never). Nothing but its keypoints and e_const place such a track, "
        "and a short one with few tracked rows can be pulled off its car as a whole: urban "
        "s13's DIS track 23 (median 2.40 m) followed the oncoming car 22 within 1-2 m online "
        "and was smoothed 3-5.5 m off it, urban s5's DIS track 44 (3.34 m): two ghosts. The "
        "other camera-only tracks the smoothing moved by more than 1.5 m anywhere (urban s1, "
        "s5, s6, s13) had medians of 0.02-0.28 m: a far birth row corrected, which the "
        "smoothing must keep", "m", lo=0.0, hi=1000.0)
    nonholonomic: bool = param(
        True, "vehicles (planar-link classes) move along their heading: the window adds "
        "e_head, the measured step across the travel axis learned from the track (not in "
        "the paper; it ties a lead car's yaw, which its rear face at 30-45 m hardly constrains, "
        "to its direction of travel)")
    lateral_sigma_m: float = param(
        0.02, "step across the travel axis allowed per frame (an origin off the rear axle in "
        "a turn is in the Huber tail). Urban seeds 0-2 RPE_r: 0.59/0.23/0.36 deg/m at 0.02, "
        "0.55/0.37/0.38 at 0.05, 0.56/0.59/0.45 at 0.1; crowded unchanged", "m/frame")
    axis_free_heading_min_step_m: float = param(
        0.0, "> 0: a vehicle without a travel axis yet (born in a turn, or not straight long "
        "enough) gets the axis-free e_head in the window: two consecutive steps, both at least "
        "this long per frame, point the same way in the object frame (sigma lateral_sigma_m), "
        "so that the yaw turns with the path the positions observe. Urban s15's car 14, "
        "turning at 45-18 m, had its yaw turned twice as fast as the car by e_const "
        "(docs/visual_objects.md, 'Unseen seeds'); 0: off", "m/frame", lo=0.0, hi=100.0)
    axis_free_heading_min_chord_m: float = param(
        0.0, "> 0: each of the axis-free e_head's two displacements spans the fewest frames "
        "that make it at least this long, so that its direction is long against the "
        "positions' noise (the residual's noise is the positions', its yaw signal grows with "
        "the chord); 0: one frame each", "m", lo=0.0, hi=1000.0)
    travel_min_path_m: float = param(
        3.0, "distance the track must have travelled before its travel axis is used (urban "
        "RPE_r 0.59/0.24/0.36 deg/m at 1.5 m, 0.59/0.23/0.36 at 3, 0.57/0.34/0.40 at 6)", "m")
    travel_min_anisotropy: float = param(
        10.0, "the travel axis is used once the largest eigenvalue of the step moments is "
        "this many times the second (steps within ~18 deg of one axis). 3 measured on 19 "
        "sequences: urban s23's far crossing car 17 RPE_r 3.95 -> 1.73 deg/m, but crowded s16's "
        "car 13 (a track in the gap before it) 5.8 deg/m, mean 0.175 -> 0.217 (files)",
        "ratio", lo=1.0)
    travel_min_straightness: float = param(
        0.5, "the travel axis is used once the net displacement is this fraction of the path: "
        "a crawling far car's steps are stereo depth jitter along the line of sight, as "
        "anisotropic as a drive, and cancel out. Urban s0 / s8 and crowded s1: tracks that "
        "drive 0.71-1.00, jittering ones 0.13-0.23 (urban s8's 2.3 km/h car, 47 m away, "
        "was smoothed 4 m deep along its jitter's axis)", "ratio", lo=0.0, hi=1.0)
    extra_keypoints: bool = param(
        True, "a second, denser ORB pass inside the object masks, and a SAD scan along the "
        "row for every object keypoint without stereo depth (paper: small and far objects "
        "keep enough points)")
    extra_keypoints_max: int = param(
        1000, "extra keypoints per frame over all object masks", "keypoints")
    extra_min_instance_keypoints: int = param(
        40, "a vehicle's mask (planar_class_ids) holding fewer keypoints after the extra pass "
        "gets a second pass of its own, with this many per such mask (0: off): the pass's "
        "budget goes mostly to the large masks of near cars (crowded seed 2: car 69, 2200 px "
        "at 18 m behind a near car, got 8-11 of the 1000 and 1-6 with depth, never a "
        "cluster; its mask alone holds 58 corners). Ten sequences, camera alone: 43 -> 44 of "
        "47 cars tracked, ghosts 4 -> 4, mean aligned ATE 0.072 -> 0.078 m; with the LiDAR "
        "unchanged. 20 changed nothing", "keypoints", lo=0, hi=100000)
    extra_min_instance_area_px: int = param(
        1000, "... when its mask covers at least this many pixels: without the floor (40 "
        "keypoints, ten sequences, camera alone) 45 cars, but the far cars' small masks took "
        "wrong depths and the mean aligned ATE went 0.072 -> 0.100 m (urban s0 car 11: "
        "0.04 -> 0.38 m)", "px", lo=0, hi=100000000)
    extra_keypoint_levels: int = param(
        2, "pyramid levels of the extra pass: far objects are small, coarse levels hold "
        "nothing of them", "levels", lo=1, hi=32)
    extra_fast_threshold: int = param(
        7, "FAST threshold of the extra pass (the frame's is 20): car paint is low-contrast",
        "grey levels", lo=1, hi=254)
    extra_cell_px: int = param(10, "FAST retry cell of the extra pass", "px", lo=8, hi=4096)
    extra_min_spacing_px: float = param(
        3.0, "an extra keypoint this close to a keypoint of the frame is dropped", "px")
    extra_min_depth_m: float = param(
        1.5, "closest depth of the SAD scan (its cost grows with the disparity range)", "m")
    extra_max_sad_cost: float = param(
        0.7, "SAD scan: accepted zero-mean SAD over the window's contrast")
    extra_sad_uniqueness: float = param(
        0.7, "SAD scan: the best cost must be below this times the second-best minimum")
    left_right_check: bool = param(
        True, "with extra_keypoints: every object keypoint's stereo match is checked back "
        "from the right image, and dropped when the right window's best match in the left "
        "row is elsewhere. Objects occlude each other differently in the two cameras (0.54 m "
        "apart): a car queued behind another, or far behind a near one, is partly hidden in "
        "the right image only, and its points got the occluder's depth (crowded seed 1, car "
        "17: stereo median 22-25 m at a true 13.7 m; urban seed 0: far oncoming cars)")
    left_right_tolerance_px: float = param(
        2.0, "left-right check: largest distance between the keypoint and the way back. "
        "Urban seed 0, object keypoints against the simulator's disparity: 2 removes 833 of "
        "the 1434 matches off by over 1 px (and 10 %), losing 2.5 % of the 69 k good ones; "
        "1 removes 871 and loses 3.0 %", "level px", lo=0.0, hi=100.0)
    instance_pixel_stereo: bool = param(
        True, "with extra_keypoints and an instance image: an object keypoint of "
        "instance_pixel_class_ids whose SAD window also covers pixels of other instances or of "
        "the background is matched again over the whole disparity range on its own instance's "
        "pixels only, and loses its depth when that match is rejected. A person is thinner "
        "than the 15 px window: beside a textured background its points took the background's "
        "disparity (urban seed 4: a pedestrian beside a nearer tree trunk, 1.5-3 m short; urban "
        "seed 1: one at 40-50 m, 1.3-1.5 m beyond; both ghost tracks, both gone)")
    instance_pixel_class_ids: list[int] = param(
        [24, 25], "classes of instance_pixel_stereo (Cityscapes person, rider). Not vehicles: "
        "a car is wider than the window, and on its outline the contrast with the background "
        "is what makes the window distinctive. With every object class, urban seed 3's lead "
        "car (followed at ~30 m) lost 17 % of its frames and its aligned ATE went 0.16 -> 0.62 m")
    instance_pixel_min_fraction: float = param(
        0.3, "instance_pixel_stereo: a window with a smaller share of its pixels on the "
        "keypoint's instance keeps its depth (too few pixels to match). At 0.5 neither ghost "
        "above is removed: a person's windows hold 30-50 % of its pixels", "fraction",
        lo=0.0, hi=1.0)
    pulled_nearer_check: bool = param(
        True, "a vehicle keypoint at least pulled_nearer_min_depth_m away whose SAD window also "
        "covers another vehicle (and at least instance_pixel_min_fraction of it its own) is "
        "matched again on its own vehicle's pixels; when those match more than "
        "pulled_nearer_max_px farther, the nearer vehicle's texture made the match and it loses "
        "its depth (a rejected own-pixel match keeps it). Urban seed 12: a parked car at 46-50 m "
        "seen between two nearer cars was tracked 1.4 m short, a ghost in both flows; 22 "
        "sequences: ghosts 2 -> 1 (files) and 1 -> 0 (DIS), cars unchanged. With any other "
        "pixels in the window (not only another vehicle's) it lost urban seed 5's lead car "
        "(both flows) and seed 1's (DIS) and added ghosts on urban seeds 5 and 13")
    pulled_nearer_min_depth_m: float = param(
        35.0, "pulled_nearer_check: nearer matches are left alone. A near car has many points, "
        "and its outline against the background is what makes its windows distinctive", "m",
        lo=0.0, hi=10000.0)
    pulled_nearer_max_px: float = param(
        0.5, "pulled_nearer_check: the disparity (level-0 px) by which the match may exceed its "
        "instance pixels' match. 0.5 px is 7 % of the depth at 50 m on KITTI, the bias that "
        "makes a far car's track miss its box", "px", lo=0.0, hi=1000.0)
    pulled_nearer_occluder_class_ids: list[int] = param(
        [17, 19, 20, 21], "pulled_nearer_check: pixels of these classes (Cityscapes pole, traffic "
        "light, traffic sign, vegetation) in a window count as another object too: tree trunks "
        "and posts stand in front of parked cars. Unseen urban seed 16 (DIS): a parked car at "
        "45-59 m behind a trunk was tracked 3-4 m short, a ghost, gone with these classes; over "
        "28 sequences a wash (DIS ghosts 2 -> 2: urban seed 5's far car beside a nearer "
        "building, which no class here covers, became a ghost again), cars and errors unchanged")
    right_occlusion_check: bool = param(
        False, "a vehicle keypoint the right camera cannot see loses its depth: one left of a "
        "nearer vehicle's left edge by less than the two disparities' difference (the right "
        "camera, 0.54 m to the right, looks at it past that edge; its SAD match took whatever "
        "looked alike). Off: on 41 sequences (files / DIS) it fixed queued cars (crowded s4's "
        "car 77 RPE_r 0.67 -> 0.15 deg/m, crowded s7's car 12 aligned ATE 0.30 -> 0.07 m) but "
        "a car wholly in the strip lost its stereo to worse cues: ghosts 3 / 2 -> 5 / 3, cars "
        "192 / 193 -> 192 / 192 of 193 (crowded s3's car 16 with DIS 1.00 -> 0.41 of its "
        "frames), docs/visual_objects.md")
    right_occlusion_margin_px: float = param(
        0.5, "right_occlusion_check: the distance (level-0 px) a keypoint must be inside the "
        "hidden strip (half a pixel: the rounding of the instance masks' columns; not varied, "
        "the check is off)", "px",
        lo=0.0, hi=1000.0)
    right_occlusion_min_keypoints: int = param(
        5, "right_occlusion_check: matched keypoints an instance needs for its disparity "
        "(their median) to judge what it hides (not varied, the check is off)", "keypoints", lo=1, hi=1000000)
