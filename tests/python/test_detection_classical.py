"""The classical LiDAR detector through its Python source: simulated cars found with their yaw
(mod pi) and size, real KITTI object cars found at BEV IoU 0.5, the front of cars seen whole
told on real KITTI, bad input handled."""

from __future__ import annotations

import numpy as np
import pytest

from twistslam.datasets import KittiObject, KittiTracking
from twistslam.geometry import box_iou_bev
from twistslam.perception import ClassicalDetector, Detections3D, detection_source
from twistslam.perception.detection_classical import default_options, option_ranges
from twistslam.sim.generate import generate

# Car prior of the detector: a rear or front view cannot measure a car's length, the prior
# stands in for it (docs/detection.md)
CAR_LENGTH_PRIOR_M = default_options()["car_length_m"]
SIM_RANGE_M = 25.0        # m, simulated cars checked: within reach of a dense scan
MIN_VISIBLE_POINTS = 150  # returns inside a car's box below which it counts as hidden


def _points_in_box(points: np.ndarray, box: np.ndarray) -> int:
    c, s = np.cos(box[6]), np.sin(box[6])
    dx, dz = points[:, 0] - box[0], points[:, 2] - box[2]
    along, across = dx * c - dz * s, dx * s + dz * c
    return int(np.sum((np.abs(along) < box[3] / 2) & (np.abs(across) < box[4] / 2)
                      & (np.abs(points[:, 1] - box[1]) < box[5] / 2)))


def _yaw_error(a: float, b: float) -> float:
    e = abs(a - b) % np.pi
    return min(e, np.pi - e)


def _simulate(root, scenario: str, seed: int, frames: int) -> KittiTracking:
    # tiny images: only the LiDAR and the labels matter here (~0.4 s a frame)
    generate(root, scenario, frames=frames, seed=seed, width=138, height=42, progress=False,
             output__flow=False, output__disparity=False)
    return KittiTracking(root, "0000")


@pytest.fixture(scope="module")
def sim_sequence(tmp_path_factory):
    return _simulate(tmp_path_factory.mktemp("sim"), "urban", seed=3, frames=3)


# urban: cars along the street (yaw +-90 deg, seen from behind and from the side); the
# intersection: crossing cars too (yaw 0 / 180 deg, seen from the side)
@pytest.mark.parametrize("scenario, seed, frames, min_cars",
                         [("urban", 3, 3, 5), ("intersection", 0, 2, 2)])
def test_finds_the_simulated_cars_with_yaw_and_size(tmp_path, scenario, seed, frames, min_cars):
    sequence = _simulate(tmp_path, scenario, seed, frames)
    detect = ClassicalDetector()
    checked = 0
    for frame in sequence:
        dets = detect(frame)
        cars = dets.select(dets.classes == "Car")
        labels = frame.objects_gt.of_class("Car")
        for box in labels.box_3d:
            seen = (np.hypot(box[0], box[2]) <= SIM_RANGE_M and box[2] > abs(box[0])
                    and _points_in_box(frame.points_c, box) >= MIN_VISIBLE_POINTS)
            if not seen:
                continue
            checked += 1
            assert len(cars), f"frame {frame.index}: no car detected"
            iou = box_iou_bev(box[None], cars.boxes)[0]
            best = cars.boxes[int(np.argmax(iou))]
            message = f"frame {frame.index}: label {np.round(box, 2)} best {np.round(best, 2)}"
            assert iou.max() >= 0.5, message
            # 1 deg heading search plus the scan's noise: a few degrees
            assert np.degrees(_yaw_error(best[6], box[6])) < 5.0, message
            # width and height are measured (returns on the surface: a bit small); the length
            # of a car seen from behind is the prior's
            assert abs(best[4] - box[4]) < 0.35, message
            assert abs(best[5] - box[5]) < 0.25, message
            assert abs(best[3] - box[3]) < max(0.5, abs(box[3] - CAR_LENGTH_PRIOR_M) + 0.3), message
    assert checked >= min_cars  # the scenario places several cars near the ego car


