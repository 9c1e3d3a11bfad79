"""The whole system on real KITTI 0001 from stereo + LiDAR, with the classical detector (what
runs with no weights and no precomputed files) and with the PointRCNN detection files; masks
from the boxes, DIS flow (issues 10 and 11). The sequence as recorded, then the same real
frames replayed as the ego would see them had it stopped for a while (one frame repeated), and
at 5 Hz (every other frame: twice the motion between frames). Each run must track every
labelled car within 30 m, keep the camera on the oxts path, and hold still while the ego
stands.

The variants are folders of links to the real files (nothing copied), with the labels, oxts and
detections renumbered."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import twistslam
from twistslam.datasets import KittiTracking
from twistslam.datasets.labels import read_labels

SEQ = "0001"
NUM_REAL_FRAMES = 27
#: A labelled car is evaluated in the frames where it is within this range (m, camera frame).
MAX_RANGE_M = 30.0
#: A reported car box whose centre lies this close (m) to a labelled car's covers it.
HIT_DISTANCE_M = 1.5

#: A car is evaluated when it was seen (within range, wholly in the image) this long (s).
MIN_SEEN_S = 0.5

#: name -> (real frames in order, frame rate in Hz)
VARIANTS = {
    "as recorded": (list(range(NUM_REAL_FRAMES)), 10.0),
    # the ego stands for 8 frames at frame 8: the same images and scan again and again
    "ego stopped": (list(range(9)) + [8] * 8 + list(range(9, NUM_REAL_FRAMES)), 10.0),
    "5 Hz": (list(range(0, NUM_REAL_FRAMES, 2)), 5.0),
}


def make_variant(real: Path, out: Path, frames: list[int]) -> Path:
    """A KITTI tracking root whose sequence 0001 is the given real frames in order."""
    training = out / "training"
    for folder, ext in (("image_02", "png"), ("image_03", "png"), ("velodyne", "bin")):
        (training / folder / SEQ).mkdir(parents=True)
        for new, old in enumerate(frames):
            (training / folder / SEQ / f"{new:06d}.{ext}").symlink_to(
                real / "training" / folder / SEQ / f"{old:06d}.{ext}")
    (training / "calib").mkdir()
    (training / "calib" / f"{SEQ}.txt").symlink_to(real / "training" / "calib" / f"{SEQ}.txt")
    oxts = (real / "training" / "oxts" / f"{SEQ}.txt").read_text().splitlines()
    (training / "oxts").mkdir()
    (training / "oxts" / f"{SEQ}.txt").write_text("".join(oxts[i] + "\n" for i in frames))
    for table, separator in ((Path("training") / "label_02", " "),
                             (Path("detections") / "pointrcnn_car_val", ",")):
        rows = [line.split(separator, 1) for line in
                (real / table / f"{SEQ}.txt").read_text().splitlines()]
        (out / table).mkdir(parents=True)
        (out / table / f"{SEQ}.txt").write_text("".join(
            f"{new}{separator}{rest}\n" for new, old in enumerate(frames) for frame, rest in rows
            if int(frame) == old))
    return out


@pytest.fixture(scope="module")
def runs(kitti_tracking_lidar, tmp_path_factory):
    """(variant, detector) -> (frames, variant root, Result, reported boxes), each run once."""
    roots, done = {}, {}

    def get(name, detector="classical"):
        if name not in roots:
            roots[name] = make_variant(kitti_tracking_lidar, tmp_path_factory.mktemp("variant"),
                                       VARIANTS[name][0])
        if (name, detector) not in done:
            result = twistslam.run(KittiTracking(roots[name], SEQ), progress=False,
                                   detector=detector, segmentation="boxes", flow="dis")
            assert result.detector == detector
            saved = result.save(tmp_path_factory.mktemp("result"))
            done[name, detector] = (VARIANTS[name][0], roots[name], result,
                                    read_labels(saved["tracking"]))
        return done[name, detector]
    return get


def path_length(poses: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1).sum())


def car_coverage(labels, reported) -> dict[int, tuple[int, int]]:
    """Labelled car id -> (frames within MAX_RANGE_M and wholly in the image, of those
    covered by a reported car). A car leaving the image is labelled truncated (KITTI tracking:
    1 or 2) for its last frames; the system ends a track whose car leaves the view."""
    cars = labels.select((labels.cls == "Car") & (labels.truncation == 0))
    ours = reported.select(reported.cls == "Car")
    out: dict[int, tuple[int, int]] = {}
    for k in range(len(cars)):
        centre = cars.box_3d[k, :3]
        if np.linalg.norm(centre) > MAX_RANGE_M:
            continue
        here = ours.box_3d[ours.frame == cars.frame[k], :3]
        hit = len(here) > 0 and np.linalg.norm(here - centre, axis=1).min() < HIT_DISTANCE_M
        seen, covered = out.get(int(cars.track_id[k]), (0, 0))
        out[int(cars.track_id[k])] = (seen + 1, covered + int(hit))
    return out


@pytest.mark.parametrize("detector", ["classical", "files"])
@pytest.mark.parametrize("name", list(VARIANTS))
def test_every_labelled_car_within_30_m_is_tracked(runs, name, detector):
    """Measured (2026-12-06): the 6 cars seen for 0.5 s or more are covered in every such frame
    in all six runs."""
    frames, root, result, reported = runs(name, detector)
    labels = read_labels(root / "training" / "label_02" / f"{SEQ}.txt")
    coverage = car_coverage(labels, reported)
    min_frames = int(np.ceil(MIN_SEEN_S * VARIANTS[name][1]))
    evaluated = {car: c for car, c in coverage.items() if c[0] >= min_frames}
    run_name = f"{name}, {detector}"
    assert len(evaluated) >= 5, f"{run_name}: only {len(evaluated)} labelled cars evaluated"
    for car, (seen, covered) in evaluated.items():
        assert covered >= 0.9 * seen, f"{run_name}: car {car} covered in {covered} of {seen}"


@pytest.mark.parametrize("name", list(VARIANTS))
def test_the_camera_follows_the_oxts_path(runs, name):
    """Every frame tracked; the camera's path within 1 % of the oxts one. Measured
    (2026-12-06): 0.9995 (as recorded), 0.9981 (ego stopped), 0.9984 (5 Hz)."""
    frames, root, result, reported = runs(name)
    assert len(result.camera_poses) == len(frames)
    assert np.isfinite(result.camera_poses).all(), f"{name}: a frame without a camera pose"
    assert (result.status != "lost").all(), f"{name}: tracking lost"
    truth = KittiTracking(root, SEQ).gt_poses
    ratio = path_length(result.camera_poses) / path_length(truth)
    assert abs(ratio - 1.0) < 0.01, f"{name}: path {ratio:.4f} of the oxts one"


def test_the_camera_holds_still_while_the_ego_stands(runs):
    frames, root, result, reported = runs("ego stopped")
    t = result.camera_poses[:, :3, 3]
    repeated = [i for i in range(1, len(frames)) if frames[i] == frames[i - 1]]
    steps = np.linalg.norm(t[repeated] - t[[i - 1 for i in repeated]], axis=1)
    # measured: 2.4, 2.0, 0.7 mm, then 0 for the last five repeats
    assert steps.max() < 0.01, f"the camera moved {steps.max():.3f} m between identical frames"
