"""Panoptic perception sources: simulator and COCO files, masks from 3D boxes (real KITTI and
the simulator's exact panoptic images), and their errors."""

import json
from dataclasses import replace

import numpy as np
import pytest
from PIL import Image

from conftest import require_real_data
from twistslam.datasets import KittiTracking, data_path
from twistslam.perception.hull_fill import fill_convex_hull
from twistslam.perception.panoptic import CAR, ROAD, UNKNOWN, Panoptic
from twistslam.perception.panoptic_files import (CocoPanopticFiles, SimPanopticFiles,
                                                 read_coco_panoptic, read_sim_panoptic)
from twistslam.perception.panoptic_from_boxes import (BoxMaskConfig, PanopticFromBoxes,
                                                      ground_plane, points_in_box)
from twistslam.perception.panoptic_source import check_panoptic, panoptic_source
from twistslam.sim.generate import generate
from twistslam.sim.png16 import read_png16


@pytest.fixture(scope="module")
def sim_sequence(tmp_path_factory):
    # half KITTI resolution: masks of cars 20-40 m away still span tens of pixels
    out = generate(tmp_path_factory.mktemp("sim") / "s", frames=2, width=621, height=188,
                   seed=3, output__flow=False, progress=False)
    return KittiTracking(out, "0000")


