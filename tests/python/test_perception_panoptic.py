"""Panoptic perception: the result type, simulator and COCO files, the source choice, and their
errors (masks from 3D boxes: test_perception_panoptic_boxes.py)."""

import json

import numpy as np
import pytest
from PIL import Image

from twistslam.datasets import KittiTracking
from twistslam.perception.panoptic import CAR, ROAD, UNKNOWN, Panoptic
from twistslam.perception.panoptic_files import (CocoPanopticFiles, SimPanopticFiles,
                                                 read_coco_panoptic, read_sim_panoptic)
from twistslam.perception.panoptic_source import check_panoptic, panoptic_source
from twistslam.sim.generate import generate
from twistslam.datasets.png16 import read_png16


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


def test_sixteen_bit_ids_decode_as_the_integer_arithmetic_does():
    """16-bit PNG values go through lookup tables; every code, stuff and things, the largest
    included, must decode as the int64 path does, and an unknown class still names itself."""
    rng = np.random.default_rng(0)
    codes = np.array([0, 7, 11, 23, 24000, 26001, 26999, 33000, 26005, 24017], np.uint16)
    ids = rng.choice(codes, size=(40, 50)).astype(np.uint16)
    fast = Panoptic.from_cityscapes_ids(ids)
    slow = Panoptic.from_cityscapes_ids(ids.astype(np.int64))
    assert fast.class_id.dtype == slow.class_id.dtype == np.int32
    np.testing.assert_array_equal(fast.class_id, slow.class_id)
    np.testing.assert_array_equal(fast.instance_id, slow.instance_id)
    assert fast.instance_id.max() == 33000 and fast.class_id[ids == 26005].tolist() == [26] * int(
        (ids == 26005).sum())
    with pytest.raises(ValueError, match=r"class_id \[65\] not in the Cityscapes vocabulary"):
        Panoptic.from_cityscapes_ids(np.full((2, 2), 65535, np.uint16))
    with pytest.raises(ValueError, match=r"class_id \[-3\] not in the Cityscapes vocabulary"):
        Panoptic(np.full((2, 2), -3), np.zeros((2, 2), int))  # negative: the np.unique path


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
