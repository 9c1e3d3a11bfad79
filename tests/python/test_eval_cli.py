"""``twistslam eval`` end to end: perfect scores, the JSON layout, camera poses, bad input."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twistslam import cli
from twistslam.datasets import read_labels, write_poses, write_tracking_results
from twistslam.eval.camera import evaluate_camera
from twistslam.eval.results import ResultsNotFoundError
from twistslam.eval.sequence import evaluate_sequence

from conftest import require_real_data

ROOT = require_real_data("kitti_tracking")
LABEL = require_real_data("kitti_tracking", "training", "label_02", "0001.txt")

MOT_KEYS = {"mota", "motp", "idsw", "frag", "fp", "fn", "mt", "ml"}
OBJECT_KEYS = {"ate", "rpe_t", "rpe_r", "yaw", "tp_2d", "motp_2d", "tp_bv", "motp_bv", "tp_3d", "motp_3d"}
CAMERA_KEYS = {"rpe_t_mean", "rpe_r_mean", "rpe_t_rmse", "rpe_r_rmse", "ate_rmse"}


def test_cli_ground_truth_is_perfect(tmp_path, capsys):
    (tmp_path / "tracking").mkdir()
    shutil.copy(LABEL, tmp_path / "tracking" / "0001.txt")
    out = tmp_path / "m.json"
    root = tmp_path / "labels_only"  # calibration and labels, no oxts: the camera-frame case
    for folder in ("calib", "label_02"):
        shutil.copytree(ROOT / "training" / folder, root / "training" / folder)
    with pytest.warns(UserWarning, match="camera frame"):
        code = cli.main(["eval", str(root), str(tmp_path), "--seq", "0001", "--json", str(out),
                         "--plots", str(tmp_path / "plots"), "--markdown", str(tmp_path / "r.md")])
    assert code == 0
    text = capsys.readouterr().out
    assert "01 / 0 / car" in text and "CLEAR MOT" in text
    mot_lines = [line for line in text.splitlines() if line.startswith("01 ") and ("3D" in line)]
    assert mot_lines and "100.00" in mot_lines[0]

    m = json.loads(out.read_text())
    assert set(m) == {"objects", "objects_mean", "mot", "settings"}  # no camera_poses.txt -> no camera
    assert set(m["mot"]) == {"2d", "bv", "3d"}
    for mode, mot in m["mot"].items():
        assert MOT_KEYS <= set(mot)  # plus the protocol and the score-sweep metrics
        assert mot["mota"] == pytest.approx(100.0) and mot["motp"] == pytest.approx(100.0)
        assert (mot["idsw"], mot["frag"], mot["fp"], mot["fn"]) == (0, 0, 0, 0)
        assert mot["mt"] == pytest.approx(100.0) and mot["ml"] == 0.0
    assert set(m["objects_mean"]) == OBJECT_KEYS
    for obj in m["objects"]:
        assert set(obj) == OBJECT_KEYS | {"seq", "track_id", "class"}
        assert obj["seq"] == "0001" and obj["class"] == "car"
        assert obj["tp_3d"] == pytest.approx(100.0) and obj["ate"] == pytest.approx(0.0)
    assert (tmp_path / "plots" / "0001_objects_bev.png").stat().st_size > 1000
    assert "| seq / obj. id / class |" in (tmp_path / "r.md").read_text()


def planar_trajectory(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    poses, T = [], np.eye(4)
    for _ in range(n):
        poses.append(T.copy())
        d = np.eye(4)
        d[:3, :3] = Rotation.from_rotvec([0, rng.normal(0, 0.02), 0]).as_matrix()
        d[:3, 3] = [0, 0, 1.0]
        T = T @ d
    return np.stack(poses)


@pytest.fixture
def root_with_poses(tmp_path) -> tuple[Path, np.ndarray]:
    """A copy of sequence 0001 (calib + labels) with ground-truth camera poses added."""
    root = tmp_path / "kitti"
    for sub in ("calib", "label_02"):
        (root / "training" / sub).mkdir(parents=True)
        shutil.copy(ROOT / "training" / sub / "0001.txt", root / "training" / sub / "0001.txt")
    n = int(read_labels(LABEL).frame.max()) + 1
    poses = planar_trajectory(n)
    write_poses(root / "training" / "poses" / "0001.txt", poses)
    return root, poses


def test_camera_section_and_objects_in_estimated_world(root_with_poses, tmp_path, capsys):
    root, gt_poses = root_with_poses
    results = tmp_path / "results"
    # estimate: ground truth moved 1 m along world x, plus noise, with two frames missing
    est = gt_poses.copy()
    est[:, 0, 3] += 1.0
    est[1:, :3, 3] += np.random.default_rng(1).normal(0, 0.02, (len(est) - 1, 3))
    est[[10, 11]] = np.nan
    write_poses(results / "camera_poses.txt", est)
    write_tracking_results(results / "tracking" / "0001.txt", read_labels(LABEL))

    code = cli.main(["eval", str(root), str(results), "--seq", "1",
                     "--json", str(tmp_path / "m.json"), "--plots", str(tmp_path / "plots")])
    assert code == 0
    m = json.loads((tmp_path / "m.json").read_text())
    assert set(m["camera"]) == CAMERA_KEYS
    ref = evaluate_camera(gt_poses, est)
    assert ref.n_skipped == 2
    for k in CAMERA_KEYS:
        assert m["camera"][k] == pytest.approx(getattr(ref, k))
    assert ref.ate_rmse_unaligned > 0.9 and ref.ate_rmse < 0.1  # JSON holds the aligned ATE
    assert (tmp_path / "plots" / "0001_camera_bev.png").is_file()

    # boxes are exact, so every object error is the camera error: ~1 m canonical ATE
    metrics = evaluate_sequence(root, results, "0001")
    assert metrics.world_frame == "estimated camera poses"
    ates = np.array([o.ate for o in metrics.objects if np.isfinite(o.ate)])
    assert np.all(np.abs(ates - 1.0) < 0.1)
    aligned = evaluate_sequence(root, results, "0001", object_alignment="se3")
    assert aligned.to_dict()["objects_mean"]["ate"] < 0.1
    assert aligned.to_dict()["mot"] == metrics.to_dict()["mot"]


def test_camera_only_results(root_with_poses, tmp_path, capsys):
    root, gt_poses = root_with_poses
    write_poses(tmp_path / "r" / "camera_poses.txt", gt_poses)
    assert cli.main(["eval", str(root), str(tmp_path / "r"), "--seq", "0001",
                     "--json", str(tmp_path / "m.json")]) == 0
    m = json.loads((tmp_path / "m.json").read_text())
    assert set(m) == {"camera"}
    assert m["camera"]["ate_rmse"] == pytest.approx(0.0, abs=1e-9)
    assert "Camera" in capsys.readouterr().out


def test_results_dir_without_results_is_a_clear_error(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    with pytest.raises(ResultsNotFoundError, match="camera_poses.txt.*tracking/0001.txt"):
        evaluate_sequence(ROOT, tmp_path / "empty", "0001")
    assert cli.main(["eval", str(ROOT), str(tmp_path / "empty"), "--seq", "0001"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("twistslam eval: error:") and "camera_poses.txt" in err
    assert "Traceback" not in err
    assert cli.main(["eval", str(ROOT), str(tmp_path / "missing"), "--seq", "0001"]) == 2
    assert "not found" in capsys.readouterr().err


def test_malformed_tracking_line_names_file_and_line(tmp_path, capsys):
    lines = LABEL.read_text().splitlines()
    lines[2] = " ".join(lines[2].split()[:10])  # a truncated line 3
    path = tmp_path / "tracking" / "0001.txt"
    path.parent.mkdir()
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=rf"{path}:3: "):
        evaluate_sequence(ROOT, tmp_path, "0001")
    assert cli.main(["eval", str(ROOT), str(tmp_path), "--seq", "0001"]) == 2
    assert f"{path}:3:" in capsys.readouterr().err


def test_track_id_twice_in_a_frame_is_an_error(tmp_path):
    lines = LABEL.read_text().splitlines()
    row = next(line for line in lines if line.split()[1] != "-1")
    path = tmp_path / "tracking" / "0001.txt"
    path.parent.mkdir()
    path.write_text("\n".join(lines + [row]) + "\n")
    frame, tid = row.split()[:2]
    with pytest.raises(ValueError, match=rf"{path}: track id {tid} appears 2 times in frame {frame}"):
        evaluate_sequence(ROOT, tmp_path, "0001")


def test_bad_options_are_rejected(tmp_path):
    with pytest.raises(SystemExit):
        cli.main(["eval", str(ROOT), str(tmp_path), "--seq", "0001", "--iou", "1.5"])
    with pytest.raises(SystemExit):
        cli.main(["eval", str(ROOT), str(tmp_path), "--seq", "0001", "--difficulty", "extreme"])


def test_public_api_of_the_package():
    import twistslam.eval as ev

    assert ev.evaluate_sequence is evaluate_sequence
    for name in ev.__all__:
        assert hasattr(ev, name), name
    assert callable(ev.plot_trajectories)
