#pragma once
// Options of the classical LiDAR detector (docs/detection.md), every one with its unit and the
// reason for its default. Points are in the rectified camera frame c (x right, y down,
// z forward); "height" below means up = -y, measured from the local ground.
#include "options/option_range.hpp"

namespace twistslam::detection {

struct DetectorOptions {
  // --- region of interest ---
  // keep only points in front of the camera within fov_half_angle_deg of its axis: KITTI
  // labels (and its evaluation) only cover objects in the left image.
  bool front_only = true;
  // deg, half the horizontal field kept when front_only: the KITTI colour camera sees
  // atan(621 / 721) = 40.7 deg; 45 keeps objects straddling the image border whole.
  double fov_half_angle_deg = 45.0;
  // deg, the points are clustered within fov_half_angle_deg + this, and a box is kept if it
  // reaches into fov_half_angle_deg: a near car straddling the border, cut at the border,
  // got a box grown the wrong way (real KITTI and simulated cars at 4-9 m and 40-50 deg:
  // centre 1-2 m off, depth +1 m). Measured in docs/detection.md.
  double fov_margin_deg = 25.0;
  // m, horizontal range (sqrt(x^2 + z^2)) below which points are dropped: the ego car's own
  // body and the HDL-64's near blind zone.
  double min_range_m = 2.5;
  // m, horizontal range beyond which points are dropped: a car at 60 m gets < 40 HDL-64
  // returns, too few for a heading; KITTI's moderate class mostly lies within it.
  double max_range_m = 60.0;

  // --- ground (polar grid: azimuth segments x range bins) ---
  // m, radial length of a road bin: ~10 returns of a ring even at 40 m, while a 10 % grade
  // changes by only 0.1 m along it.
  double ground_cell_m = 1.0;
  // deg, angular width of a road segment: 1 deg is 0.7 m at 40 m, a bin about as wide as long.
  double ground_segment_deg = 1.0;
  // the k-th lowest return of a bin is its road height: a lone return below the road
  // (multipath, puddles) must not drag the road down.
  int ground_rank = 3;
  // m of height per m of range the road may rise or fall between bins: roads stay below
  // ~10 % grade; 0.15 leaves room for the bins' noise.
  double max_ground_slope = 0.15;
  // m, extra rise a bin's road may have over the last one: the HDL-64's ~2 cm noise and a
  // curb's ~0.1 m, but below a car's sill (~0.2-0.3 m), so the road never climbs onto a car.
  double ground_climb_m = 0.1;
  // m, extra drop: returns farther below the road so far are multipath (KITTI scans have
  // returns 10+ m below the road) and ignored; the road ahead may dip behind an object by
  // up to this.
  double ground_drop_m = 1.0;
  // The road behind an occluder is hidden: past a nearer return whose line of sight passes
  // above the road (the shadow line, from the camera centre), the road may rise only one
  // bin's slope (+ climb) per bin instead of the slope times the whole gap. Without it the
  // first returns past a parked car (a building face's lowest visible row, 1.1-1.6 m up)
  // became the road, and that face a car standing on it: 560 of the 3900 classical car boxes
  // on 22 simulated sequences, the masks-from-boxes row's ghosts (docs/detection.md,
  // "The road behind an occluder").
  bool hold_road_in_shadows = true;
  // m above the local road that still counts as road: the HDL-64's ~2 cm noise plus the
  // grid's slope error across a cell; curbs (~0.15 m) stay on the road side.
  double ground_margin_m = 0.25;
  // m above the road beyond which points are ignored: above the tallest class detected (a
  // 2.2 m van roof), below the tree canopies that would merge the cars parked under them.
  double max_object_height_m = 2.6;

  // --- clustering ---
  // m, side of the bird's-eye-view occupancy cells of the clustering
  double cluster_cell_m = 0.2;
  // m, the widest gap between returns of one object: cells up to ceil(gap / cell) apart are
  // neighbours. A face seen at a grazing angle has its returns spread along it: an azimuth
  // step of 0.09 deg (HDL-64) at 20 m and 10 deg of incidence leaves 0.2 m, 0.2 deg (the
  // simulator) 0.35 m; 0.6 m still separates cars parked 0.8 m apart.
  double cluster_gap_m = 0.6;
  // returns a cluster needs: below 10 no heading or size is measurable.
  int min_cluster_points = 10;
  // m, a low cluster (below) within this of a larger cluster and inside its bearings joins it
  // (a far car's bumper cut off by its hood's gap; fragment_merge.hpp); 0: off.
  double fragment_merge_gap_m = 1.5;
  // m, the vertical extent of a fragment's returns at most: a bumper and grille span ~0.2-0.8
  // m above the road, a person (1.1 m and up) or a car body more.
  double fragment_max_height_extent_m = 0.6;
  // m, the nearest range of a fragment: nearer, the hood's (trunk's) lid is hit by rings too.
  double fragment_min_range_m = 20.0;
  // m, how much higher the top of the cluster a fragment joins must be (a car's cabin over its
  // bumper: 0.5 m and more).
  double fragment_min_rise_m = 0.3;

