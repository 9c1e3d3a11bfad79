"""The ``lidar_objects`` section of :class:`twistslam.Config`: the LiDAR fusion of the visual
object tracking (paper sec. "Injecting LiDAR scans", eq. 5-9; C++
``tracking::ObjectLidarOptions``, cpp/tracking/object_lidar_options.hpp).

It runs when a run has 3D detections (``twistslam.run(..., detector=...)``): each frame's boxes
are associated with the object clusters; a cluster's first box gives its canonical pose (the
box frame), the boxes its size (per-dimension median) and the drift-free twist e_det of its
sliding window.
"""

from __future__ import annotations

from dataclasses import dataclass

from ._settings import param


@dataclass
class LidarObjectsConfig:
    """3D detections in the visual object tracking."""

    use_detections: bool = param(True, "associate each frame's 3D detections with the clusters")
    detection_max_distance_m: float = param(
        2.0, "the paper's gate: box centre to a canonical cluster's origin, or (before it has a "
        "box) the cluster centroid's distance to the box, which a car's visible faces keep near "
        "0 while the centre lies half a car length away", "m")
    box_instance_min_returns: int = param(
        5, "a cluster's first box (which sets its object frame) must lie on the cluster's "
        "instance: of the box's LiDAR returns that project onto object masks, the most must "
        "fall on the cluster's own mask, decided once at least this many do (0: off). A partly "
        "hidden car's stereo points straddle the car in front of it, and that car's box then "
        "moved the cluster onto it (crowded seed 4: a car untracked for 45 frames). Ten "
        "simulated sequences (seeds 0-4), with box_instance_max_distance_m: cars tracked "
        "classical 45 -> 48 of 49, oracle 42 -> 47; ghosts 8 -> 6 and 10 -> 6 (with the own-"
        "mask box the only one a cluster may take, box_instance_max_distance_m; "
        "docs/lidar_objects.md). Five returns: not tuned", "returns", lo=0, hi=1000000)
    box_instance_max_distance_m: float = param(
        6.0, "a box whose returns fall on the cluster's own mask is associated with it up to "
        "this far (cluster centroid to box) instead of detection_max_distance_m: the mask says "
        "it is the same car, and a far cluster's stereo depth can be metres off; it is then the "
        "only box the cluster may take (a nearer box whose returns were too few to vote won "
        "over it: oracle urban seed 0, 5/6 -> 6/6 cars). Not tuned: 6 m is 1.5 car lengths "
        "(docs/lidar_objects.md, association)", "m", lo=0.0, hi=1000.0)
    own_mask_boxes_for_canonical: bool = param(
        True, "the rule above for a canonical vehicle track's later boxes too (off: only its "
        "first box; people keep the gate: a person's narrow mask catches the returns of what "
        "stands behind it, crowded seed 0 got a ghost 2 m off its pedestrian): a far oncoming "
        "car's visual motion fell 0.1-0.2 m/frame short, its boxes drifted "
        "beyond detection_max_distance_m and none came back for 20 frames (urban seed 11, "
        "400 frames: its heading, set by one box mod pi, stayed 165 deg off)")
    mask_max_depth_ratio: float = param(
        1.3, "a cluster given an instance by mask overlap alone (too few matched points on it) "
        "loses it when its points projected on the mask lie this many times nearer or farther "
        "than the mask's LiDAR returns (median depths; 0: off): the flow and the masks follow "
        "the image, and a car passing in front of a far cluster covers its points (urban seed "
        "0, classical detector: a parked car's cluster at 51 m took oncoming car 12's mask at "
        "38 m, a ratio of 1.34, and no cluster started on car 12 for 17 frames). 1.3 leaves "
        "room for a far car's stereo error (4 m at 42 m); not tuned. Ten simulated sequences: "
        "classical cars 48 -> 49 of 49, ghosts 6 -> 4; oracle ghosts 6 -> 4, canonical ATE "
        "0.191 -> 0.100 m (docs/visual_objects.md, association). A new cluster's stereo "
        "points more than this ratio in front of its mask's LiDAR depth are left out (SAD "
        "matches at the search's near end seeded two ghosts 1-2 m before the camera: crowded "
        "s4, classical detector)", "ratio",
        lo=0.0, hi=1000.0)
    mask_min_returns: int = param(
        1, "a mask with fewer LiDAR returns has no LiDAR depth (the two tests above are "
        "skipped). 3 raised oracle urban s3's canonical ATE from 0.24 to 1.14 m (far car 12 "
        "kept a mask that was not its own)", "returns", lo=1,
        hi=1000000)
    instance_lidar_depth: bool = param(
        True, "a new (or re-seeded) vehicle cluster with too few stereo points places its "
        "keypoints without depth at the depth the LiDAR returns on its own mask give them (a "
        "local plane through those near each keypoint) when that completes the seed, before "
        "the ground-contact and nearest-stereo cues; such a new cluster reports its rows once "
        "tracked. A car behind a nearer one shows a sliver whose stereo mostly fails: with the "
        "check below, sixteen simulated sequences (default row) went 70 -> 71 of 74 cars "
        "tracked >= 90 % (crowded s1's car 17 0.46 -> 0.98), ghosts 1 -> 1, means RPE_t 0.0385 "
        "-> 0.0412 m/m (two hard cars newly counted), RPE_r 0.153 -> 0.153 deg/m, ATE 0.066 -> "
        "0.064 m; real KITTI 0001 camera alone object ATE 0.687 -> 0.648 m "
        "(docs/visual_objects.md)")
    instance_lidar_max_depth_m: float = param(
        30.0, "... only for a mask whose returns' median depth is within this (as "
        "visual_objects.depth_fill_max_depth_m): beyond, a far car's few returns gave poor "
        "local planes and started it early (urban s0's oncoming car 10: RPE_r 0.065 -> 0.72 "
        "deg/m; with the oracle boxes its heading flipped)", "m", lo=0.0, hi=10000.0)
    instance_lidar_max_depth_error: float = param(
        0.2, "a stereo point of an instance whose depth is farther than this fraction from the "
        "median depth of the LiDAR returns on that mask within 8 px of it joins no cluster (a "
        "match on a nearer car's edge; 0: off). Without it the LiDAR completion lost car 17 "
        "(its cluster sat on the occluder's edge: 70 of 74 cars); 0.1 kept it but made a ghost "
        "(2 instead of 1) and raised RPE_t to 0.0427", "fraction", lo=0.0, hi=10.0)
    keypoint_lidar_depth: int = param(
        0, "vehicle keypoints take the depth of the LiDAR returns on their own mask: 0 off, 1 "
        "those without a stereo depth, 2 also stereo ones farther than "
        "instance_lidar_max_depth_error from it, 3 every one with returns near it. Off by "
        "default (measured 2026-12-02, docs/visual_objects.md): mode 2 within 30 m lowered the "
        "camera-alone means on sixteen simulated sequences (RPE_t 0.0416 -> 0.0373-0.0388 m/m, "
        "RPE_r 0.166 -> 0.150-0.153 deg/m) and tracked crowded s6's car 15, but either lost "
        "urban s7's lead car (local plane) or, from the returns' median, raised real KITTI "
        "0001's camera-alone object ATE 0.47 -> 0.75 m (masks from boxes take background "
        "returns)", "mode", lo=0, hi=3)
    keypoint_lidar_max_depth_m: float = param(
        80.0, "... only where that depth is within this; 30 m (as instance_lidar_max_depth_m) "
        "was measured: without a limit, heavily occluded far parked cars started 2-4 m off "
        "(two ghosts, urban s4 and s5)", "m", lo=0.0, hi=10000.0)
    keypoint_lidar_plane: bool = param(
        False, "... the depth of a local plane through those returns (the camera's LiDAR depth, "
        "nearest layer) instead of their median within 8 px")
    keypoint_lidar_agreement: float = param(
        0.0, "... only where the local plane's depth and the returns' median agree within this "
        "fraction (0: no test)", "fraction", lo=0.0, hi=10.0)
    detection_min_score: float = param(
        -1e9, "detections below this score are ignored; the detector's own threshold decides "
        "by default (scores are not comparable across detectors)")
    canonical_pose: bool = param(
        True, "the first associated box sets the object frame (origin at the box centre, x "
        "along the length): poses are canonical, not the cluster's first camera-aligned frame")
    heading_from_motion_m: float = param(
        1.5, "once a canonical track has moved this far from where its box was first seen, a "
        "frame whose x axis (front) points against the motion is turned around: a LiDAR box's "
        "heading may be off by pi (the classical detector's is only known mod pi), a car drives "
        "forward. A canonical track moves with its boxes (~0.1 m scatter), so 1.5 m is >10 "
        "sigmas; classical detector, urban / crowded seeds 0 and 2: yaw error 25 / 0.5 / 0.5 / "
        "45 deg at 3 m, 5.9 / 0.5 / 0.5 / 45 at 1.5 m (a slow car never moved 3 m)", "m")
    heading_motion_min_sigmas: float = param(
        5.0, "... and at least this many standard errors of that distance (the box centres' "
        "scatter about their fitted line, objects/box_travel.hpp): a far car's boxes scatter by "
        "~0.6 m, and a car that crept 0.5 m at 55 m seemed to have driven 1.5 m backwards (urban "
        "s4's car 20, turned around for good: yaw 180 deg). Simulated 12-box tracks at 0.6 m "
        "scatter: a parked car passes 4 / 5 / 6 sigmas in 0.8 / 0.1 / 0.0 % of trials, one "
        "driving 0.5 m/frame in 98 / 95 / 91 % (the check repeats every frame: a rare pass "
        "still turns a track)", "sigmas", lo=0.0, hi=1e6)
    heading_motion_max_angle_deg: float = param(
        45.0, "... and within this angle of the frame's x axis, either way (a car drives along "
        "its length; 45: more along it than across). Urban s11's car 22, stopped across the "
        "camera's road at 44-48 m: its first three oracle boxes lay 3 m short and faced "
        "backwards, the line through its boxes ran 3 m sideways, and the sign of that run "
        "against the axis turned the frame around for good (yaw 180 deg). Measured in "
        "docs/lidar_objects.md", "deg", lo=0.0, hi=90.0)
    side_view_min_angle_deg: float = param(
        60.0, "a box whose length is the detector's prior (a partly seen car) knows its length "
        "axis only if that axis lies at least this far from the camera's line of sight to it: "
        "the seen face then ran along the car, a side. Nearer the line of sight the axis was "
        "laid away from a face seen end-on, a rear, or a partly hidden side read as one. A "
        "track whose frame only such boxes set takes the axis of the first box that saw a "
        "side (a measured length outranks both). The classical detector lays a rear's length "
        "within 45 deg of the line of sight; 60 leaves its heading scatter a margin. Urban "
        "s11's car 22, stopped across the road 35-45 m ahead with half its side hidden: its "
        "rear-read boxes lay 14-18 deg from the line of sight, its side boxes 70-75 deg", "deg",
        lo=0.0, hi=90.0)
    heading_from_votes: bool = param(
        True, "until it has moved heading_from_motion_m, a canonical track faces the way most of "
        "its boxes' own headings do (one box, one vote; the classical detector's point-extent "
        "boxes know the heading mod pi only and do not vote): the first box alone set it, and "
        "the oracle's 2 % boxes off by pi turned a car waiting at a light around for good "
        "(urban s4's car 20, yaw 180 deg in every frame)")
    heading_from_profile: bool = param(
        True, "a canonical vehicle track's own returns vote on its heading with the boxes "
        "(heading_from_votes): each frame's object scan that spans front_profile_min_span of its "
        "length gives the hood-minus-trunk gap (detection/front_profile.hpp) in the object frame; "
        "once their mean is clear, each view is one vote. The classical detector tells a front "
        "only from one clear view (0.4 m): classical urban s13's car 21, stopped across the road "
        "at 11-29 m, gave 0.03-0.47 m per view (mean 0.24 m), one box told it wrong, and it was "
        "tracked turned around (yaw error 180 deg) without the views' votes")
    front_profile_min_views: int = param(
        5, "views before the profile decides: a mean of fewer is too unsure", "views")
    front_profile_min_span: float = param(
        0.9, "a view counts when its returns span this fraction of the track's length: a car "
        "seen from one end shows its greenhouse but not the far bumper (the gap there is ~0); "
        "the detector's prototype on labelled real KITTI cars used 85 %", "fraction")
    front_profile_min_sigmas: float = param(
        3.0, "the views' mean must lie this many standard errors from 0 (a view scatters by "
        "~0.15 m)", "sigmas")
    front_profile_min_difference_m: float = param(
        0.1, "... and this far: sedans' hoods are ~0.2-0.5 m longer than their trunk plus rear "
        "window slope, vans' and hatchbacks' more", "m")
    road_side_heading: int = param(
        1, "a box that knows its heading mod pi only (the classical detector's) votes with the "
        "heading a parked car has on its side of the camera's lane: 1 right-hand traffic (beside "
        "the camera on its right a car faces the camera's travel, on its left the other way; "
        "parking against the traffic is not allowed in Germany, KITTI's country), -1 left-hand "
        "traffic, 0 no vote. A parked car never moves, so nothing else gives its front: on real "
        "0001 the classical detector's boxes of cars along the road faced backwards (124 of "
        "127 matched boxes; 31 with the vote, median yaw error 178 -> 2 deg)", lo=-1, hi=1)
    road_side_min_lateral_m: float = param(
        2.0, "road_side_heading: a box whose centre lies nearer the camera's path (sideways, in "
        "the camera frame) gives no vote: a car ahead or behind in the camera's own lane", "m")
    road_side_max_lateral_m: float = param(
        8.0, "road_side_heading: nor does one farther aside, off the camera's road (a two-lane "
        "road's far curb lies ~6-7 m aside): real 0001's three cars 20-26 m to the left, in "
        "another carriageway or a car park, face the camera's way", "m")
    road_side_max_angle_deg: float = param(
        30.0, "road_side_heading: a box whose length axis is farther off the camera's direction "
        "gives no vote (parked across, or turning)", "deg", lo=0.0, hi=90.0)
    cluster_turn_max_deg_per_frame: float = param(
        5.0, "a camera-only track whose rows turned faster than this (their mean over the "
        "frames before its first box) made the turn up from a few far points: the first box "
        "gives those rows its heading and keeps their positions (a car turns <= ~3 deg/frame "
        "at 10 Hz; the simulator's sharpest onset is 3.3). Measured 2026-12-02, 5 against 0, urban "
        "seeds 0 2 5 8 12 and crowded 0 3 with the classical detector: aligned RPE_t 0.0300 -> "
        "0.0280 m/m, RPE_r 0.153 -> 0.124 deg/m, yaw 0.55 -> 0.40 deg (urban s0's car 11 keeps "
        "its boxes); oracle boxes within 0.002. 0: never",
        "deg/frame", lo=0.0, hi=180.0)
    refine_canonical: bool = param(
        True, "each new box re-anchors the canonical frame to the weighted mean offset of all "
        "the track's boxes to their poses: the first box alone leaves its noise (the "
        "simulator's oracle ~0.1 m, ~2 deg) in every pose of the track")
    refine_min_range_m: float = param(
        5.0, "a box's weight in that mean is 1 / max(range, this)^2: box centres scatter in "
        "proportion to range (sparser returns); nearer, partial views and truncation, not range, "
        "limit them", "m")
    refine_min_shift_m: float = param(
        0.01, "a mean offset smaller than this (and turned less than refine_min_turn_rad) "
        "leaves the frame as it is: below the ATE's centimetre, re-expressing every point is "
        "work for nothing", "m")
    refine_min_turn_rad: float = param(0.002, "0.1 deg, see refine_min_shift_m", "rad")
    refine_min_agreement: float = param(
        0.6, "the frame is only refined while at least this fraction of the track's boxes lie "
        "within 1 m / 15 deg of their mean offset: boxes that disagree mean the tracked poses "
        "drift (a far cluster's wrong twist), and refining would chase them. Oracle boxes, urban "
        "s1 det row: yaw error 46 deg (a track turned by chasing) -> 2.0 at 0.6; at 0.8 urban s0 "
        "det-reg RPE_r rose 0.31 -> 0.50 deg/m (0.34 at 0.6)", "fraction")
    refine_min_boxes: int = param(
        5, "the frame is refined only once the track has this many boxes: two or three boxes "
        "of a new far track agree by chance while its first poses still swing (oracle urban s1, "
        "an oncoming car at 45 m: the third box turned the frame by 22 deg)", "boxes")
    duplicate_margin_m: float = param(
        0.3, "two tracks on one car (a second cluster on it, seeded on a wrong box): a track "
        "whose origin lies inside another canonical track's box grown by this margin, in the "
        "same frame, is not reported there if it has fewer boxes (the other one, with more, is "
        "the car). A box's centre scatters by 0.1-0.3 m; cars side by side are >= 1.8 m apart "
        "centre to centre, so a 0.3 m margin never joins two cars. Oracle urban s1: a 2-box "
        "duplicate track turned by 170 deg was the car's main track. < 0: never", "m")
    backfill_frames: int = param(
        10, "a new canonical track takes, as its rows before its first frame (reported, never "
        "tracked or smoothed), the boxes no track took in up to this many earlier frames that "
        "line up with its first box (objects/box_chain.hpp; 0: off): a cluster starts only once "
        "its mask holds enough stereo points, while the detector may box a far, dark or queued "
        "car frames earlier (crowded s1's car 17: tracked from frame 38, boxed from 31)",
        "frames", lo=0, hi=1000)
    backfill_first_gate_m: float = param(
        3.0, "the first step back has no velocity: its box within this of the first box (a car "
        "at 100 km/h moves 2.8 m a frame)", "m", lo=0.0, hi=100.0)
    backfill_gate_m: float = param(
        1.0, "later steps: within this of the constant-velocity prediction (oracle boxes "
        "scatter by 0.1-0.6 m with range)", "m", lo=0.0, hi=100.0)
    backfill_ambiguity_m: float = param(
        1.0, "the nearest box must be this much nearer than the next one, or the chain stops "
        "(two cars side by side are >= 1.8 m apart)", "m", lo=0.0, hi=100.0)
    see_through_min_rays: int = param(
        10, "a canonical track without a box this frame is not reported when at least this "
        "many LiDAR returns lie beyond its box on rays crossing it (a car is where its returns "
        "are; rays pass through where no car is; 0: off): oracle urban s4's ghost, a second "
        "cluster on a parked car tracking points 3-4 m beyond it for 45 frames. A hidden car "
        "has rays ending before it: no verdict", "returns", lo=0, hi=1000000)
    see_through_ratio: float = param(
        3.0, "... and at least this many times the returns inside the box (a real car's box "
        "partly off its car still holds many)", "ratio", lo=0.0, hi=1e6)
    see_through_shrink_m: float = param(
        0.3, "the box shrinks by this on every side for the crossing test: the rays are cast "
        "from the camera, ~0.3 m from the LiDAR's origin on KITTI, and a box's own error "
        "(0.1-0.3 m) must not let rays graze it", "m", lo=0.0, hi=10.0)
    lidar_check_max_ratio: float = param(
        0.04, "a vehicle track without a canonical frame (camera-only) whose points lie nearer "
        "than the LiDAR returns around them on its mask, by a median over its rows of more "
        "than this fraction of their depth (and lidar_check_min_offset_m), is not reported in "
        "its rows without a box: far cars' stereo corners on a nearer occluder's edge take part "
        "of its disparity (urban s5's parked car 24, tracked 4-5 m short at 45-57 m, a ghost: "
        "1.060). On eight simulated sequences' camera-only vehicle tracks the medians above "
        "1.02 were 1.028 (a car it follows, 0.9 m), 1.056 and 1.060 (a parked car tracked "
        "1.3-3.7 m off, and the ghost); 0: off. Single rows cannot decide: a car's points on "
        "its rear edge and the returns on its roof differ by metres in rows that are on their "
        "car (2 m hid 31 such rows for 22 rows off every object)", "ratio", lo=0.0, hi=10.0)
    lidar_check_min_offset_m: float = param(
        1.5, "... and by a median of more than this (m): within it a track stays on its car "
        "(0.9 m above)", "m", lo=0.0, hi=1000.0)
    lidar_check_max_far_ratio: float = param(
        0.08, "the other side of the same test: a camera-only vehicle track whose points lie "
        "beyond the returns around them by a median of more than this fraction of their depth "
        "(and lidar_check_min_far_offset_m) is not reported in its rows without a box. Such a "
        "track moves along the line of sight, which its projections barely show: urban s8's "
        "track 36, born on a parked car at 45 m, drove away at 1.1 m/frame (median 0.880, "
        "-6.3 m), urban s2's DIS-flow ghost 27 (0.900, -3.5 m). Twice the near side's bounds: "
        "no stereo failure puts points long, but returns of an occluder at a mask's edge read "
        "short. Twelve simulated sequences (urban 0 2 3 5 8 12, crowded 0-4 8), files and DIS "
        "flow, tracks of 5+ checked rows: the other far-side medians 0.926 (-2.85 m, a track "
        "on another object) and 0.955-1.0; 0: off", "ratio", lo=0.0, hi=1.0)
    lidar_check_min_far_offset_m: float = param(
        3.0, "... and by a median of more than this (m)", "m", lo=0.0, hi=1000.0)
    lidar_check_min_rows: int = param(
        5, "checked rows before the track's medians decide (the ghost-track length the "
        "evaluation counts)", "rows", lo=1, hi=1000000)
    lidar_check_min_returns: int = param(
        5, "fewer LiDAR returns on the mask: the row is not checked", "returns", lo=1,
        hi=1000000)
    lidar_check_min_points: int = param(
        3, "fewer of the track's points on its mask with returns around them (3 within 8 px): "
        "the row is not checked", "points", lo=1, hi=1000000)
    far_lidar_align_min_depth_m: float = param(
        30.0, "the final rows of a camera-only vehicle track farther than this move along their "
        "lines of sight by the median, over the track's rows, of the LiDAR returns' depth over "
        "its points' (each row: the returns on its instance mask within 8 px of each point, as "
        "lidar_check_*). Beyond ~30 m a stereo depth is good to 1-3 m and a far car's matches "
        "lean one way for many frames; its 20-50 returns measure it to centimetres. 0: off. "
        "Measured (2026-12-06) on 32 simulated sequences, files / DIS flow: see "
        "docs/visual_objects.md, 'Far rows at the LiDAR's depth'", "m", lo=0.0, hi=1000.0)
    far_lidar_align_ramp_m: float = param(
        15.0, "... the scale grows in from far_lidar_align_min_depth_m over this many metres "
        "of depth, so that no row jumps where it starts (applied at full strength from 30 m, "
        "a prototype on urban s19 raised that sequence's RPE_t 0.021 -> 0.030 m/m; ramped over "
        "15 m, 0.021 -> 0.023)", "m", lo=0.0, hi=1000.0)
    far_lidar_align_max_ratio: float = param(
        0.15, "... a row's median ratio counts only within this of 1: far stereo errors are a "
        "few per cent (urban s5's ghost 6 %), a larger one is an occluder's or the "
        "background's returns", "fraction", lo=0.0, hi=1.0)
    far_lidar_align_min_rows: int = param(
        3, "... rows with a ratio before the track's median moves it", "rows", lo=1,
        hi=1000000)
    far_lidar_align_surface_floor: bool = param(
        True, "... a move nearer stops where the track's origin (its points' median, on the "
        "faces the camera sees) meets the near face its returns measure "
        "(far_lidar_align_surface_quantile): the ratio goes below 1 also when a far track's "
        "lagging depth motion smeared its points behind its origin, and then pulled the origin "
        "in front of the car (urban s26's lead car at 55-66 m: returns on its rear at 56 m, "
        "origin moved 56.9 -> 54.7 m, a ghost). Measured: docs/visual_objects.md, 'The "
        "alignment stops at the LiDAR's surface'")
    far_lidar_align_surface_quantile: float = param(
        0.1, "... that face: this quantile of the depths of the returns on the row's mask (the "
        "median over the track's rows of quantile / origin depth). With the median the floor "
        "bound too often: a car seen obliquely has returns along its side, deeper than its "
        "origin (42 sequences "
        "x 2 flows: 90 car rows changed by more than 5 mm, either way; with 0.1, 29)",
        "fraction", lo=0.0, hi=1.0)
    far_lidar_align_surface_margin: float = param(
        0.01, "... the origin may come this fraction of its depth nearer than that face (0.5 m "
        "at 50 m): the origin is a median of stereo points and sits on the face only to their "
        "noise; without it the floor held back right moves of 0.4-2 % (urban s0's car 10, "
        "urban s11's car 11: aligned ATE 0.03 -> 0.10 and 0.10 -> 0.19 m). With it, on 42 "
        "sequences, only urban s26 (its two ghosts gone) and urban s5's car 0 changed",
        "fraction", lo=0.0, hi=1.0)
    far_lidar_align_surface_lift: bool = param(
        True, "... and an origin already in front of that face (less the margin) moves onto it, "
        "by at most far_lidar_align_max_ratio: the final smoothing moves a camera-only track's "
        "points but not its origin, which then need not lie among them (urban s19's track 21, "
        "a parked car at 47-39 m: its points 1.6 % beyond the returns, its origin 2 m in front "
        "of its face, a ghost). Measured (2026-12-07) on 39 simulated sequences x 2 flows: "
        "that ghost gone, every other line identical (docs/visual_objects.md, 'An origin in "
        "front of its returns' face')")
    near_lidar_surface_lift: bool = param(
        True, "a camera-only vehicle row nearer than far_lidar_align_min_depth_m whose origin "
        "lies in front of the face its own mask's returns measured then "
        "(far_lidar_align_surface_quantile of their depths, less far_lidar_align_surface_margin) "
        "moves onto it at the end, by at most far_lidar_align_max_ratio (not where the mask "
        "reaches the image's side or bottom border: the part in view need not hold the car's "
        "nearest faces; urban s35's car 8 passing the camera at 5-8 m). Crowded s21's DIS ghost 27, on a car seen "
        "between two nearer ones, started 2.2 m in front of its rear at 15.7 m and reached it "
        "over 20 frames: too little for the LiDAR check's track medians (0.9 m). Measured: "
        "docs/visual_objects.md, 'A near origin in front of its returns' face'")
    near_lidar_surface_window_rows: int = param(
        7, "... each row's floor (its face over its origin's depth) is the running median of "
        "this many rows' around it, as the free-link rows' ratios, so that a row whose mask's "
        "returns meet an occluder's edge does not move alone. 1 (each row by its own) measured "
        "the same on 47 simulated sequences: same cars and ghosts, no car's aligned ATE 1 cm "
        "apart, RPE_t 0.0385 / 0.0414 against 0.0387 / 0.0416 m/m (files / DIS)", "rows", lo=1, hi=1000000)
    far_lidar_align_free_window_rows: int = param(
        7, "the final rows of a camera-only free-link track (a pedestrian, a cyclist) farther "
        "than far_lidar_align_free_min_depth_m move along their lines of sight each by its own "
        "ratio of the returns' depth over its points' (as the vehicles' rows, within "
        "far_lidar_align_max_ratio of 1), the running median over this many rows around it: a "
        "far pedestrian's track drifts row by row (urban s24's DIS ghost 18, standing at 41-25 m "
        "and tracked as walking away, its row ratios 1.01 -> 0.91), which one track-wide ratio "
        "cannot undo, and single rows meet occluders' returns on a thin mask (one row at a time "
        "moved 4 good rows off their pedestrians on urban s24 / s26 / s29; 7 rows none). 0: off. "
        "Measured: docs/visual_objects.md, 'Far pedestrian rows at their returns' depth'",
        "rows", lo=0, hi=1000000)
    far_lidar_align_free_min_depth_m: float = param(
        25.0, "... from this depth on: a pedestrian's 0.3-0.6 m body gives its track a stereo "
        "depth good to a few per cent up to ~25 m (its tracks' medians within 0.4 m of their "
        "returns there on 24 sequences), beyond which they reach 1-3 m", "m", lo=0.0, hi=1000.0)
    far_lidar_align_free_from_origin: bool = param(
        True, "... each such row's ratio is the median depth of the returns on its mask over its "
        "origin's depth, not its points' against the returns around them: a far pedestrian "
        "cluster gathers points metres before and behind its body, and its origin need not lie "
        "where its points meet the returns (urban s35's track 54: 58 points over 6.6 m, the "
        "points with returns at the returns' depth, the origin 1.2-2 m in front, a ghost). "
        "Measured: docs/visual_objects.md, 'A far pedestrian's origin against its returns'")
    far_lidar_align_free_hide_beyond: bool = param(
        True, "... and a row whose running median ratio lies beyond far_lidar_align_max_ratio "
        "of 1 is not reported (it cannot be moved there: the returns contradict it). Urban "
        "s34's track 35, a pedestrian standing at 46-41 m reported at 35-28 m (running "
        "medians 1.27-1.38), a ghost")
    far_lidar_align_max_behind_m: float = param(
        1.5, "a camera-only vehicle's far rows (beyond far_lidar_align_min_depth_m) whose "
        "origin lies more than this beyond the median depth of their mask's returns, by their "
        "own measure and by the running median over far_lidar_align_behind_window_rows rows, "
        "move nearer by the smaller excess, after the track-wide scale (0: off). Urban s40's DIS "
        "ghost 29, a parked car at 60-45 m tracked as if it drove with the camera, ended 4.3 m "
        "beyond its returns; on 8 urban sequences (3689 far rows) the rows 1-2 m beyond them "
        "all lay on their cars (109), those 2-3.5 m beyond 9 of 18 (docs/visual_objects.md, 'Far rows behind their returns')",
        "m", lo=0.0, hi=1000.0)
    far_lidar_align_behind_window_rows: int = param(
        7, "... the running median over this many rows around each row (as "
        "near_lidar_surface_window_rows: one row's stray returns do not move it)", "rows",
        lo=1, hi=1000000)
    point_extent_lengths: bool = param(
        False, "boxes that are the tight extent of their points (Detections3D.point_extent, "
        "the classical detector) are laid from their end nearer the sensor, the car's length "
        "from point_extent_length_quantile of theirs: right where the ground truth boxes are "
        "the cars' full bodies (the simulator's mesh bounds), whose far ends a LiDAR sees "
        "thinly. Off by default because KITTI's labels are drawn on the points: on real 0001 "
        "the classical boxes' lengths exceed the labels (3.8-4.1 m for a 3.77 m label), and "
        "laying them from the near end put their centres 0.087 -> 0.149 m off even with the "
        "label's length. Six simulated sequences with the classical detector: canonical ATE "
        "0.223 -> 0.189 m, 3D MOTP 84.3 -> 85.9 %, RPE_r 0.154 -> 0.164 deg/m; real 0001: "
        "ATE 0.226 -> 0.242 m")
    point_extent_length_quantile: float = param(
        0.9, "with point_extent_lengths, a car's length is this quantile of its point extents' "
        "measured lengths (they only fall short of the body: the far end of its side returns "
        "few points). Classical detector on urban s0-s1 and crowded s0, s2 (64 cars): length "
        "error -0.16 m mean / 0.20 m absolute at 0.5 (the median), -0.08 / 0.14 at 0.75, "
        "-0.01 / 0.10 at 0.9, +0.03 / 0.11 at 1.0 (the longest)", "quantile", lo=0.0, hi=1.0)
    use_detection_twist: bool = param(True, "e_det (eq. 9) in the object window")
    det_sigma_translation: float = param(
        0.2, "twist between two boxes: LiDAR box centres scatter by ~0.1-0.15 m (the simulator's "
        "oracle 0.1 m), a difference of two by sqrt(2) of that", "m/frame")
    det_sigma_rotation: float = param(
        0.05, "box headings scatter by 2-3 deg, a difference of two by sqrt(2) of that",
        "rad/frame")
    use_detection_pose: bool = param(
        True, "a weak prior of each canonical pose on its box (not in the paper: twists alone "
        "let the canonical pose drift; the box is drift-free)")
    det_pose_sigma_translation: float = param(
        0.3, "weak: 2-3 times the box centre's scatter, so the twists keep the trajectory's "
        "shape", "m")
    det_pose_sigma_rotation: float = param(
        0.1, "2-3 times the heading scatter. 0.03 (with det_sigma_rotation 0.015) lowered the "
        "final RPE_r on simulated seeds 0-3 by 4-5 % but made online tracks follow the oracle "
        "boxes' 2 deg heading noise: urban s0's first 15 frames, oncoming car 12 online RPE_t "
        "0.03 -> 0.35 m/m, car 4 RPE_r 0.066 -> 0.100 deg/m", "rad")
    huber_det: float = param(2.0, "a wrong association or a merged box is an outlier", "sigmas")
    det_sigma_reference_range_m: float = param(
        20.0, "> 0: beyond this range every e_det and detection-pose sigma grows in proportion "
        "to the box's range (a far car gives the detector fewer points); 0: one sigma at every "
        "range. The real PointRCNN boxes of KITTI tracking 0000-0020 against label_02 (16k cars) "
        "scatter flat to ~20 m, then about linearly (centre RMS 0.14 / 0.11 / 0.15 / 0.20 / 0.28 m "
        "at 0-10 / 10-20 / 20-30 / 30-40 / 40-60 m, heading p90 2.5 / 1.8 / 2.1 / 2.6 / 5.1 deg). "
        "Measured 2026-12-02 at 20 against 0, with cluster_turn_max_deg_per_frame on, urban seeds "
        "0 2 5 8 12 and crowded 0 3: oracle boxes aligned RPE_t 0.0284 -> 0.0246 m/m, canonical "
        "ATE 0.097 -> 0.081 m; classical detector aligned RPE_t 0.0280 -> 0.0254 m/m, canonical "
        "ATE 0.205 -> 0.196 m, RPE_r 0.124 -> 0.127 deg/m; real 0001 within 3 mm "
        "(docs/lidar_objects.md)", "m")
    use_registration: bool = param(
        True, "e_reg (eq. 6-7, 9): GICP between the object scans of consecutive frames (the "
        "scan's points inside the canonical box)")
    scan_margin_m: float = param(
        0.3, "the box grows by this on each side for the object scan: box and pose errors "
        "(~0.1-0.2 m) must not cut the car's outline off", "m")
    scan_ground_clearance_m: float = param(
        0.15, "points this close above the box's bottom are road, not car (LiDAR range noise "
        "~2 cm, the road plane under a box within ~0.1 m)", "m")
    min_scan_points: int = param(
        30, "an object scan with fewer points is not registered: GICP's 20-neighbour "
        "covariances need several times that")
    reg_max_rmse_m: float = param(
        0.3, "a registration whose inlier RMS point distance exceeds this is refused: a LiDAR "
        "samples a car at 10-30 m every 0.1-0.3 m, so even aligned scans' nearest neighbours "
        "lie ~0.1 m apart (0.11 m in the tracker's test scan)", "m")
    reg_min_inlier_fraction: float = param(
        0.5, "... or one that matched fewer of the new scan's points within GICP's "
        "correspondence distance (a scan merged with another object's points, a wrong box)")
    reg_sigma_translation: float = param(
        0.03, "fixed e_reg sigma when reg_sigma_from_information is off: GICP of car scans, "
        "1-3 cm per pair (benchmarks/bench_gicp.py)", "m/frame")
    reg_sigma_rotation: float = param(
        0.005, "as reg_sigma_translation: GICP of car scans, 0.1-0.3 deg per pair", "rad/frame")
    reg_sigma_from_information: bool = param(
        True, "each registration's e_reg sigmas follow GICP's own uncertainty (the marginal "
        "standard deviations of its inverse information, translation at the object's centre, "
        "rotation about the link's axes) times a scale: a far car's scan of 50 points is ~20x "
        "less certain in yaw than a near car's of 2500 (simulated pairs: median yaw error 0.03 "
        "deg at 0-10 m, 0.44 deg at 30-45 m), which one fixed sigma cannot weigh: it was too "
        "tight for far urban cars and too loose for near crowded ones")
    reg_information_scale_translation: float = param(
        1.0, "error / information standard deviation at the centre, median over consecutive "
        "car-scan pairs: 0.32 simulated, 0.6-0.9 on real 0001 beyond 10 m against the labels; "
        "1.0 makes the median real error ~0.7 sigma", "ratio")
    reg_information_scale_rotation: float = param(
        0.5, "the same for the yaw: 0.22 simulated at every range, 0.25-0.4 on real 0001 (0.64 "
        "below 10 m, few pairs); 0.5 makes the median real error ~0.6 sigma", "ratio")
    reg_min_sigma_translation: float = param(
        0.01, "floor: real KITTI pairs end ~2 cm off the labels whatever the information says",
        "m/frame")
    reg_min_sigma_rotation: float = param(
        0.001, "floor (0.06 deg): a near car's dense scan would otherwise outweigh every other "
        "term", "rad/frame")
    reg_full_covariance: bool = param(
        True, "e_reg weighs each direction of a registered motion by GICP's own covariance "
        "along it (scaled and floored as above) instead of every direction by the largest "
        "sigma: a car seen only from behind shows one face, which pins its step along its "
        "length to ~1 cm and leaves the sideways step to ~10 cm. Cars only (planar link): a walker's "
        "scan is not rigid, and urban s10's pedestrian track drifted 0.3-1 m further off with it. "
        "Measured 2026-12-05 over 28 simulated sequences, on / off: oracle boxes aligned RPE_t "
        "0.0211 / 0.0261 m/m, RPE_r 0.115 / 0.139 deg/m, canonical ATE 0.080 / 0.091 m; classical "
        "detector 0.0180 / 0.0208 m/m, 0.103 / 0.130 deg/m, 0.198 / 0.202 m; real 0001 object ATE "
        "0.192 / 0.191 m (PointRCNN files), 0.220 / 0.247 m (classical), 3D MOTA unchanged "
        "(docs/lidar_objects.md)")
    huber_reg: float = param(2.0, "a registration to a wrong scan (merged objects) is an "
                             "outlier", "sigmas")
    keyframe_ba_terms: bool = param(
        True, "e_det, e_reg and the box prior join the keyframe BA as well, relative to its "
        "cameras (each as its use_* switch allows), whenever local_ba.dynamic_objects puts the "
        "objects there. Neutral, measured with it on (urban and crowded seeds 0-2, classical "
        "and oracle boxes): camera RPE 0.00513 / 0.00500 m per frame with / without them "
        "(classical), 0.00500 / 0.00513 (oracle), objects the same to the third digit; on by "
        "default because eq. 9's BA has them (and it acts only with dynamic_objects)")
    instance_border_px: float = param(
        0.0, "visual_objects.instance_border_px in a frame with 3D boxes: a box places its car, "
        "and a far car's corners along the nearer cars hiding it are what it has left. Six "
        "simulated sequences at 3 px against 0: oracle boxes RPE_r 0.146 -> 0.178 deg/m, "
        "canonical ATE 0.094 -> 0.108 m (urban seed 0: 6/6 -> 4/6 cars); classical boxes ATE "
        "0.223 -> 0.291 m", "px", lo=0.0, hi=50.0)
    depth_fill_below_points: int = param(
        0, "visual_objects.depth_fill_below_points in a frame with 3D boxes: a box places its "
        "car. Ten simulated sequences at 12 against 0: classical boxes 48 -> 49 of 49 cars but "
        "ghosts 0 -> 3 (far masks' clusters took false boxes beside them), oracle boxes ghosts "
        "1 -> 2", "points", lo=0)
    smoothing_keypoint_sigma_scale: float = param(
        5.0, "in the final smoothing (visual_objects.final_smoothing) of a track with LiDAR "
        "terms, its keypoints' reprojection sigmas are multiplied by this: a point's stereo and "
        "reprojection errors repeat over the many frames that see it (same texture, same sub-pixel "
        "phase), which the whole track's problem would count as independent, while the boxes and "
        "the registered scans already carry the motion. Oracle boxes, six simulated sequences "
        "(before the point quota), RPE_r 0.198 / 0.175 / 0.165 / 0.150 deg/m at 1 / 2 / 3 / 5, "
        "canonical ATE 0.106 / 0.100 / 0.100 / 0.098 m (online 0.205, 0.089); camera-only "
        "tracks keep 1: their far cars need the stereo (urban aligned ATE 0.14 at 1, 0.18-0.22 "
        "at 3)", "ratio")
