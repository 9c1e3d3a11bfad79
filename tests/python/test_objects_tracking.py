"""3D multi-object tracking from detections (twistslam.objects, cpp/objects): ids of the
simulator's moving cars, real KITTI 0001 / 0006 with PointRCNN detections, the result files,
the ``objects`` config section and the assignment solver.

Bad input (detection files, the C++ tracker's checks, CLI errors): test_objects_inputs.py.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from twistslam import _core
from twistslam.cli import main as cli_main
from twistslam.config import Config
from twistslam.datasets import MissingDataWarning, open_sequence, read_tracking_results
from twistslam.geometry import box_iou_3d, project_boxes
from twistslam.objects import ObjectsResult, track_detections
from twistslam.objects.tracking import _camera_frame_boxes, _image_size, in_image

# sequences of the real data have no images / scans here: the readers say so once
pytestmark = pytest.mark.filterwarnings("ignore::twistslam.datasets.MissingDataWarning")

DETECTIONS = ("detections", "pointrcnn_car_val")
SIM_SEQ = "0000"
# m: farther, the oracle's centre noise (0.12 m per 10 m and axis) rules out IoU >= 0.5
SIM_RANGE = 40.0


def _open(root: Path, seq: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingDataWarning)  # no images / scans here
        return open_sequence(root, seq)


def _overlap_fraction(boxes, gt, max_range: float = 40.0) -> float:
    """Fraction of the rows of ``boxes`` within ``max_range`` of the camera with 3D IoU >= 0.25
    with a row of ``gt`` of their frame. Farther, KITTI's labels thin out (the devkit ignores
    unmatched boxes under 25 px, ~45 m for a car) and the tracker reports predicted boxes of
    far cars before their first detection (objects.backcast_*), mostly unlabelled there."""
    boxes = boxes.select(np.hypot(boxes.box_3d[:, 0], boxes.box_3d[:, 2]) < max_range)
    hits = 0
    for f in np.unique(boxes.frame):
        rows, labels = boxes.frame == f, gt.frame == f
        if labels.any():
            iou = box_iou_3d(boxes.box_3d[rows], gt.box_3d[labels]).max(axis=1)
            hits += int((iou >= 0.25).sum())
    return hits / len(boxes)


# ---------------------------------------------------------------- simulator: moving cars' ids


@pytest.fixture(scope="session")
def sim_root(tmp_path_factory) -> Path:
    """One short urban sequence (oracle detections, LiDAR for the oracle's point counts; no
    rendering extras, half-size images, no shadows: ~0.4 CPU-s per frame)."""
    from twistslam.sim import generate

    out = tmp_path_factory.mktemp("objects_sim") / "sim"
    generate(out, "urban", frames=30, seed=0, seq=SIM_SEQ, width=621, height=188, progress=False,
             output__panoptic=False, output__flow=False, output__disparity=False,
             output__lidar_labels=False, output__meshes=False, light__shadows=False,
             lidar__azimuth_step=0.2)
    return out


@pytest.fixture(scope="session")
def sim_run(sim_root):
    seq = _open(sim_root, SIM_SEQ)
    config = Config()
    return seq, config, track_detections(seq, sim_root / "detections" / "oracle", config)


def _object_positions(root: Path) -> dict[int, dict[int, np.ndarray]]:
    """``training/object_poses/SEQ.txt``: {track: {frame: world position}} (ground truth)."""
    positions: dict[int, dict[int, np.ndarray]] = {}
    for line in (root / "training" / "object_poses" / f"{SIM_SEQ}.txt").read_text().splitlines():
        t = line.split()
        T = np.array([float(v) for v in t[6:18]]).reshape(3, 4)
        positions.setdefault(int(t[1]), {})[int(t[0])] = T[:, 3]
    return positions


def _best(table, frame: int, box: np.ndarray, threshold: float) -> int | None:
    """Row index (within ``frame``) of the box of ``table`` that overlaps ``box`` most, if
    its 3D IoU reaches ``threshold``."""
    rows = table.frame == frame
    if not rows.any():
        return None
    iou = box_iou_3d(box[None], table.box_3d[rows])[0]
    k = int(np.argmax(iou))
    return k if iou[k] >= threshold else None


def _moving_car_visits(seq, root: Path, cfg) -> list[tuple[int, list[int], np.ndarray]]:
    """Every (track, labelled frames, their boxes) of a ground-truth *moving* car (it moves
    more than 1 m in the world), cut into visits: runs of frames within SIM_RANGE where the
    oracle detects it confidently (3D IoU >= 0.25, score >= high_score), gaps of at most
    ``max_misses`` frames merged (the tracker is set to bridge those, not longer ones)."""
    from twistslam.datasets import read_detections

    gt = seq.gt_objects
    detections = read_detections(root / "detections" / "oracle" / f"{SIM_SEQ}.txt")
    positions = _object_positions(root)
    visits = []
    for track in np.unique(gt.track_id[gt.cls == "Car"]):
        rows = gt.track_id == track
        frames, boxes = gt.frame[rows], gt.box_3d[rows]
        p = np.array(list(positions[int(track)].values()))
        if np.linalg.norm(p.max(axis=0) - p.min(axis=0)) <= 1.0:
            continue  # parked
        seen = []
        for f, box in zip(frames, boxes):
            k = _best(detections, f, box, 0.25)
            near = np.hypot(box[0], box[2]) <= SIM_RANGE
            score = detections.score[detections.frame == f][k] if k is not None else -np.inf
            confident = score >= cfg.high_score
            if near and confident:
                seen.append(int(f))
        runs: list[list[int]] = []
        for f in seen:
            if runs and f - runs[-1][-1] - 1 <= cfg.max_misses:
                runs[-1].append(f)
            else:
                runs.append([f])
        for run in runs:
            keep = (frames >= run[0]) & (frames <= run[-1])
            if keep.sum() >= 5:
                visits.append((int(track), [int(f) for f in frames[keep]], boxes[keep]))
    return visits


def test_sim_every_moving_car_keeps_one_id(sim_root, sim_run):
    # FAILS with the current defaults (reported as a real tracker weakness, not hidden by a
    # friendlier seed): moving car 5 at 27-30 m, frames 22-29: one oracle detection 0.95 m
    # off laterally (frame 27) is followed by the newest window pose, the prediction takes
    # it as ~1 m/frame of sideways velocity and misses the next detection -> a new id.
    # const_sigma_translation = 0.3 m/frame per frame is 30 m/s^2 of allowed acceleration;
    # 0.1 makes this test pass on this and five other simulated sequences.
    seq, config, result = sim_run
    assert result.frame == "world"  # the sim writes oxts / poses
    visits = _moving_car_visits(seq, sim_root, config.objects)
    assert len(visits) >= 3, "the scenario must have moving cars to track"
    tracking = result.tracking
    owner: dict[int, int] = {}
    problems = []
    for track, frames, boxes in visits:
        ids, covered = [], []
        for f, box in zip(frames, boxes):
            k = _best(tracking, f, box, 0.5)
            if k is not None:
                ids.append(int(tracking.track_id[tracking.frame == f][k]))
                covered.append(f)
        # the first birth_hits frames may go while a track is born (a low score or a missed
        # detection there restarts it); every frame after must be covered
        after_birth = frames[config.objects.birth_hits:]
        coverage = np.isin(after_birth, covered).mean()
        if len(set(ids)) != 1 or coverage < 0.9:
            problems.append(f"car {track} frames {frames[0]}-{frames[-1]}: tracker ids "
                            f"{sorted(set(ids))}, {coverage:.0%} of its frames covered")
        for i in set(ids):
            if owner.setdefault(i, track) != track:
                problems.append(f"tracker id {i} covers cars {owner[i]} and {track}")
    assert not problems, "; ".join(problems)


def test_sim_moving_cars_speed(sim_root, sim_run):
    seq, config, result = sim_run
    positions = _object_positions(sim_root)
    by_id = {o.track_id: o for o in result.objects}
    checked = 0
    for track, frames, boxes in _moving_car_visits(seq, sim_root, config.objects):
        if len(frames) < 10:
            continue
        p = positions[track]
        truth = np.linalg.norm(p[frames[-1]] - p[frames[0]]) / (frames[-1] - frames[0]) / 0.1 * 3.6
        k = _best(result.tracking, frames[len(frames) // 2], boxes[len(frames) // 2], 0.5)
        assert k is not None, f"car {track} is not tracked mid-visit"
        mid = result.tracking.frame == frames[len(frames) // 2]
        obj = by_id[int(result.tracking.track_id[mid][k])]
        rows = np.isin(obj.frames, frames)
        assert np.median(obj.velocity_kmh[rows]) == pytest.approx(truth, rel=0.15), f"car {track}"
        checked += 1
    assert checked >= 2


# ------------------------------------------------------------- real KITTI 0001 / 0006, PointRCNN


@pytest.fixture(scope="session")
def seq_0001(kitti_tracking):
    return _open(kitti_tracking, "0001")


@pytest.fixture(scope="session")
def result_0001(kitti_tracking, seq_0001) -> ObjectsResult:
    return track_detections(seq_0001, kitti_tracking.joinpath(*DETECTIONS))


@pytest.fixture(scope="session")
def saved_0001(result_0001, tmp_path_factory) -> tuple[Path, dict[str, Path]]:
    out = tmp_path_factory.mktemp("objects_0001")
    return out, result_0001.save(out)


def test_real_0001_result_file(seq_0001, result_0001, saved_0001):
    out, paths = saved_0001
    assert paths["tracking"] == out / "tracking" / "0001.txt"
    table = read_tracking_results(paths["tracking"])
    lines = [line.split() for line in paths["tracking"].read_text().splitlines() if line.strip()]
    assert len(lines) == len(table) == len(result_0001.thresholded()) > 1000
    assert {len(tokens) for tokens in lines} == {18}, "every line carries a score"
    assert np.allclose(table.score, result_0001.thresholded().score, atol=1e-5)
    assert (table.score >= result_0001.min_track_score).all()
    assert table.frame.min() >= 0 and table.frame.max() < len(seq_0001)
    # boxes in the camera frame, on the labelled cars: 0.90 of those within 40 m with the
    # defaults (0.64 of all: see _overlap_fraction)
    gt = seq_0001.gt_objects
    gt = gt.select(np.isin(gt.cls, ["Car", "Van"]))
    assert _overlap_fraction(table, gt) >= 0.8


def test_real_0001_tracked_objects(seq_0001, result_0001):
    assert result_0001.frame == "world"  # 0001 has oxts
    assert result_0001.num_frames == len(seq_0001) == 447
    assert len(result_0001.objects) > 20
    reported = 0
    for o in result_0001.objects:
        K = len(o.frames)
        assert o.cls == "Car" and o.link == "planar"
        assert o.state in ("confirmed", "lost", "dead")
        assert np.array_equal(o.frames, np.arange(o.frames[0], o.frames[0] + K))
        assert o.T_w_o.shape == (K, 4, 4)
        R = o.T_w_o[:, :3, :3]
        assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-6)
        assert np.allclose(np.linalg.det(R), 1.0, atol=1e-6)
        assert np.allclose(o.T_w_o[:, 3], [0, 0, 0, 1])
        assert o.size.shape == (3,) and (o.size > 0).all()
        for name in ("velocity_kmh", "detected", "reported", "score"):
            assert getattr(o, name).shape == (K,), name
        assert o.detected.dtype == bool and o.reported.dtype == bool
        assert np.isfinite(o.velocity_kmh).all() and (o.velocity_kmh >= 0).all()
        assert o.velocity_kmh.max() < 200, o
        assert (o.score[~o.detected] == 0).all()
        assert o.mean_score == pytest.approx(o.score[o.detected].mean())
        reported += int(o.reported.sum())
    assert reported == len(result_0001.tracking)


def test_real_camera_frame(kitti_tracking, seq_0001):
    detections = kitti_tracking.joinpath(*DETECTIONS)
    seq_0006 = _open(kitti_tracking, "0006")
    assert seq_0006.gt_poses is None
    result_0006 = track_detections(seq_0006, detections)
    assert result_0006.frame == "camera"
    assert len(result_0006.objects) > 5
    config = Config()
    config.objects.frame = "camera"
    result = track_detections(seq_0001, detections, config)
    assert result.frame == "camera"
    # in the camera frame a track's poses are its boxes: the table repeats them
    for o in result.objects[:10]:
        for f, T in zip(o.frames[o.reported], o.T_w_o[o.reported]):
            row = (result.tracking.frame == f) & (result.tracking.track_id == o.track_id)
            assert np.allclose(result.tracking.box_3d[row][0, :3], T[:3, 3], atol=1e-6)
    config.objects.frame = "world"
    with pytest.raises(ValueError, match="camera poses"):
        track_detections(seq_0006, detections, config)


def test_real_save_writes_every_file(result_0001, saved_0001):
    out, paths = saved_0001
    assert set(paths) == {"tracking", "tracking_all", "objects", "timings", "config"}
    assert paths["tracking_all"] == out / "tracking_all" / "0001.txt"
    assert len(read_tracking_results(paths["tracking_all"])) == len(result_0001.tracking)
    arrays = np.load(paths["objects"])
    assert str(arrays["frame"]) == "world"
    for o in result_0001.objects:
        assert np.array_equal(arrays[f"{o.track_id}/T_w_o"], o.T_w_o)
        assert np.array_equal(arrays[f"{o.track_id}/frames"], o.frames)
    timings = json.loads(paths["timings"].read_text())
    assert timings["frames"] == 447 and timings["tracking_frame"] == "world"
    assert timings["frames_per_second"] == pytest.approx(result_0001.frames_per_second, abs=0.1)
    assert timings["frames_per_second"] > 0
    assert Config.from_yaml(paths["config"]).objects == result_0001.config.objects


def test_cli_run_0006_writes_tracking(kitti_tracking, tmp_path, capsys):
    out = tmp_path / "res"
    code = cli_main(["run", str(kitti_tracking), "--seq", "0006", "--no-images", "--no-progress",
                     "--detections", str(kitti_tracking.joinpath(*DETECTIONS)), "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    table = read_tracking_results(out / "tracking" / "0006.txt")
    assert len(table) > 100 and set(table.cls) == {"Car"}
    assert "camera frame" in capsys.readouterr().out


# ------------------------------------------- output policy: confidence, backcast, gaps (real)


def test_real_0001_track_score_is_the_range_corrected_confidence(result_0001):
    cfg = Config().objects
    far = 0
    for o in result_0001.objects:
        det = o.detected
        corrected = o.score[det] + cfg.range_score_slope * np.maximum(
            0.0, o.range[det] - cfg.range_score_start)
        assert o.confidence == pytest.approx(corrected.mean())
        far += int(o.confidence > o.mean_score + 1e-9)
        rows = result_0001.tracking.track_id == o.track_id
        assert np.allclose(result_0001.tracking.score[rows], o.confidence)
    assert far > 10, "far tracks gain confidence"
    kept = {o.track_id for o in result_0001.objects if o.confidence >= cfg.min_track_score}
    assert set(result_0001.thresholded().track_ids) == kept & set(result_0001.tracking.track_ids)


def test_real_0001_backcast_rows(result_0001, seq_0001):
    cfg = Config().objects
    backcast = [o for o in result_0001.objects if o.backcast]
    assert len(backcast) > 10
    num_shown = num_beside = 0
    for o in backcast:
        b = o.backcast
        assert b <= cfg.backcast_frames
        assert not o.detected[:b].any() and o.detected[b], "backcast rows precede the first detection"
        assert o.range[b] >= cfg.backcast_min_range
        assert (o.score[:b] == 0).all()
        # each in front of its camera and at least backcast_min_range away
        T_c_w = np.linalg.inv(seq_0001.gt_poses[o.frames[:b]])
        p = np.einsum("kij,kj->ki", T_c_w[:, :3], np.c_[o.T_w_o[:b, :3, 3], np.ones(b)])
        assert (p[:, 2] > 0).all()
        assert (np.linalg.norm(p, axis=1) >= cfg.backcast_min_range - 1e-6).all()
        # reported where its box shows in the left image (KITTI labels nothing beside it)
        boxes = _camera_frame_boxes(T_c_w, o.T_w_o[:b], o.size)
        shown = in_image(project_boxes(boxes, seq_0001.calib.P2, *_image_size(seq_0001)))
        np.testing.assert_array_equal(o.reported[:b], shown)
        num_shown += int(shown.sum())
        num_beside += int((~shown).sum())
    # measured: 803 of the 823 backcast rows show; the rest lead cars first seen at its edge
    assert num_shown > 10 * num_beside > 0
    assert all(o.backcast == 0 or o.range[o.backcast] >= cfg.backcast_min_range
               for o in result_0001.objects)


@pytest.fixture(scope="module")
def policy_ablation(kitti_tracking, tmp_path_factory):
    """MOTA (devkit protocol) on two validation sequences with the defaults and with each of
    the output-policy features of issue 8 off."""
    from twistslam.eval.mot import evaluate_mot

    variants = {"defaults": {}, "raw score": {"range_score_slope": 0.0},
                "no backcast": {"backcast_frames": 0}, "no interpolation": {"interpolate_gaps": False}}
    seqs = ["0006", "0010"]
    out = {}
    for name, change in variants.items():
        config = Config()
        for k, v in change.items():
            setattr(config.objects, k, v)
        res = tmp_path_factory.mktemp(name.replace(" ", "_"))
        for seq in seqs:
            r = track_detections(_open(kitti_tracking, seq), kitti_tracking.joinpath(*DETECTIONS), config)
            r.save(res)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            every = res / "every"
            every.mkdir()
            (every / "tracking").symlink_to(res / "tracking_all")
            out[name] = evaluate_mot(kitti_tracking, every, seqs, protocol="kitti",
                                     min_score=config.objects.min_track_score).overall
    return out


def test_real_output_policy_features_each_help(policy_ablation):
    # measured: MOTA 96.1 (FP 19, FN 23); raw score 89.5 (FN 108); no backcast 93.1 (FN 55);
    # interpolation makes no difference on these two (tests/cpp/objects/test_tracker_policy.cpp)
    d = policy_ablation["defaults"]
    assert d.mota > 94 and d.idsw == 0
    assert policy_ablation["raw score"].mota < d.mota - 4  # far cars fall under the threshold
    assert policy_ablation["raw score"].fn > d.fn + 50
    assert policy_ablation["no backcast"].fn > d.fn + 20   # far births reported earlier
    assert policy_ablation["no backcast"].mota < d.mota - 2
    assert policy_ablation["no interpolation"].mota <= d.mota


# ------------------------------------------------------------------------------- config section


def test_config_tracker_options_match_cpp_defaults():
    python = Config().objects.tracker_options()
    cpp = _core.objects.default_tracker_options()
    assert set(python) == set(cpp)
    differ = {k: (python[k], cpp[k]) for k in python
              if python[k] != cpp[k] or type(python[k]) is not type(cpp[k])}
    assert not differ, f"Config().objects vs C++ TrackerOptions (python, c++): {differ}"


def test_config_unknown_option_is_an_error():
    options = Config().objects.tracker_options()
    _core.objects.Tracker(options)  # the full set is accepted
    with pytest.raises(ValueError, match="max_cots"):
        _core.objects.Tracker({**options, "max_cots": 1.0})


GATES = {"giou_3d": 1.2, "iou_bev": 0.95, "centre_distance": 2.0}  # each in its metric's unit


@pytest.fixture(scope="module")
def metric_results(kitti_tracking, seq_0001):
    results = {}
    for metric, gate in GATES.items():
        config = Config()
        config.objects.association = metric
        config.objects.max_cost = config.objects.second_pass_max_cost = gate
        results[metric] = track_detections(seq_0001, kitti_tracking.joinpath(*DETECTIONS), config)
    return results


@pytest.mark.parametrize("metric", list(GATES))
def test_config_association_metrics_run(metric, metric_results, seq_0001):
    result = metric_results[metric]
    gt = seq_0001.gt_objects
    cars = gt.select(np.isin(gt.cls, ["Car", "Van"]))
    assert _overlap_fraction(result.thresholded(), cars) >= 0.7
    others = [m for m in GATES if m != metric]
    assert all(len(metric_results[m].tracking) != len(result.tracking)
               or not np.array_equal(metric_results[m].tracking.box_3d, result.tracking.box_3d)
               for m in others), "the metric must reach the tracker"


def test_config_unknown_metric_names_the_valid_ones(seq_0001, kitti_tracking):
    config = Config()
    config.objects.association = "iou_3d"
    with pytest.raises(ValueError, match="iou_3d") as info:
        track_detections(seq_0001, kitti_tracking.joinpath(*DETECTIONS), config)
    for name in GATES:
        assert name in str(info.value)


def test_config_iou_bev_default_gate_keeps_far_detections_apart():
    # FAILS (real bug): max_cost = 1.2 and second_pass_max_cost = 1.0 are GIoU gates; with
    # association = iou_bev the cost 1 - IoU never exceeds 1, so nothing is gated and a
    # detection 33 m away is associated with the track (on 0001: 34 tracks instead of ~170,
    # 44 % of the reported boxes on a labelled car instead of 86 %).
    config = Config().objects
    config.association = "iou_bev"
    tracker = _core.objects.Tracker(config.tracker_options())
    one = (np.array([9.0]), np.array([0]), np.array([True]))
    for f in range(3):
        tracker.step(f, np.eye(4), np.array([[0.0, 1.0, 10.0, 4.0, 1.8, 1.5, 0.0]]), *one)
    tracker.step(3, np.eye(4), np.array([[15.0, 1.0, 40.0, 4.0, 1.8, 1.5, 0.0]]), *one)
    first = tracker.tracks()[0]
    assert not first["detected"][first["frames"] == 3].any(), "a 33 m jump was associated"


# ------------------------------------------------------------------------------ assignment


@pytest.mark.parametrize("shape", [(1, 1), (5, 5), (8, 8), (3, 7), (7, 3), (12, 9)])
def test_solve_assignment_matches_scipy(shape):
    rng = np.random.default_rng(sum(shape))
    for _ in range(20):
        cost = rng.uniform(-1.0, 3.0, size=shape)
        pairs = _core.objects.solve_assignment(cost, np.inf)
        rows, cols = linear_sum_assignment(cost)
        assert pairs.shape == (min(shape), 2) and pairs.dtype == np.int64
        assert len(set(pairs[:, 0])) == len(set(pairs[:, 1])) == min(shape)
        total = cost[pairs[:, 0], pairs[:, 1]].sum()
        assert total == pytest.approx(cost[rows, cols].sum(), abs=1e-9)


@pytest.mark.parametrize("shape", [(6, 6), (4, 9), (9, 4)])
def test_solve_assignment_never_above_max_cost(shape):
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import maximum_bipartite_matching

    rng = np.random.default_rng(7)
    for max_cost in (0.2, 0.5, 1.0):
        cost = rng.uniform(0.0, 2.0, size=shape)
        cost[rng.uniform(size=shape) < 0.1] = np.nan  # forbidden too
        pairs = _core.objects.solve_assignment(cost, max_cost)
        chosen = cost[pairs[:, 0], pairs[:, 1]]
        assert (chosen <= max_cost).all()
        assert len(set(pairs[:, 0])) == len(set(pairs[:, 1])) == len(pairs)
        allowed = csr_matrix(np.nan_to_num(cost, nan=np.inf) <= max_cost)
        most = int((maximum_bipartite_matching(allowed, perm_type="column") >= 0).sum())
        assert len(pairs) == most, "the most allowed pairs"