  // --- box fitting ---
  // m above the road up to which returns shape the footprint: car bodies are vertical up to
  // ~1 m (below the windows); above, windows, roof and hood slope inwards and spread their
  // returns over the top (a 1.5 m roof seen from a 1.73 m sensor). Clusters with fewer than
  // min_cluster_points such returns use all of theirs.
  double footprint_max_height_m = 1.0;
  // deg, step of the heading search of the L-shape fit over [0, 90) deg: a 1 deg heading
  // error shifts a 4 m car's corner by 3.5 cm, below the LiDAR's own footprint.
  double heading_step_deg = 1.0;
  // m, floor of a point's distance to the nearest rectangle edge in the closeness criterion,
  // so a few returns exactly on an edge do not dominate. It must stay below the offset a
  // 2 deg tilt gives along a car's 1.7 m rear (6 cm): 0.05 m picked 2 deg off on a noiseless
  // rear view, 0.02 m the exact heading; the HDL-64's range noise is ~0.02 m.
  double closeness_floor_m = 0.02;
  // m of floor per m of range (the cluster's mean): far returns are sparse (the simulator's
  // 0.2 deg step spaces them 0.14 m at 40 m, the HDL-64's 0.09 deg 0.06 m) and a curved
  // face's few returns line up with any of several headings within that spacing; the floor
  // becomes 0.06 m at 40 m. Measured (docs/detection.md): 0.0015 cut the 20-40 m yaw p90
  // on real KITTI (12.5 -> 9.1 deg) and on the six simulated sequences (5.3 -> 3.4 deg);
  // 0.0025 worsened the simulated 40-60 m p90 (10 -> 13 deg).
  double closeness_floor_per_range = 0.0015;
  // returns used by the fit at most (a regular subsample of a larger cluster): a car at
  // 5 m has ~4000; 400 give the same heading within the step at a tenth of the cost.
  int max_fit_points = 400;

  // --- the car-size prior (KITTI training label means: l 3.88 m, w 1.63 m, h 1.53 m) ---
  // m, length given to a car whose length was not seen whole (one face, or an L shorter
  // than car_min_length_m), its far end put this far behind the visible face. The centre
  // error of a view of one face is |true length - prior| / 2; its mean over 525 real KITTI
  // car tracks (median 3.89 m) plus that over 1010 simulated cars (median 4.35 m) is least
  // at 4.1 m (0.380 m; 3.9: 0.412, 4.0: 0.388), but 4.1 dropped the real object frames' 3D
  // AP@0.7 (moderate 20.6 -> 16.2 %) where 4.0 kept it.
  double car_length_m = 4.0;
  double car_width_m = 1.65;   // m, width given to a car whose width was not seen whole
  // m, an L-shape (two faces) whose length side spans at least this shows the car's whole
  // length: it is kept rather than extended to car_length_m. KITTI car tracks are >= 3.24 m
  // long for 95 % (3.10 m: 98 %); a shorter side is taken as partly occluded. Keeping the
  // seen length (rather than growing every L to the prior) cut the real KITTI matched cars'
  // median centre error 0.23 -> 0.16 m (0001 + object frames: their 3.2-3.6 m cars).
  double car_min_length_m = 3.2;
  // deg, the LiDAR's azimuth step: an L's length side is seen whole only if consecutive
  // steps hit it less than cluster_gap_m apart at its far end (see classify.cpp); sparser, a
  // side may have been cut off (a simulated 4.87 m car at 24 m seen at ~6 deg kept 3.3 m
  // of its side). The simulator steps 0.2 deg, the HDL-64 ~0.09 deg: the coarser is the
  // safe side for either.
  double sensor_azimuth_step_deg = 0.2;
  // m, added behind the far end of an L-shape's length side: the returns of a side seen at
  // a grazing angle stop where the body rounds off towards the hidden end (measured true -
  // seen length: simulated cars ~0.4 m, real KITTI 0001 + object frames median 0.07 m).
  // 0.15 m leaves the real L-views' length unbiased (median dl -0.06 m at 0, +0.01 at 0.15)
  // and cuts the simulated ones' centre error (median 0.23 -> 0.20 m); 0.3 m overshoots real.
  double car_hidden_end_m = 0.15;
  // m, longest footprint side still taken for a car (vans up to ~5.5 m; buses and walls beyond)
  double car_max_length_m = 6.0;
  double car_max_width_m = 2.6;   // m, widest footprint side of a car (2.1 m + mirrors + noise)
  double car_min_height_m = 1.0;  // m, the lowest car roof above the road (sports cars ~1.1 m)
  // m, shortest longer footprint side of a car: its narrowest face (the rear, ~1.5 m) partly
  // occluded; thinner clusters of car height are people.
  double car_min_visible_m = 1.2;
  // m, a footprint whose shorter side is below this shows one face only (a face's returns
  // spread ~0.2 m: bumper, curved body); see cyclist_max_upper_extent_m.
  double single_face_m = 0.6;
  // m, the tallest car roof: KITTI Car labels are 1.53 +- 0.14 m high, 2.1 m is 4 sigma;
  // taller clusters are vans (their own KITTI class), trucks, bushes. Measured on real KITTI
  // (object frames + 0001): 2.4 -> 2.1 m removes half the false cars within 30 m, no true one.
  double car_max_height_m = 2.1;
  // m above the road the lowest return of an object must lie within: cars and people stand on
  // the road; floating clusters (branches, signs, overhangs) do not.
  double max_ground_gap_m = 0.7;
  // m, largest mean distance of a car's footprint returns to the nearest edge of their fitted
  // rectangle (its faces): a car's body is a shell, volumetric clutter (bushes, hedges, tree
  // clumps) fills its rectangle. Measured (docs/detection.md): true cars of real KITTI 0001 +
  // object frames at most 0.235 m (150, median 0.11), of four simulated sequences at most
  // 0.222 m (685); the real false cars within 30 m that were vegetation 0.27-0.61 m. 0.25
  // removed 12 of 82 real false cars and no true one.
  double car_max_edge_distance_m = 0.25;

