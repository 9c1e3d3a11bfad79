"""twistslam.run / Slam / Result / ``twistslam run``.

Two parts:

- The Python side (frame loading and checks, labels, Result, timings, files, CLI) against
  ``FakeSystem``, a TEST DOUBLE of ``twistslam._core.slam.System`` defined here and
  patched in per test; it never ships.
- End to end against the real C++ core on a short low-resolution simulated sequence: RPE
  thresholds, a blank frame flagged lost then recovered, a one-frame run.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import twistslam
from twistslam import Config, Result, Slam, cli
from twistslam.datasets import (
    Calibration, KittiTracking, read_poses, write_calibration, write_poses)
from twistslam.timings import Timings

SEQ = "0000"
W, H = 64, 48
# the tiny sequences have no LiDAR, which the reader reports; camera SLAM does not need it
pytestmark = pytest.mark.filterwarnings("ignore::twistslam.datasets.MissingDataWarning")


# ------------------------------------------------------------------------ the test double
class FakeSystem:
    """TEST DOUBLE of ``twistslam._core.slam.System`` (same call signature and output keys).

    Moves 0.5 m forward per frame; a blank left or right image (one grey level) is "lost",
    the first good frame after a loss "relocalized"; frames where ``index % 5 == 0`` are
    keyframes and only they report a ``local_ba`` stage.
    """

    instances: list["FakeSystem"] = []

    def __init__(self, camera, options):
        self.camera, self.options = camera, options
        self.calls: list[dict] = []
        self.was_lost = False
        self.nan_when_lost = False
        FakeSystem.instances.append(self)

    def track(self, index, timestamp, image_left, image_right, labels, points_c=None,
              instances=None, flow=None, boxes=None, scores=None, class_ids=None,
              open_ends=None, point_extents=None, headings_known=None):
        self.calls.append(dict(index=index, timestamp=timestamp, shape=image_left.shape,
                               labels=None if labels is None else labels.copy(),
                               points_c=None if points_c is None else points_c.shape,
                               instances=None if instances is None else instances.copy(),
                               flow=None if flow is None else flow.shape,
                               boxes=None if boxes is None else np.array(boxes),
                               class_ids=None if class_ids is None else np.array(class_ids),
                               open_ends=None if open_ends is None else np.array(open_ends),
                               point_extents=None if point_extents is None
                               else np.array(point_extents),
                               headings_known=None if headings_known is None
                               else np.array(headings_known)))
        blank = image_left.min() == image_left.max() or image_right.min() == image_right.max()
        if blank:
            status = "lost"
        elif len(self.calls) == 1:
            status = "initialized"
        else:
            status = "relocalized" if self.was_lost else "ok"
        self.was_lost = blank
        T = np.eye(4)
        T[2, 3] = 0.5 * index
        if blank and self.nan_when_lost:
            T[:] = np.nan
        keyframe = index % 5 == 0 and not blank
        timings = {"features": 2.0, "stereo": 1.0}
        if keyframe:
            timings["local_ba"] = 10.0
        return dict(status=status, T_w_c=T, is_keyframe=keyframe, num_inliers=0 if blank else 99,
                    num_map_points=10 * len(self.calls), num_keyframes=1 + index // 5,
                    timings_ms=timings)

    def keyframes(self):
        idx = np.array([c["index"] for c in self.calls if c["index"] % 5 == 0])
        return {"frame_index": idx, "T_w_c": np.tile(np.eye(4), (len(idx), 1, 1))}

    def map_points(self):
        return {"X_w": np.zeros((3, 3)), "cluster_id": np.zeros(3, np.int64),
                "num_observations": np.full(3, 2)}

    def objects(self):
        return []

    def smooth_objects(self):
        self.smoothed = True
        return {"num_tracks": 0, "num_rejected": 0, "num_residuals": 0}

    def reset(self):
        self.calls.clear()


@pytest.fixture
def fake(monkeypatch):
    FakeSystem.instances = []
    monkeypatch.setattr("twistslam.slam._new_system", FakeSystem)
    return FakeSystem


# ------------------------------------------------------------------ a tiny KITTI layout
def tiny_calibration() -> Calibration:
    P2 = np.array([[100.0, 0, W / 2, 0], [0, 100.0, H / 2, 0], [0, 0, 1, 0]])
    P3 = P2.copy()
    P3[0, 3] = -100.0 * 0.5  # 0.5 m baseline
    I34 = np.hstack([np.eye(3), np.zeros((3, 1))])
    return Calibration(P0=P2, P1=P3, P2=P2, P3=P3, R_rect=np.eye(3), Tr_velo_cam=I34,
                       Tr_imu_velo=I34)


def write_tiny_sequence(root: Path, frames: int = 8, seq: str = SEQ) -> Path:
    """Textured random stereo images, calibration and ground-truth poses; returns root."""
    base = root / "training"
    write_calibration(base / "calib" / f"{seq}.txt", tiny_calibration())
    rng = np.random.default_rng(0)
    for i in range(frames):
        for cam in ("image_02", "image_03"):
            path = base / cam / seq / f"{i:06d}.png"
            path.parent.mkdir(parents=True, exist_ok=True)
            Image.fromarray(rng.integers(0, 255, (H, W, 3), dtype=np.uint8)).save(path)
    poses = np.tile(np.eye(4), (frames, 1, 1))
    poses[:, 2, 3] = 0.5 * np.arange(frames)
    write_poses(base / "poses" / f"{seq}.txt", poses)
    return root


@pytest.fixture
def tiny(tmp_path) -> Path:
    return write_tiny_sequence(tmp_path / "data")


def image_path(root: Path, cam: str, i: int) -> Path:
    return root / "training" / cam / SEQ / f"{i:06d}.png"


def quiet_run(*args, **kwargs) -> Result:
    return twistslam.run(*args, progress=False, **kwargs)


# ------------------------------------------------------------------ Python side, double
def test_run_result_arrays(fake, tiny):
    result = quiet_run((tiny, SEQ))
    n = 8
    assert isinstance(result, Result) and len(result) == n and result.seq == SEQ
    assert result.camera_poses.shape == (n, 4, 4) and result.camera_poses.dtype == np.float64
    assert list(result.status) == ["initialized"] + ["ok"] * (n - 1)
    np.testing.assert_array_equal(result.frames, np.arange(n))
    np.testing.assert_array_equal(result.is_keyframe, np.arange(n) % 5 == 0)
    assert result.num_inliers.tolist() == [99] * n and result.num_lost == 0
    assert result.keyframes["frame_index"].tolist() == [0, 5]
    assert result.map_points["X_w"].shape == (3, 3)
    assert result.config == Config()
    # what the core was given: the calibrated camera of the image size, the options dict
    system = fake.instances[0]
    assert (system.camera.width, system.camera.height) == (W, H)
    assert system.camera.baseline == pytest.approx(0.5)
    assert system.options == Config().to_options()
    assert [c["timestamp"] for c in system.calls] == pytest.approx(0.1 * np.arange(n))
    assert all(c["shape"] == (H, W, 3) and c["labels"] is None for c in system.calls)


def test_camera_poses_are_the_refined_trajectory(fake, tiny, monkeypatch):
    class RefiningSystem(FakeSystem):  # a core that keeps a trajectory refined by BA
        def trajectory(self):
            idx = np.array([c["index"] for c in self.calls if c["index"] != 2])
            T = np.tile(np.eye(4), (len(idx), 1, 1))
            T[:, 0, 3] = 0.01  # what BA moved
            T[:, 2, 3] = 0.5 * idx
            return {"frame_index": idx, "T_w_c": T, "status": ["ok"] * len(idx)}

    monkeypatch.setattr("twistslam.slam._new_system", RefiningSystem)
    result = quiet_run((tiny, SEQ))
    np.testing.assert_allclose(result.camera_poses[:, 2, 3], 0.5 * np.arange(8))
    np.testing.assert_allclose(result.camera_poses[:, 0, 3], [0.01] * 2 + [0] + [0.01] * 5)
    np.testing.assert_allclose(result.tracked_poses[:, 0, 3], 0)


def test_timings(fake, tiny):
    t = quiet_run((tiny, SEQ)).timings
    assert set(t.stages) == {"load", "track", "features", "stereo", "local_ba"}
    assert np.isnan(t.stages["local_ba"]).sum() == 6  # only keyframes 0 and 5 ran it
    assert (t.frame_ms >= t.stages["track"]).all()
    s = t.summary()
    assert set(s) == {"frames", "hz", "per_frame_ms", "stages", "after_loop_ms"}
    assert s["after_loop_ms"] == {}  # no segmentation: no objects to smooth
    assert set(s["per_frame_ms"]) == {"median", "p90", "max"}
    assert s["frames"] == 8 and s["hz"] > 0
    assert s["stages"]["local_ba"] == 10.0 and s["stages"]["features"] == 2.0


def test_timings_summary_numbers():
    t = Timings.from_frames([{"load": 1.0, "track": 9.0, "ba": 5.0},
                             {"load": 1.0, "track": 19.0},
                             {"load": 2.0, "track": 28.0, "ba": 7.0}], [10.0, 20.0, 30.0])
    s = t.summary()
    assert s["frames"] == 3 and s["hz"] == pytest.approx(3 / 0.06)
    assert s["per_frame_ms"] == {"median": 20.0, "p90": 28.0, "max": 30.0}
    assert s["stages"] == {"load": 1.0, "track": 19.0, "ba": 6.0}
    assert Timings.from_frames([], []).summary()["frames"] == 0
    with pytest.raises(ValueError, match="2 stage records for 1 frame times"):
        Timings.from_frames([{}, {}], [1.0])


def test_save_writes_the_results_directory(fake, tiny, tmp_path):
    config = Config().override("tracking.min_inliers=33")
    result = quiet_run((tiny, SEQ), config)
    paths = result.save(tmp_path / "res")
    assert {p.name for p in paths.values()} == {"camera_poses.txt", "timings.json",
                                                "config.yaml", "status.txt"}
    np.testing.assert_allclose(read_poses(paths["camera_poses"]), result.camera_poses)
    timings = json.loads(paths["timings"].read_text())
    assert timings == json.loads(json.dumps(result.timings.summary()))
    assert Config.from_yaml(paths["config"]).tracking.min_inliers == 33
    lines = paths["status"].read_text().splitlines()
    assert lines[:2] == ["0 initialized", "1 ok"] and len(lines) == 8
    # the run copied the config: the caller's object is not the result's
    assert result.config == config and result.config is not config


def test_inputs_accepted(fake, tiny, tmp_path):
    yaml_path = tmp_path / "c.yaml"
    yaml_path.write_text("run:\n  max_frames: 2\n")
    a = quiet_run(KittiTracking(tiny, SEQ), yaml_path)
    b = quiet_run(tiny / "training" / "image_02" / SEQ, {"run": {"max_frames": 3}})
    c = quiet_run((str(tiny), 0), Config().override("run.max_frames=4"))
    assert (len(a), len(b), len(c)) == (2, 3, 4)


def test_start_and_max_frames(fake, tiny, tmp_path):
    result = quiet_run((tiny, SEQ), Config().override(["run.start_frame=3", "run.max_frames=4"]))
    np.testing.assert_array_equal(result.frames, [3, 4, 5, 6])
    assert result.status[0] == "initialized"
    poses = read_poses(result.save(tmp_path / "res")["camera_poses"])
    # line i = dataset frame i, as `twistslam eval` reads it
    assert len(poses) == 7 and np.isnan(poses[:3, :3]).all() and np.isfinite(poses[3:]).all()
    with pytest.raises(ValueError, match="run.start_frame = 9 but the sequence has 8 frames"):
        quiet_run((tiny, SEQ), Config().override("run.start_frame=9"))


def test_one_frame_sequence(fake, tmp_path):
    root = write_tiny_sequence(tmp_path / "one", frames=1)
    result = quiet_run((root, SEQ))
    assert len(result) == 1 and list(result.status) == ["initialized"]
    saved = result.save(tmp_path / "res")
    assert json.loads(saved["timings"].read_text())["frames"] == 1


def test_blank_frame_is_lost_and_the_run_goes_on(fake, tiny):
    Image.fromarray(np.zeros((H, W, 3), np.uint8)).save(image_path(tiny, "image_02", 3))
    result = quiet_run((tiny, SEQ))
    assert list(result.status[2:5]) == ["ok", "lost", "relocalized"] and result.num_lost == 1
    assert np.isfinite(result.camera_poses).all()


def test_lost_frame_pose_is_predicted_when_the_core_gives_none(fake, tiny):
    Image.fromarray(np.full((H, W, 3), 128, np.uint8)).save(image_path(tiny, "image_03", 4))
    slam = Slam(Config(), KittiTracking(tiny, SEQ).calib)
    seq = KittiTracking(tiny, SEQ)
    outs = []
    for i in range(6):
        outs.append(slam.track(seq[i]))
        fake.instances[0].nan_when_lost = True
    assert outs[4].status == "lost"
    # constant velocity from frames 2 and 3: 0.5 m per frame along z
    np.testing.assert_allclose(outs[4].T_w_c[2, 3], 2.0)
    assert outs[5].status == "relocalized"


def test_missing_right_camera_fails_before_tracking(fake, tiny):
    shutil.rmtree(tiny / "training" / "image_03")
    with pytest.warns(UserWarning, match="image_03"):
        seq = KittiTracking(tiny, SEQ)
    with pytest.raises(FileNotFoundError, match=r"image_03/0000 not found: the sequence has no "
                       r"right images, and stereo SLAM needs both"):
        quiet_run(seq)
    assert not fake.instances  # nothing was tracked


def test_missing_right_image_names_frame_and_file(fake, tiny):
    image_path(tiny, "image_03", 5).unlink()
    with pytest.raises(FileNotFoundError, match=r"frame 5: no right image \(.*image_03/0000/"
                       r"000005\.png not found\)"):
        quiet_run((tiny, SEQ))


def test_unreadable_image_names_frame_and_file(fake, tiny):
    image_path(tiny, "image_02", 2).write_bytes(b"not a png")
    with pytest.raises(ValueError, match=r"frame 2: cannot read .*image_02/0000/000002\.png"):
        quiet_run((tiny, SEQ))


def test_wrong_image_size_names_the_frame(fake, tiny):
    for cam in ("image_02", "image_03"):
        Image.fromarray(np.zeros((H // 2, W // 2, 3), np.uint8)).save(image_path(tiny, cam, 6))
    with pytest.raises(ValueError, match=r"frame 6: image size 32x24 differs from 64x48"):
        quiet_run((tiny, SEQ))


def test_left_right_size_mismatch(fake, tiny):
    Image.fromarray(np.zeros((H, W // 2, 3), np.uint8)).save(image_path(tiny, "image_03", 1))
    with pytest.raises(ValueError, match=r"frame 1: left image \(48, 64, 3\) and right image "
                       r"\(48, 32, 3\) differ"):
        quiet_run((tiny, SEQ))


def test_empty_sequence(fake, tmp_path):
    root = write_tiny_sequence(tmp_path / "empty", frames=0)
    (root / "training" / "poses" / f"{SEQ}.txt").unlink()
    for cam in ("image_02", "image_03"):
        (root / "training" / cam / SEQ).mkdir(parents=True)
    with pytest.raises(ValueError, match="the sequence has no frames"):
        quiet_run((root, SEQ))


def test_slam_checks_images_directly(fake):
    slam = Slam(None, tiny_calibration(), image_size=(W, H))
    frame = twistslam.datasets.Frame(0, 0.0, np.zeros((H, W), np.uint8), None, None, None,
                                     tiny_calibration())
    with pytest.raises(ValueError, match="frame 0: no right image"):
        slam.track(frame)
    frame.image_right = np.zeros((H, W), np.float32)
    with pytest.raises(ValueError, match="right image must be uint8"):
        slam.track(frame)
    frame.image_right = np.zeros((H, W), np.uint8)
    with pytest.raises(ValueError, match=r"labels of shape \(2, 2\)"):
        slam.track(frame, labels=np.zeros((2, 2)))
    out = slam.track(frame)  # grey images are fine; blank -> lost, not an error
    assert out.status == "lost" and set(out.timings_ms) >= {"track", "features"}
    assert slam.keyframes()["T_w_c"].shape[1:] == (4, 4)


def write_panoptic(root: Path, i: int, ids: np.ndarray) -> None:
    path = root / "training" / "panoptic" / SEQ / f"{i:06d}.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(ids.astype(np.uint16)).save(path)


def test_panoptic_labels_are_passed_as_class_ids(fake, tiny):
    ids = np.full((H, W), 7, np.uint16)  # road
    ids[10:20, 10:20] = 26 * 1000 + 4  # car, instance 3
    ids[30:, :5] = 24 * 1000 + 1  # person
    for i in range(8):
        if i != 2:  # frame 2 has no label file: passes None
            write_panoptic(tiny, i, ids)
    masked = Config().override("tracking.dynamic_class_ids=[26]")
    quiet_run((tiny, SEQ), masked)
    calls = fake.instances[-1].calls
    labels = calls[0]["labels"]
    assert labels.dtype == np.int32 and labels.shape == (H, W)
    assert set(np.unique(labels)) == {7, 24, 26} and labels[15, 15] == 26
    assert calls[2]["labels"] is None
    # not read when nothing is masked, or when switched off
    shutil.rmtree(tiny / "training" / "panoptic")
    with pytest.warns(UserWarning, match="dynamic_class_ids is set but the sequence has no "
                      "panoptic/ labels"):
        quiet_run((tiny, SEQ), masked)
    quiet_run((tiny, SEQ))
    quiet_run((tiny, SEQ), Config().override(["tracking.dynamic_class_ids=[26]",
                                              "run.use_labels=false"]))
    assert all(c["labels"] is None for s in fake.instances[-3:] for c in s.calls)


def test_progress_bar_shows_hz(fake, tiny, capsys):
    twistslam.run((tiny, SEQ), progress=True)
    err = capsys.readouterr().err
    assert "Hz" in err and "8/8" in err


def test_cli_run(fake, tiny, tmp_path, capsys):
    out = tmp_path / "res"
    cfg = tmp_path / "c.yaml"
    cfg.write_text("tracking:\n  min_inliers: 20\n  max_hamming: 60\n")
    code = cli.main(["run", str(tiny), "--seq", SEQ, "--out", str(out), "--config", str(cfg),
                     "--set", "tracking.min_inliers=40", "run.max_frames=5",
                     "--set", "orb.num_features=500", "--no-progress"])
    assert code == 0
    text = capsys.readouterr().out
    assert "0000: 5 frames" in text and "Hz" in text and "0 lost" in text
    saved = Config.from_yaml(out / "config.yaml")
    # --set wins over --config, which wins over the defaults
    assert (saved.tracking.min_inliers, saved.tracking.max_hamming) == (40, 60)
    assert (saved.run.max_frames, saved.orb.num_features) == (5, 500)
    assert fake.instances[0].options["orb"]["num_features"] == 500
    assert len(read_poses(out / "camera_poses.txt")) == 5
    assert json.loads((out / "timings.json").read_text())["frames"] == 5


@pytest.mark.parametrize("extra, message", [
    (["--set", "tracking.min_inlier=3"], "unknown key 'tracking.min_inlier'; keys of section"),
    (["--set", "tracking.min_inliers=abc"], "tracking.min_inliers: expected int"),
    (["--config", "/nonexistent/c.yaml"], "No such file"),
])
def test_cli_run_user_errors_are_one_line(fake, tiny, tmp_path, capsys, extra, message):
    code = cli.main(["run", str(tiny), "--seq", SEQ, "--out", str(tmp_path / "r"),
                     "--no-progress", *extra])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("twistslam run: error: ") and message in err
    assert len(err.strip().splitlines()) == 1


def test_cli_run_missing_image(fake, tiny, tmp_path, capsys):
    image_path(tiny, "image_03", 0).unlink()
    code = cli.main(["run", str(tiny), "--seq", SEQ, "--out", str(tmp_path / "r"),
                     "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "frame 0: no right image" in err


def test_cli_still_has_eval():
    parser = cli.build_parser()
    args = parser.parse_args(["eval", "root", "res", "--seq", "0001"])
    assert args.command == "eval"


def test_slam_takes_a_stereo_camera(fake):
    camera = tiny_calibration().stereo_camera(W, H)
    slam = Slam(None, camera)
    assert slam.image_size == (W, H) and slam.camera is camera
    rng = np.random.default_rng(1)
    image = rng.integers(0, 255, (H, W), dtype=np.uint8)
    frame = twistslam.datasets.Frame(3, 0.3, image, image, None, None, tiny_calibration())
    assert slam.track(frame).status == "initialized"
    assert fake.instances[0].camera is camera
    frame.image_left = frame.image_right = image[:, :-1]
    with pytest.raises(ValueError, match="frame 3: image size 63x48 differs from 64x48"):
        slam.track(frame)


def test_demo_generates_the_sequence_once(monkeypatch, tmp_path):
    from twistslam import demo

    calls = []

    def fake_generate(out, **kwargs):  # stands in for the simulator
        calls.append(kwargs)
        (Path(out) / "training").mkdir(parents=True)
        return Path(out)

    monkeypatch.setattr("twistslam.sim.generate", fake_generate)
    (tmp_path / "urban-seed0-n5.partial").mkdir()  # an interrupted earlier generation
    root = demo.cached_sequence(tmp_path, frames=5, progress=False)
    assert root == tmp_path / "urban-seed0-n5" and (root / "training").is_dir()
    assert calls == [dict(scenario="urban", frames=5, seed=0, seq="0000", progress=False)]
    assert not (tmp_path / "urban-seed0-n5.partial").exists()
    assert demo.cached_sequence(tmp_path, frames=5, progress=False) == root
    assert len(calls) == 1  # cached
    (root / demo.MARKER).unlink()  # incomplete: generated again
    demo.cached_sequence(tmp_path, frames=5, progress=False)
    assert len(calls) == 2
    assert demo.demo_config().tracking.dynamic_class_ids == demo.MOVABLE_CLASSES


# ------------------------------------------------------------- end to end, the real core
SIM_W, SIM_H, SIM_FRAMES = 621, 188, 30


@pytest.fixture(scope="module")
def sim_root(tmp_path_factory) -> Path:
    """A short half-resolution urban sequence, only what SLAM reads (images, panoptic)."""
    from twistslam.sim import generate

    root = tmp_path_factory.mktemp("sim") / "urban"
    generate(root, scenario="urban", frames=SIM_FRAMES, seed=0, seq=SEQ, width=SIM_W,
             height=SIM_H, progress=False, lidar__enabled=False, oracle__enabled=False,
             output__flow=False, output__disparity=False, output__meshes=False,
             output__lidar_labels=False)
    return root


def copy_sequence(root: Path, dst: Path) -> Path:
    shutil.copytree(root, dst)
    return dst


def camera_errors(result: Result, root: Path):
    from twistslam.eval.camera import evaluate_camera

    gt = KittiTracking(root, SEQ).gt_poses[result.frames]
    return evaluate_camera(gt, result.camera_poses)


def test_end_to_end_rpe(sim_root, tmp_path):
    result = twistslam.run((sim_root, SEQ), progress=False)
    assert len(result) == SIM_FRAMES
    assert result.status[0] == "initialized" and result.num_lost == 0, list(result.status)
    assert np.isfinite(result.camera_poses).all()
    np.testing.assert_allclose(result.camera_poses[0], np.eye(4), atol=1e-9)
    m = camera_errors(result, sim_root)
    # exact ground truth: half-resolution stereo tracks to a few cm and a tenth of a degree
    assert m.rpe_t_mean < 0.05, m
    assert m.rpe_r_mean < 0.15, m
    assert m.ate_rmse < 0.5, m
    assert result.is_keyframe[0] and result.keyframes["T_w_c"].shape[1:] == (4, 4)
    assert len(result.map_points["X_w"]) > 100
    s = result.timings.summary()
    assert {"features", "stereo", "track_motion", "track_local_map"} <= set(s["stages"])
    # the files `twistslam eval` reads
    from twistslam.eval.sequence import evaluate_sequence

    result.save(tmp_path / "res")
    metrics = evaluate_sequence(sim_root, tmp_path / "res", SEQ).to_dict()
    assert metrics["camera"]["rpe_t_mean"] == pytest.approx(m.rpe_t_mean, rel=1e-6)


def test_end_to_end_masks_movable_objects(sim_root):
    config = Config().override("tracking.dynamic_class_ids=[24, 26]")
    result = twistslam.run((sim_root, SEQ), config, progress=False)
    assert result.num_lost == 0
    assert camera_errors(result, sim_root).rpe_t_mean < 0.05


def test_end_to_end_blank_frame_is_lost_then_recovered(sim_root, tmp_path):
    root = copy_sequence(sim_root, tmp_path / "blank")
    blank = 12
    for cam in ("image_02", "image_03"):
        Image.fromarray(np.zeros((SIM_H, SIM_W, 3), np.uint8)).save(image_path(root, cam, blank))
    result = twistslam.run((root, SEQ), progress=False)  # never raises
    assert len(result) == SIM_FRAMES and np.isfinite(result.camera_poses).all()
    assert result.status[blank] == "lost", list(result.status)
    assert set(result.status[:blank]) <= {"initialized", "ok"}
    after = list(result.status[blank + 1:])
    assert after[0] == "relocalized" and set(after[1:]) == {"ok"}, after
    # the trajectory after the loss is still right frame to frame
    gt = KittiTracking(root, SEQ).gt_poses
    est = np.full((SIM_FRAMES, 4, 4), np.nan)
    good = np.flatnonzero(result.status != "lost")
    est[good] = result.camera_poses[good]
    from twistslam.eval.camera import evaluate_camera

    m = evaluate_camera(gt, est)
    # relocalised in the same map: the trajectory stays consistent, not just frame to frame
    assert m.rpe_t_mean < 0.03 and m.ate_rmse < 0.1, m  # seen: 0.009, 0.017


def test_end_to_end_blank_right_image_never_crashes(sim_root, tmp_path):
    # the left image alone still matches the map (monocular observations): lost or not,
    # the run goes on and tracks the frames after it
    root = copy_sequence(sim_root, tmp_path / "blank_right")
    blank = 12
    Image.fromarray(np.zeros((SIM_H, SIM_W, 3), np.uint8)).save(image_path(root, "image_03", blank))
    result = twistslam.run((root, SEQ), progress=False)
    assert len(result) == SIM_FRAMES and np.isfinite(result.camera_poses).all()
    assert result.status[blank] in ("ok", "lost")
    assert "lost" not in list(result.status[blank + 3:]), list(result.status)


def test_end_to_end_one_frame(sim_root):
    result = twistslam.run((sim_root, SEQ), Config().override("run.max_frames=1"),
                           progress=False)
    assert list(result.status) == ["initialized"]
    np.testing.assert_allclose(result.camera_poses[0], np.eye(4), atol=1e-12)
    assert result.timings.summary()["frames"] == 1


def test_end_to_end_bad_size_is_an_error(sim_root, tmp_path):
    root = copy_sequence(sim_root, tmp_path / "size")
    for cam in ("image_02", "image_03"):
        Image.fromarray(np.zeros((SIM_H - 1, SIM_W, 3), np.uint8)).save(image_path(root, cam, 4))
    with pytest.raises(ValueError, match=f"frame 4: image size {SIM_W}x{SIM_H - 1} differs"):
        twistslam.run((root, SEQ), progress=False)


def test_loader_thread_runs_at_a_lower_priority_than_the_loop():
    """run.loader_nice: the reading thread's niceness rises by it, the caller's stays."""
    import os
    import threading
    from concurrent.futures import ThreadPoolExecutor

    from twistslam.pipeline import _lower_priority

    def niceness() -> int:
        return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())

    mine = niceness()
    with ThreadPoolExecutor(max_workers=1, initializer=_lower_priority, initargs=(3,)) as pool:
        theirs = pool.submit(niceness).result()
    assert theirs == min(mine + 3, 19)
    assert niceness() == mine
    with ThreadPoolExecutor(max_workers=1, initializer=_lower_priority, initargs=(0,)) as pool:
        assert pool.submit(niceness).result() == mine