def test_real_kitti_object_cars_within_30m(kitti_object):
    """Recall of the labelled cars within 30 m at BEV IoU 0.5 (greedy, best score first)."""
    detect = detection_source("classical")
    ds = KittiObject(kitti_object)
    found = labelled = 0
    for index in ds.ids:
        frame = ds.frame(index, image=False)
        labels = frame.objects_gt.of_class("Car")
        near = labels.box_3d[np.hypot(labels.box_3d[:, 0], labels.box_3d[:, 2]) <= 30.0]
        dets = detect(frame)
        cars = dets.select(dets.classes == "Car")
        labelled += len(near)
        if len(near) and len(cars):
            iou = box_iou_bev(cars.boxes, near)
            taken = np.zeros(len(near), bool)
            for i in np.argsort(-cars.scores, kind="stable"):
                j = int(np.argmax(np.where(taken, -1.0, iou[i])))
                if iou[i, j] >= 0.5 and not taken[j]:
                    taken[j] = True
            found += int(taken.sum())
    assert labelled >= 10
    # measured 12 / 16 = 0.75 (docs/detection.md); the floor leaves room for other scans
    assert found / labelled >= 0.6, f"recall {found}/{labelled}"


def test_boxes_follow_the_detections3d_contract(sim_sequence):
    dets = ClassicalDetector()(sim_sequence[0])
    assert isinstance(dets, Detections3D) and len(dets) > 0
    assert dets.boxes.shape == (len(dets), 7) and dets.boxes.dtype == np.float64
    assert np.all((dets.scores > 0) & (dets.scores <= 1)) and np.all(np.diff(dets.scores) <= 0)
    assert set(dets.classes) <= {"Car", "Pedestrian", "Cyclist"}
    # yaw mod pi, unless the car's front was told from its height profile
    known = dets.heading_known
    assert dets.heading_known.dtype == bool and np.all(dets.classes[known] == "Car")
    assert np.all((dets.boxes[~known, 6] >= -np.pi / 2) & (dets.boxes[~known, 6] < np.pi / 2))
    assert np.all((dets.boxes[known, 6] >= -np.pi) & (dets.boxes[known, 6] < np.pi))
    assert np.all(dets.boxes[:, 2] > 0)  # front_only: the camera's field of view
    assert dets.point_extent.all()  # rectangles around their points: lengths are lower bounds
    # open_end: a prior-length car's unseen end; a measured one has none
    assert dets.open_end.dtype == np.int8 and set(dets.open_end.tolist()) <= {-1, 0, 1}
    assert np.all(dets.open_end[dets.classes != "Car"] == 0)


def test_open_ends_point_away_from_the_sensor_on_rear_views(sim_sequence):
    # urban: cars along the street, most seen from behind or in front; the prior's end of a
    # box is the one away from the sensor unless something nearer hides its other end
    dets = ClassicalDetector()(sim_sequence[0])
    is_open = dets.open_end != 0
    assert is_open.sum() >= 2, "urban has rear views: some boxes have the prior's length"
    assert np.allclose(dets.boxes[is_open, 3], CAR_LENGTH_PRIOR_M, atol=0.05)
    heading = np.stack([np.cos(dets.boxes[:, 6]), -np.sin(dets.boxes[:, 6])], axis=1)
    ray = dets.boxes[:, [0, 2]] / np.linalg.norm(dets.boxes[:, [0, 2]], axis=1, keepdims=True)
    outward = np.sum(dets.open_end[:, None] * heading * ray, axis=1)
    assert np.mean(outward[is_open] > 0) >= 0.75, outward[is_open]


def _heading_error(a: float, b: float) -> float:
    e = abs(a - b) % (2 * np.pi)
    return min(e, 2 * np.pi - e)


def test_real_kitti_cars_seen_whole_face_their_labelled_front(kitti_tracking_lidar, kitti_object):
    """Every car whose front the detector told (from its height profile) faces the way its
    label does; measured 60 told of 61 whole-length cars within 1 m of a label, none wrong
    (docs/detection.md)."""
    detect = ClassicalDetector()
    frames = []
    seq = KittiTracking(kitti_tracking_lidar, "0001")
    frames += [(seq.frame(i).points_c, seq.gt_objects.in_frame(i)) for i in range(len(seq))]
    objects = KittiObject(kitti_object)
    frames += [(objects.frame(i, image=False).points_c, objects.labels(i)) for i in objects.ids]
    told = wrong = 0
    for points, labels in frames:
        dets = detect.detect_points(points)
        cars = labels.of_class("Car").box_3d
        for box in dets.boxes[dets.heading_known]:
            gap = np.hypot(cars[:, 0] - box[0], cars[:, 2] - box[2]) if len(cars) else np.array([np.inf])
            if gap.min() > 1.0:
                continue
            told += 1
            wrong += _heading_error(box[6], cars[int(np.argmin(gap)), 6]) > np.radians(30)
    assert told >= 40, told
    assert wrong == 0, f"{wrong} of {told} fronts wrong"