  // --- front and back of a car whose whole length was seen (front_profile.hpp) ---
  // tell the front from the height profile: the box's yaw then points to the car's front
  // (Detection::heading_known); off, every yaw stays in [-pi/2, pi/2) (mod pi).
  bool front_from_profile = true;
  // fraction of the car's top height above which returns belong to the greenhouse (windows,
  // pillars, roof): below ~0.7 the hood and trunk lids join it, above ~0.9 only the roof's
  // few returns remain.
  double front_profile_upper_fraction = 0.8;
  // m, the gap from the greenhouse to the front bumper must exceed the one to the rear bumper
  // by at least this (or the other way round) to decide. Measured on the detector's cars seen
  // whole, matched to labels (docs/detection.md), told / wrong at 0.3 / 0.4 / 0.5 m: real
  // KITTI 61 / 0, 60 / 0, 58 / 0; simulated urban s0-s2 467 / 2, 422 / 0, 371 / 0. 0.4 keeps
  // most fronts with none wrong there (crowded s2's ten wrong ones are a hidden hood, which
  // tell_front's hidden-end rule handles).
  double front_profile_min_gap_difference_m = 0.4;

  // --- pedestrians and cyclists (KITTI means: pedestrian 0.84 x 0.66 x 1.76 m, cyclist
  // 1.76 x 0.60 x 1.74 m) ---
  double person_min_height_m = 1.2;  // m, a child; lower clusters are bushes and bollards
  double person_max_height_m = 2.05; // m, a tall adult; taller thin clusters are poles, trunks
  double pedestrian_max_length_m = 1.1;  // m, longest footprint side of a walking person
  double cyclist_max_length_m = 2.2;     // m, a bicycle is ~1.8 m long
  double person_max_width_m = 1.0;       // m, shortest footprint side of a person or cyclist
  // m, a one-face cluster at most cyclist_max_length_m long, at least cyclist_min_height_m
  // high, whose returns above footprint_max_height_m span less than this along it is a
  // cyclist seen from the side (a rider's torso and arms: ~0.6 m), not a car's rear (its
  // rear window spans > 1 m). Height alone cannot tell them apart: KITTI cyclists are 1.74 m
  // high, many cars 1.6-1.8 m.
  double cyclist_max_upper_extent_m = 0.9;
  // m, see cyclist_max_upper_extent_m: a far car's rear window often returns nothing (glass),
  // its upper returns then look narrow; cars of 1.5 m and less stay cars. On real KITTI
  // (object frames) the extent alone turned an occluded car at 30 m (1.37 m) into a cyclist.
  double cyclist_min_height_m = 1.5;