def test_sim_files_read_back_to_the_simulators_classes(sim_sequence):
    source = SimPanopticFiles.of_sequence(sim_sequence)
    frame = sim_sequence[0]
    pan = source(frame)
    raw = read_png16(source.folder / "000000.png").astype(np.int64)
    assert pan.shape == frame.image_left.shape[:2]
    assert set(np.unique(pan.class_id)) <= {7, 8, 11, 14, 17, 20, 21, 22, 23, 24, 26}
    np.testing.assert_array_equal(pan.class_id, np.where(raw >= 1000, raw // 1000, raw))
    # every labelled car is an instance of class car, its id encoding the track id
    cars = frame.objects_gt.of_class("Car")
    assert len(cars) > 3
    instances = pan.instances()
    for track in cars.track_id:
        assert instances[26000 + int(track) + 1] == CAR
    assert (pan.instance_id[pan.class_id < 24] == 0).all()
    # unknown and stuff are static; cars and people dynamic unless configured otherwise
    np.testing.assert_array_equal(pan.dynamic_mask(), np.isin(pan.class_id, [24, 26]))
    np.testing.assert_array_equal(pan.dynamic_mask(dynamic_classes=[24]), pan.class_id == 24)
    assert pan.static_mask(dynamic_classes=[]).all()


def _coco_files(tmp_path, segments, categories, ids):
    rgb = np.stack([ids % 256, ids // 256 % 256, ids // 65536], axis=-1).astype(np.uint8)
    Image.fromarray(rgb).save(tmp_path / "000000.png")
    json_path = tmp_path / "panoptic.json"
    json_path.write_text(json.dumps({
        "annotations": [{"image_id": 0, "file_name": "000000.png", "segments_info": segments}],
        "categories": categories}))
    return tmp_path / "000000.png", json_path


COCO_CATEGORIES = [{"id": 3, "name": "car", "isthing": 1}, {"id": 1, "name": "person", "isthing": 1},
                   {"id": 149, "name": "road", "isthing": 0}, {"id": 52, "name": "banana", "isthing": 1}]


def test_coco_panoptic_png_and_json_decode(tmp_path):
    ids = np.zeros((6, 8), np.int64)
    ids[:, :4] = 7                 # road (R channel only)
    ids[0:2, 4:6] = 300            # a car: id needs the G channel
    ids[3:5, 4:6] = 70000          # another car: the B channel
    ids[5, 6:] = 5                 # a person
    ids[0, 7] = 9                  # a category the vocabulary lacks -> unknown
    segments = [{"id": 7, "category_id": 149, "isthing": 0}, {"id": 300, "category_id": 3, "isthing": 1},
                {"id": 70000, "category_id": 3, "isthing": 1}, {"id": 5, "category_id": 1, "isthing": 1},
                {"id": 9, "category_id": 52, "isthing": 1}]
    png, js = _coco_files(tmp_path, segments, COCO_CATEGORIES, ids)
    pan = read_coco_panoptic(png, js)
    expected = np.where(ids == 7, ROAD, np.where(np.isin(ids, [300, 70000]), CAR, UNKNOWN))
    expected[ids == 5] = 24
    np.testing.assert_array_equal(pan.class_id, expected)
    cars = np.unique(pan.instance_id[pan.class_id == CAR])
    assert len(cars) == 2 and 0 not in cars
    assert (pan.instance_id[ids == 7] == 0).all() and (pan.instance_id[ids == 0] == 0).all()
    # the source reads a frame's PNG by index; a user mapping may name the road static "ground"
    frame = type("F", (), {"index": 0})()
    source = CocoPanopticFiles(tmp_path, js, category_map={"road": 6, "car": CAR})
    assert (source(frame).class_id[ids == 7] == 6).all()


def test_coco_errors_name_the_file(tmp_path):
    ids = np.full((4, 4), 7, np.int64)
    segments = [{"id": 7, "category_id": 149}]
    png, js = _coco_files(tmp_path, segments, COCO_CATEGORIES, ids)
    with pytest.raises(FileNotFoundError, match="nothing.png"):
        read_coco_panoptic(tmp_path / "nothing.png", js)
    with pytest.raises(FileNotFoundError, match="none.json"):
        read_coco_panoptic(png, tmp_path / "none.json")
    ids[0, 0] = 12
    png, js = _coco_files(tmp_path, segments, COCO_CATEGORIES, ids)
    with pytest.raises(ValueError, match=r"000000.png: segment ids \[12\].*segments_info"):
        read_coco_panoptic(png, js)
    png, js = _coco_files(tmp_path, [{"id": 7, "category_id": 999}], COCO_CATEGORIES, ids * 0 + 7)
    with pytest.raises(ValueError, match="category_id 999"):
        read_coco_panoptic(png, js)
    js.write_text(json.dumps({"annotations": [], "categories": []}))
    with pytest.raises(ValueError, match="no annotation with file_name '000000.png'"):
        read_coco_panoptic(png, js)
    js.write_text("{not json")
    with pytest.raises(ValueError, match="not a COCO panoptic JSON"):
        read_coco_panoptic(png, js)
    Image.fromarray(np.zeros((4, 4), np.uint8)).save(tmp_path / "grey.png")
    js.write_text(json.dumps({"annotations": [{"file_name": "grey.png", "segments_info": []}],
                              "categories": []}))
    with pytest.raises(ValueError, match="grey.png: expected an 8-bit RGB PNG"):
        read_coco_panoptic(tmp_path / "grey.png", js)


def test_sim_reader_and_result_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="000123.png"):
        read_sim_panoptic(tmp_path / "000123.png")
    Image.fromarray(np.zeros((4, 4, 3), np.uint8)).save(tmp_path / "rgb.png")
    with pytest.raises(ValueError, match="rgb.png: expected a single-channel"):
        read_sim_panoptic(tmp_path / "rgb.png")
    with pytest.raises(ValueError, match=r"class_id \[40\] not in the Cityscapes vocabulary"):
        Panoptic(np.full((2, 2), 40), np.zeros((2, 2), int))
    with pytest.raises(ValueError, match="same shape"):
        Panoptic(np.zeros((2, 2), int), np.zeros((2, 3), int))
    with pytest.raises(FileNotFoundError, match="panoptic folder not found"):
        SimPanopticFiles(tmp_path / "missing")


def test_hull_fill_covers_the_hull_and_the_points_pixels():
    mask = fill_convex_hull(np.array([[2.0, 2.0], [8.0, 2.0], [8.0, 6.0], [2.0, 6.0], [5, 4]]), (10, 12))
    expected = np.zeros((10, 12), bool)
    expected[2:6, 2:8] = True  # pixel centres inside [2, 8] x [2, 6]
    expected[6, 8] = expected[2, 8] = expected[6, 2] = True  # pixels holding a corner point
    np.testing.assert_array_equal(mask, expected)
    # a hull reaching far outside the image (a point near the camera plane) is clipped
    huge = fill_convex_hull(np.array([[-1e7, 5.0], [1e7, 5.0], [0.0, -1e7]]), (10, 12))
    assert huge[:5].all() and not huge[5:].any()


def test_sim_masks_from_boxes_match_the_exact_car_pixels(sim_sequence):
    """Measured over seeds 3, 7, 11 (3 frames each, 621x188): car-class IoU 0.84-0.94, cars
    of >= 500 px not cut by the border 0.80-0.96, road IoU 0.74-0.90 (part of the sidewalk
    next to the road is called road). What is lost: points hidden from the LiDAR
    but seen by the camera, and the hull's straight edges around round silhouettes."""
    truth_source = SimPanopticFiles.of_sequence(sim_sequence)
    for frame in sim_sequence:
        boxes = frame.objects_gt
        pan = PanopticFromBoxes(sim_sequence.gt_objects)(frame)
        truth = truth_source(frame)
        car_t, car_p = truth.class_id == CAR, pan.class_id == CAR
        assert (car_t & car_p).sum() / (car_t | car_p).sum() > 0.75
        for k in range(len(boxes)):
            exact = truth.instance_id == CAR * 1000 + boxes.track_id[k] + 1
            # a car cut by the image border 1-3 m away is left out: its LiDAR points near the
            # camera plane, hidden behind its own body, spread the hull (IoU 0.53 measured)
            if boxes.cls[k] == "Car" and exact.sum() >= 500 and boxes.truncation[k] == 0:
                ours = pan.instance_id == k + 1
                assert (exact & ours).sum() / (exact | ours).sum() > 0.7
        road_t, road_p = truth.class_id == ROAD, pan.class_id == ROAD
        assert (road_t & road_p).sum() / (road_t | road_p).sum() > 0.6


@pytest.fixture(scope="module")
def kitti_0001():
    require_real_data("kitti_tracking_lidar")
    return KittiTracking(data_path("kitti_tracking_lidar"), "0001")


@pytest.mark.parametrize("index", [0, 8, 16, 24])
def test_real_kitti_masks_from_labelled_cars(kitti_0001, index):
    """Measured on frames 0-26: every above-ground point of a labelled car lands in a car mask,
    91 % in its own (a nearer car's convex mask covers the rest: it spans the gaps, windows
    and the space over a bonnet, through which the farther car is seen), and each mask lies
    inside its car's labelled 2D box."""
    frame = kitti_0001[index]
    cars = frame.objects_gt.of_class("Car")
    config = BoxMaskConfig()
    pan = PanopticFromBoxes(cars, config)(frame)
    points = frame.points_c[:, :3].astype(np.float64)
    plane = ground_plane(points, config)
    # the fitted road plane lies at KITTI's camera height (1.65 m) below the camera, level
    assert abs(plane[3] - 1.65) < 0.15 and plane[1] < -0.99
    H, W = pan.shape
    above = (points @ plane[:3] + plane[3] > config.hull_ground_clearance_m) & (points[:, 2] > 0.1)
    total = own = in_car = 0
    for k in range(len(cars)):
        uvw = points[points_in_box(points, cars.box_3d[k]) & above] @ frame.calib.P2[:, :3].T + frame.calib.P2[:, 3]
        uv = np.floor(uvw[:, :2] / uvw[:, 2:3]).astype(int)
        uv = uv[(uv[:, 0] >= 0) & (uv[:, 0] < W) & (uv[:, 1] >= 0) & (uv[:, 1] < H)]
        total += len(uv)
        own += (pan.instance_id[uv[:, 1], uv[:, 0]] == k + 1).sum()
        in_car += (pan.class_id[uv[:, 1], uv[:, 0]] == CAR).sum()
        mask = pan.instance_id == k + 1
        if mask.sum() >= 50:
            v, u = np.nonzero(mask)
            x1, y1, x2, y2 = cars.box_2d[k] + [-2, -2, 2, 2]  # px: label rounding
            assert ((u >= x1) & (u <= x2) & (v >= y1) & (v <= y2)).mean() > 0.95
    assert total > 300 and in_car / total >= 0.95 and own / total >= 0.85
    assert (pan.class_id == ROAD).mean() > 0.15  # the road fills the lower image
    assert (pan.class_id[: H // 3] != ROAD).all()  # and never the sky's third


def test_masks_from_boxes_need_the_scan_and_the_image(kitti_0001):
    frame = replace(kitti_0001[0], points_c=None)
    with pytest.raises(ValueError, match="frame 0: masks from boxes need the LiDAR scan"):
        PanopticFromBoxes(kitti_0001.gt_objects)(frame)
    frame = replace(kitti_0001[0], image_left=None)
    with pytest.raises(ValueError, match="frame 0: .*image_left is None"):
        PanopticFromBoxes(kitti_0001.gt_objects)(frame)


def test_real_pointrcnn_detections_cover_the_labelled_cars(kitti_0001):
    """Masks from the real PointRCNN boxes (all of them, no score threshold) cover 95 % of
    the labelled cars' above-ground points over frames 0, 4, ..., 24 (missed and
    misplaced detections lose the rest), and 98.7 % of the car pixels lie in a labelled
    object's 2D box (100 % with ``min_score`` 2)."""
    from twistslam.objects import load_detections

    detections = load_detections(data_path("kitti_tracking_lidar", "detections", "pointrcnn_car_val"),
                                 "0001", len(kitti_0001))
    source = panoptic_source("auto", kitti_0001, boxes=detections)
    assert isinstance(source, PanopticFromBoxes)  # real KITTI has no panoptic files
    config, total, covered, car_pixels, in_labels = BoxMaskConfig(), 0, 0, 0, 0
    for index in range(0, len(kitti_0001), 4):
        frame = kitti_0001[index]
        pan = source(frame)
        points = frame.points_c[:, :3].astype(np.float64)
        plane = ground_plane(points, config)
        above = (points @ plane[:3] + plane[3] > config.hull_ground_clearance_m) & (points[:, 2] > 0.1)
        P, (H, W) = frame.calib.P2, pan.shape
        for box in frame.objects_gt.of_class("Car").box_3d:
            uvw = points[points_in_box(points, box) & above] @ P[:, :3].T + P[:, 3]
            uv = np.floor(uvw[:, :2] / uvw[:, 2:3]).astype(int)
            uv = uv[(uv[:, 0] >= 0) & (uv[:, 0] < W) & (uv[:, 1] >= 0) & (uv[:, 1] < H)]
            total += len(uv)
            covered += (pan.class_id[uv[:, 1], uv[:, 0]] == CAR).sum()
        labelled = np.zeros(pan.shape, bool)
        for x1, y1, x2, y2 in np.round(frame.objects_gt.box_2d).astype(int):  # DontCare too
            labelled[max(y1 - 2, 0) : y2 + 3, max(x1 - 2, 0) : x2 + 3] = True
        car_pixels += (pan.class_id == CAR).sum()
        in_labels += ((pan.class_id == CAR) & labelled).sum()
    assert total > 1000 and covered / total >= 0.9
    assert in_labels / car_pixels >= 0.95
    # a score threshold drops boxes: frame 20 has detections scored below 2 with masks
    strict = PanopticFromBoxes(detections, BoxMaskConfig(min_score=2.0))(kitti_0001[20])
    assert (strict.class_id == CAR).sum() < (source(kitti_0001[20]).class_id == CAR).sum()


def test_source_choice_and_stage_output_checks(sim_sequence, tmp_path):
    assert isinstance(panoptic_source("auto", sim_sequence), SimPanopticFiles)
    with pytest.raises(ValueError, match="expected one of auto, files, coco, boxes"):
        panoptic_source("mask-rcnn", sim_sequence)
    with pytest.raises(ValueError, match="no panoptic files and no 3D boxes"):
        panoptic_source("boxes", sim_sequence)
    with pytest.raises(ValueError, match="needs coco_folder"):
        panoptic_source("coco", sim_sequence)
    # a user's function may return a (class_id, instance_id) pair
    pan = check_panoptic((np.full((4, 5), 26), np.ones((4, 5), int)), (4, 5), "my_fn")
    assert pan.dynamic_mask().all()
    with pytest.raises(ValueError, match=r"my_fn: panoptic labels are \(4, 5\), the image is \(4, 6\)"):
        check_panoptic(pan, (4, 6), "my_fn")
    with pytest.raises(ValueError, match="my_fn: a panoptic stage must return"):
        check_panoptic(np.zeros((4, 5)), (4, 5), "my_fn")