def test_real_0001_orientation_score_follows_the_told_fronts(kitti_tracking_lidar):
    """KITTI's AOS (orientation similarity) of the classical boxes on real 0001: a box turned
    around scores 0. Measured 56.5 % AOS@0.7 for 71.1 % 2D AP@0.7 (moderate cars) with the
    told fronts, 36.4 % without (docs/detection.md; before the road was held behind occluders
    53.8 / 60.7 / 35.4 %: the far cars it added are partial views whose front is not told)."""
    from twistslam.eval.detection_ap import evaluate_detections

    seq = KittiTracking(kitti_tracking_lidar, "0001")
    scores = {}
    for told in (True, False):
        detect = ClassicalDetector(front_from_profile=told)
        dets = {}
        for frame in seq:
            height, width = np.asarray(frame.image_left).shape[:2]
            dets[frame.index] = detect(frame).to_table(frame.index, seq.calib, (width, height))
        r = evaluate_detections(seq.gt_objects, dets, classes=("Car",), metrics=("2d",), iou=0.7,
                                difficulties=("moderate",))
        scores[told] = (r.aos("Car", "moderate", 0.7), r.ap("Car", "moderate", "2d", 0.7))
    (aos, ap), (aos_off, ap_off) = scores[True], scores[False]
    assert ap == pytest.approx(ap_off)  # the front changes no overlap
    assert aos >= 0.75 * ap, scores
    assert aos - aos_off >= 15.0, scores


def test_front_from_profile_off_keeps_every_yaw_mod_pi(sim_sequence):
    dets = ClassicalDetector(front_from_profile=False)(sim_sequence[0])
    assert not dets.heading_known.any()
    assert np.all((dets.boxes[:, 6] >= -np.pi / 2) & (dets.boxes[:, 6] < np.pi / 2))


def test_detections3d_refuses_bad_open_ends():
    box = [[0.0, 1.0, 10.0, 4.0, 1.8, 1.5, 0.0]]
    with pytest.raises(ValueError, match="open_end"):
        Detections3D(box, [1.0], ["Car"], open_end=[2])
    with pytest.raises(ValueError, match="open_end"):
        Detections3D(box, [1.0], ["Car"], open_end=[0, 1])
    assert Detections3D(box, [1.0], ["Car"]).open_end.tolist() == [0]  # files: none known
    assert Detections3D(box, [1.0], ["Car"], open_end=[-1]).select([0]).open_end.tolist() == [-1]


def test_detections3d_point_extent_defaults_to_estimates_and_is_checked():
    box = [[0.0, 1.0, 10.0, 4.0, 1.8, 1.5, 0.0]]
    assert Detections3D(box, [1.0], ["Car"]).point_extent.tolist() == [False]  # files, 3DSSD
    assert Detections3D(box, [1.0], ["Car"], point_extent=[True]).select([0]).point_extent.tolist() == [True]
    with pytest.raises(ValueError, match="point_extent"):
        Detections3D(box, [1.0], ["Car"], point_extent=[True, False])
    with pytest.raises(ValueError, match="point_extent"):
        Detections3D(box, [1.0], ["Car"], point_extent=["yes"])
    # heading_known: files know front from back, a point extent by default does not
    assert Detections3D(box, [1.0], ["Car"]).heading_known.tolist() == [True]
    assert Detections3D(box, [1.0], ["Car"], point_extent=[True]).heading_known.tolist() == [False]
    told = Detections3D(box, [1.0], ["Car"], point_extent=[True], heading_known=[True])
    assert told.select([0]).heading_known.tolist() == [True]
    with pytest.raises(ValueError, match="heading_known"):
        Detections3D(box, [1.0], ["Car"], heading_known=[1.5])


def test_empty_and_nan_scans():
    detect = ClassicalDetector()
    assert len(detect.detect_points(np.zeros((0, 4), np.float32))) == 0
    nan_scan = np.full((1000, 4), np.nan, np.float32)
    assert len(detect.detect_points(nan_scan)) == 0
    assert detect.last_stats["num_non_finite"] == 1000


def test_nan_rows_do_not_change_the_detections(sim_sequence):
    detect = ClassicalDetector()
    points = sim_sequence[0].points_c
    clean = detect.detect_points(points)
    dirty = points.copy()
    dirty[::97, 1] = np.nan  # ~1 % of the rows
    noisy = detect.detect_points(dirty)
    assert detect.last_stats["num_non_finite"] == len(points[::97])
    assert len(noisy) == len(clean)
    # the same objects (scores, hence the order, may change a little): every clean box has a
    # noisy one within 0.3 m
    gap = np.linalg.norm(clean.boxes[:, None, [0, 2]] - noisy.boxes[None, :, [0, 2]], axis=2)
    assert np.all(gap.min(axis=1) < 0.3)