  // --- score ---
  // returns at which the count term of the score reaches 1 - 1/e: a car at ~25 m.
  double score_points_scale = 150.0;
  // m, mean distance of a car's returns to the fitted edges at which the fit term of the score
  // is 1/e: a clean face measures ~0.05 m, a bush or a merged pair several tenths.
  double score_edge_distance_m = 0.15;

  // --- surface roughness (surface_roughness.hpp) ---
  // A car candidate whose returns' median surface variation exceeds this is foliage (a hedge,
  // a bush), not a car; 0: off. Measured with the defaults below on the detector's car boxes:
  // real KITTI 0001 frames 0-26 and object frames 0-10, 132 judged boxes on labelled cars:
  // median 0.023, 95th percentile 0.047, the roughest 0.066 (a car at 20 m with 47 returns);
  // of 70 boxes on no labelled car, 13 above 0.08 (among them 2 of the 5 frames of a red kiosk
  // with a tree and shrubs against it, 26-32 m right of 0001's road, whose frames measure
  // 0.058-0.086); 16 simulated sequences (every 5th
  // frame): 2058 judged boxes on cars, none above 0.050. 0.08 keeps a margin of 1.2 over the
  // roughest real car (0.07 caught 4 of the kiosk's 5 frames with a margin of 1.07: too thin
  // for sequences we have not seen). Real 0001 with the classical detector: MOTA 3D 54.2 ->
  // 62.5 %, FP 10 -> 8, nothing else changed.
  double car_max_surface_variation = 0.08;
  // m, voxel of the thinning before the neighbourhoods: 10 neighbours then span ~0.3 m at any
  // range. Without it the simulator's dense near cars (3700 returns at 6 m, 1 cm range noise)
  // measured 0.09-0.1 and real cars up to 0.055: the scale, not the surface, decided.
  double surface_voxel_m = 0.1;
  int surface_neighbors = 10;   // returns per covariance
  // fewer thinned returns are too few to judge, and the car stays: with 20, a simulated car
  // at 58 m (21 returns) measured 0.083; from 30 none of the 16 sequences' cars passes 0.05
  int surface_min_points = 30;