def test_bad_shapes_and_options_are_refused():
    detect = ClassicalDetector()
    with pytest.raises(ValueError, match="points_c"):
        detect.detect_points(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="max_range_m"):
        ClassicalDetector(max_range_m=-5.0)
    with pytest.raises(ValueError, match="min_range_m must be below max_range_m"):
        ClassicalDetector({"min_range_m": 40.0, "max_range_m": 30.0})
    with pytest.raises((TypeError, ValueError), match="max_rnage_m"):
        ClassicalDetector(max_rnage_m=50.0)
    lo, hi = option_ranges()["max_range_m"]
    assert lo <= default_options()["max_range_m"] <= hi


def test_frame_without_scan_is_an_error(sim_sequence):
    frame = sim_sequence[0]
    frame.points_c = None
    with pytest.raises(ValueError, match="no LiDAR scan"):
        ClassicalDetector()(frame)


def test_binding_reports_each_boxs_edge_distance_and_the_cap_holds(sim_sequence):
    from twistslam._core import detection as _d

    points = sim_sequence[0].points_c
    out = _d.detect(points)
    edge = out["edge_distance_m"]
    assert edge.dtype == np.float64 and edge.shape == (len(out["boxes"]),)
    assert np.all(edge >= 0)
    cars = np.asarray(out["classes"]) == "Car"
    assert cars.any() and np.all(edge[cars] <= default_options()["car_max_edge_distance_m"])
    # a tighter cap keeps exactly the cars within it
    cap = float(np.median(edge[cars]))
    tight = _d.detect(points, {"car_max_edge_distance_m": cap})
    tight_cars = np.asarray(tight["classes"]) == "Car"
    assert np.all(tight["edge_distance_m"][tight_cars] <= cap)
    assert tight_cars.sum() < cars.sum()


def test_real_scans_near_car_boxes_lie_on_labelled_cars(kitti_tracking_lidar):
    # KITTI 0001 passes a row of bushes and hedges on its right at 11-17 m: each was a
    # car-sized cluster, its returns spread through it (mean edge distance 0.27-0.61 m where
    # the labelled cars' are 0.08-0.23 m); measured 6 boxes off the labels within 20 m over
    # the 27 scans without car_max_edge_distance_m, 1 with it
    seq = KittiTracking(kitti_tracking_lidar, "0001")
    labels = seq.gt_objects
    # Holding the road behind occluders removes 4 of the 6 on its own (2026-12-05: most of
    # them stood behind parked cars, on a road raised to their lowest visible returns), so
    # the two rules are checked with it off, on all six. Measured: 6 with neither rule nor the
    # held road, 0 with the defaults, 1 with the roughness rule alone, 2 with the held road
    # alone (before it: 1 with the defaults).
    climbing = {"hold_road_in_shadows": False}
    detectors = {"default": ClassicalDetector(),
                 "lenient": ClassicalDetector(car_max_edge_distance_m=10.0,
                                              car_max_surface_variation=0.0, **climbing),
                 "roughness only": ClassicalDetector(car_max_edge_distance_m=10.0, **climbing),
                 "held road only": ClassicalDetector(car_max_edge_distance_m=10.0,
                                                     car_max_surface_variation=0.0)}
    off_labels = dict.fromkeys(detectors, 0)
    for i in range(len(seq)):
        frame = seq.frame(i)
        rows = (labels.frame == i) & np.isin(labels.cls, ["Car", "Van"])
        centres = labels.box_3d[rows][:, [0, 2]]
        for name, det in detectors.items():
            dets = det(frame)
            cars = dets.boxes[dets.classes == "Car"]
            near = cars[np.hypot(cars[:, 0], cars[:, 2]) < 20.0]
            for box in near:
                gap = np.min(np.hypot(*(centres - box[[0, 2]]).T)) if len(centres) else np.inf
                off_labels[name] += int(gap > 2.0)
    assert off_labels["lenient"] >= 5, off_labels  # the bushes are there to be removed
    assert off_labels["default"] <= 2, off_labels
    # the surface roughness (car_max_surface_variation) tells the same foliage on its own
    assert off_labels["roughness only"] <= 2, off_labels
    assert off_labels["held road only"] <= 3, off_labels