  // --- posts read as people (person_outline.hpp) ---
  // A person whose head band is at least this wide relative to its shoulder band is a post
  // (a pole, a tree trunk) and no person (0: off). Real KITTI: labelled pedestrians
  // 0.29-0.72, the tree trunk 0001 passes 0.96-1.00; simulated people median 0.40, trunks and
  // poles 1.00 with p5 0.83-0.86 (docs/detection.md, "Posts read as people").
  double person_max_head_ratio = 0.9;
  // azimuth steps (sensor_azimuth_step_deg) the shoulder band must span for the ratio to be
  // judged: a far person is 1-2 returns wide at head and shoulders alike (simulated people
  // at 22-40 m measured 1.0)
  int person_outline_min_steps = 3;
  // m: a person or cyclist whose highest return lies within this of the LiDAR's top beam
  // (top_beam.hpp) is a post cut by the field of view and no person (0: off). The posts'
  // tops lie on the fitted beam within 0.015 m (simulated poles and trunks; real 0001's
  // trunk), people's heads 0.17 m or more below it (simulated), 0.26 m or more (real KITTI's
  // labelled pedestrians and cyclists): 0.08 leaves room for a fit 0.02-0.05 m off.
  double person_top_beam_margin_m = 0.08;
};

// Range of every option (inclusive, in the option's unit); the Python bindings and validate()
// share it.
template <typename Visit>
void for_each_option(DetectorOptions& o, Visit&& visit) {
  visit("front_only", o.front_only, 0, 1);
  visit("fov_half_angle_deg", o.fov_half_angle_deg, 1.0, 180.0);
  visit("fov_margin_deg", o.fov_margin_deg, 0.0, 180.0);
  visit("min_range_m", o.min_range_m, 0.0, 50.0);
  visit("max_range_m", o.max_range_m, 1.0, 200.0);  // m, 200 m is past any automotive LiDAR
  visit("ground_cell_m", o.ground_cell_m, 0.1, 10.0);
  visit("ground_segment_deg", o.ground_segment_deg, 0.1, 90.0);
  visit("ground_rank", o.ground_rank, 1, 100);
  visit("ground_climb_m", o.ground_climb_m, 0.0, 5.0);
  visit("hold_road_in_shadows", o.hold_road_in_shadows, 0, 1);
  visit("ground_drop_m", o.ground_drop_m, 0.0, 20.0);
  visit("max_ground_slope", o.max_ground_slope, 0.0, 2.0);
  visit("ground_margin_m", o.ground_margin_m, 0.0, 2.0);
  visit("max_object_height_m", o.max_object_height_m, 0.1, 20.0);
  visit("cluster_cell_m", o.cluster_cell_m, 0.05, 5.0);  // the grid stays below ~16M cells
  visit("cluster_gap_m", o.cluster_gap_m, 0.0, 5.0);    // at most 100 cells of reach
  visit("min_cluster_points", o.min_cluster_points, 3, 1000000);  // 3: a fit needs a shape
  visit("fragment_merge_gap_m", o.fragment_merge_gap_m, 0.0, 5.0);
  visit("fragment_max_height_extent_m", o.fragment_max_height_extent_m, 0.0, 10.0);
  visit("fragment_min_range_m", o.fragment_min_range_m, 0.0, 200.0);
  visit("fragment_min_rise_m", o.fragment_min_rise_m, 0.0, 10.0);
  visit("footprint_max_height_m", o.footprint_max_height_m, 0.0, 20.0);
  visit("heading_step_deg", o.heading_step_deg, 0.1, 45.0);
  visit("closeness_floor_m", o.closeness_floor_m, 0.001, 1.0);
  visit("closeness_floor_per_range", o.closeness_floor_per_range, 0.0, 0.1);
  visit("max_fit_points", o.max_fit_points, 10, 1000000);
  visit("car_length_m", o.car_length_m, 0.5, 20.0);
  visit("car_width_m", o.car_width_m, 0.3, 5.0);
  visit("car_min_length_m", o.car_min_length_m, 0.0, 20.0);
  visit("sensor_azimuth_step_deg", o.sensor_azimuth_step_deg, 0.0, 10.0);
  visit("car_hidden_end_m", o.car_hidden_end_m, 0.0, 2.0);
  visit("car_max_length_m", o.car_max_length_m, 0.5, 30.0);
  visit("car_max_width_m", o.car_max_width_m, 0.3, 10.0);
  visit("car_min_height_m", o.car_min_height_m, 0.0, 10.0);
  visit("car_max_height_m", o.car_max_height_m, 0.1, 20.0);
  visit("car_min_visible_m", o.car_min_visible_m, 0.0, 20.0);
  visit("single_face_m", o.single_face_m, 0.0, 10.0);
  visit("max_ground_gap_m", o.max_ground_gap_m, 0.0, 20.0);
  visit("car_max_edge_distance_m", o.car_max_edge_distance_m, 0.0, 10.0);
  visit("front_from_profile", o.front_from_profile, 0, 1);
  visit("front_profile_upper_fraction", o.front_profile_upper_fraction, 0.0, 1.0);
  visit("front_profile_min_gap_difference_m", o.front_profile_min_gap_difference_m, 0.0, 10.0);
  visit("person_min_height_m", o.person_min_height_m, 0.0, 10.0);
  visit("person_max_height_m", o.person_max_height_m, 0.1, 10.0);
  visit("pedestrian_max_length_m", o.pedestrian_max_length_m, 0.1, 10.0);
  visit("cyclist_max_length_m", o.cyclist_max_length_m, 0.1, 10.0);
  visit("person_max_width_m", o.person_max_width_m, 0.1, 10.0);
  visit("cyclist_max_upper_extent_m", o.cyclist_max_upper_extent_m, 0.0, 10.0);
  visit("cyclist_min_height_m", o.cyclist_min_height_m, 0.0, 10.0);
  visit("car_max_surface_variation", o.car_max_surface_variation, 0.0, 1.0);
  visit("surface_voxel_m", o.surface_voxel_m, 0.01, 10.0);
  visit("surface_neighbors", o.surface_neighbors, 3, 100);
  visit("surface_min_points", o.surface_min_points, 4, 1000000);
  visit("person_max_head_ratio", o.person_max_head_ratio, 0.0, 10.0);
  visit("person_outline_min_steps", o.person_outline_min_steps, 1, 1000);
  visit("person_top_beam_margin_m", o.person_top_beam_margin_m, 0.0, 1.0);
  visit("score_points_scale", o.score_points_scale, 1.0, 1e6);
  visit("score_edge_distance_m", o.score_edge_distance_m, 0.001, 10.0);
}

// Throws std::invalid_argument naming the first option out of range, or an inconsistent pair
// (min_range_m >= max_range_m, a car maximum below its prior, cell sizes that would make a
// grid of more than ~16M cells).
void validate(const DetectorOptions& options);

}  // namespace twistslam::detection
