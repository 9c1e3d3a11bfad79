"""Bad input (issue 9, section 3): every case is one clear error naming the file, line or
option -- never a traceback, a hang or a silently wrong result -- or a documented graceful
behaviour. Sequences are a small simulated one (always available) and symlinks to the real
KITTI frames (``require_real_data``)."""

from __future__ import annotations

import os
import shutil
import struct
import subprocess
import sys
import tempfile
import warnings
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from twistslam import cli
from twistslam.datasets import (Calibration, read_calibration, read_detections, read_image,
                                read_labels, read_poses, write_calibration, write_poses)
from twistslam.demo import demo_config
from twistslam.pipeline import run
from twistslam.sim.generate import generate
from twistslam.datasets.png16 import read_png16, write_png16

from conftest import require_real_data

SEQ = "0000"
# the simulated sequence has no LiDAR, which its reader reports; camera SLAM does not need it
pytestmark = pytest.mark.filterwarnings("ignore::twistslam.datasets.MissingDataWarning")
LABEL = "0 1 Car 0 0 -1.5 100 120 220 200 1.5 1.6 3.9 2.0 1.6 12.0 -1.5"
DETECTION = "0, 2, 100, 120, 220, 200, 9.1, 1.5, 1.6, 3.9, 2.0, 1.6, 12.0, -1.5, -1.4"


@pytest.fixture(scope="module")
def sim_root(tmp_path_factory) -> Path:
    """10 frames at half KITTI size (the local BA runs on them), no LiDAR or extras."""
    out = tmp_path_factory.mktemp("sim")
    off = {f"output.{k}": False for k in ("flow", "disparity", "meshes", "lidar_labels")}
    return generate(out, frames=10, width=621, height=188, progress=False,
                    **{"lidar.enabled": False, "oracle.enabled": False, **off})


def call(args: list[str], capsys) -> tuple[int, list[str], str]:
    """Exit code, stderr lines and stdout of ``twistslam ARGS`` run in this process."""
    code = cli.main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.err.strip().splitlines(), captured.out


def call_warned(args: list[str], capsys) -> tuple[int, list[str], str, list[str]]:
    """:func:`call` and the messages of every warning it raised (pytest would hide them)."""
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        code, err, out = call(args, capsys)
    return code, err, out, [str(w.message) for w in record]


def one_error(err: list[str], command: str) -> str:
    assert len(err) == 1 and err[0].startswith(f"twistslam {command}: error: "), err
    return err[0]


def make_read_only(folder: Path, monkeypatch) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    folder.chmod(0o555)
    if os.geteuid() == 0:  # permissions do not bind root: refuse the probe as the OS would
        real = tempfile.TemporaryFile

        def refuse(*args, dir=None, **kwargs):
            if dir is not None and Path(dir).resolve() == folder.resolve():
                raise PermissionError(13, "Permission denied")
            return real(*args, dir=dir, **kwargs)

        monkeypatch.setattr(tempfile, "TemporaryFile", refuse)


# --------------------------------------------------------------------------- calibration
def edited_calibration(tmp_path: Path, key: str, column: int, value: str) -> Path:
    """The simulator's KITTI calibration with one number of matrix ``key`` replaced."""
    from twistslam.sim.world import load_calibration

    path = tmp_path / "calib.txt"
    write_calibration(path, load_calibration(None, 1242, 375))
    lines = path.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.split()[0] == key)
    tokens = lines[k].split()
    tokens[1 + column] = value
    lines[k] = " ".join(tokens)
    path.write_text("\n".join(lines) + "\n")
    return path


CALIB_CASES = [("P2", 0, "nan", 3, "not finite"), ("Tr_velo_cam", 3, "inf", 6, "not finite"),
               ("P2", 0, "0", 3, "focal length"), ("P3", 5, "-1e-9", 4, "focal length"),
               ("R_rect", 0, "0.09999239", 5, "not a rotation"),
               ("Tr_imu_velo", 0, "1e400", 7, "not finite")]


@pytest.mark.parametrize("key, column, value, line, what", CALIB_CASES)
def test_calibration_value_names_file_line_and_key(tmp_path, key, column, value, line, what):
    path = edited_calibration(tmp_path, key, column, value)
    with pytest.raises(ValueError, match=rf"calib\.txt:{line}: {key}: .*{what}"):
        read_calibration(path)


def test_calibration_built_in_code_names_the_field():
    P = np.array([[700.0, 0, 600, 0], [0, 700, 180, 0], [0, 0, 1, 0]])
    Tr = np.hstack([np.eye(3), [[0.0], [np.inf], [0.0]]])
    with pytest.raises(ValueError, match="Tr_velo_cam: holds NaN or inf"):
        Calibration(P0=P, P1=P, P2=P, P3=P, R_rect=np.eye(3), Tr_velo_cam=Tr, Tr_imu_velo=Tr)


def test_sim_with_nan_calibration_fails_at_once(tmp_path):
    """It used to hang forever: a subprocess, so that a hang fails instead of blocking."""
    calib = edited_calibration(tmp_path, "P2", 0, "nan")
    done = subprocess.run([sys.executable, "-m", "twistslam.cli", "sim", tmp_path / "out",
                           "--calib", calib, "--frames", "1", "--no-progress"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip() == f"twistslam sim: error: {calib}:3: P2: 'nan' is not finite (NaN or Inf)"


@pytest.mark.parametrize("key, column, value, line, what", CALIB_CASES[1:3])
def test_sim_with_bad_calibration_is_one_error(tmp_path, capsys, key, column, value, line, what):
    calib = edited_calibration(tmp_path, key, column, value)
    code, err, _ = call(["sim", tmp_path / "out", "--calib", calib, "--frames", 1,
                         "--no-progress"], capsys)
    assert code == 2 and f"calib.txt:{line}: {key}: " in one_error(err, "sim") and what in err[0]


# ---------------------------------------------------------- labels, results, detections
def write_lines(path: Path, lines: list[str]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(line + "\n" for line in lines))
    return path


def edit(line: str, column: int, value: str, sep: str = " ") -> str:
    tokens = line.split(sep)
    tokens[column] = value
    return sep.join(tokens)


@pytest.mark.parametrize("column, value", [(10, "nan"), (13, "inf"), (16, "-inf"),
                                           (6, "1e400"), (17, "nan"), (0, "nan"), (0, "inf"),
                                           (0, "1e30"), (0, "100001"), (0, "-3"), (1, "1e12")])
def test_label_and_result_values_name_file_and_line(tmp_path, column, value):
    good = LABEL + " 0.9"  # a result line: the 18th column is the score
    path = write_lines(tmp_path / "results.txt", [good, edit(good, column, value), good])
    with pytest.raises(ValueError, match=rf"^{path}:2: "):
        read_labels(path)


@pytest.mark.parametrize("column, value", [(0, "nan"), (0, "inf"), (0, "1e30"), (10, "nan"),
                                           (6, "inf")])
def test_detection_values_name_file_and_line(tmp_path, column, value):
    path = write_lines(tmp_path / "0001.txt",
                       [DETECTION, DETECTION, edit(DETECTION, column, f" {value}", sep=",")])
    with pytest.raises(ValueError, match=rf"^{path}:3: "):
        read_detections(path)


def test_poses_nan_rows_are_frames_without_pose_but_partial_ones_are_errors(tmp_path):
    row = " ".join(["1", "0", "0", "0", "0", "1", "0", "0", "0", "0", "1", "0"])
    path = write_lines(tmp_path / "poses.txt", [row, " ".join(["nan"] * 12), row])
    assert np.isnan(read_poses(path)[1, :3]).all()
    write_lines(path, [row, edit(row, 3, "nan"), row])
    with pytest.raises(ValueError, match=rf"^{path}:2: pose: expected 12 finite numbers"):
        read_poses(path)
    write_lines(path, [row, row, edit(row, 0, "inf")])
    with pytest.raises(ValueError, match=rf"^{path}:3: "):
        read_poses(path)


def test_eval_with_nan_result_box_is_one_error(sim_root, tmp_path, capsys):
    """It used to end in "SVD did not converge"."""
    results = tmp_path / "results"
    bad = write_lines(results / "tracking" / f"{SEQ}.txt",
                      [LABEL + " 0.9", edit(LABEL + " 0.9", 13, "nan")])
    code, err, _ = call(["eval", sim_root, results, "--seq", SEQ], capsys)
    assert code == 2 and one_error(err, "eval").endswith(f"{bad}:2: box: 'nan' is not finite (NaN or Inf)")


# ------------------------------------------------------------------------------ images
def test_16_bit_images_are_scaled_not_clipped_white(tmp_path):
    grey = (np.arange(256, dtype=np.uint16) * 257).reshape(16, 16)
    write_png16(tmp_path / "grey.png", grey)
    image = read_image(tmp_path / "grey.png")
    assert image.shape == (16, 16, 3) and np.array_equal(image[..., 0], np.arange(256).reshape(16, 16))
    rgb = np.stack([grey, grey // 2, 65535 - grey], axis=-1)
    write_png16(tmp_path / "rgb.png", rgb)
    assert np.abs(read_image(tmp_path / "rgb.png").astype(int) - rgb // 257).max() <= 1


def bomb_png(path: Path, width: int, height: int, depth: int = 8, colour_type: int = 0) -> Path:
    """A few kB of zeros whose header claims ``width x height`` pixels."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        crc = zlib.crc32(kind + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", width, height, depth, colour_type, 0, 0, 0)
    rows = zlib.compress(b"\0" * (width * depth // 8 + 1) * 200, 9)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", rows)
                     + chunk(b"IEND", b""))
    return path


@pytest.mark.parametrize("size", [(9000, 9000), (60000, 60000)])
@pytest.mark.parametrize("colour_type", [0, 2])  # grey, RGB (the core's kind below the limit)
def test_decompression_bomb_is_refused_before_decoding(tmp_path, size, colour_type):
    path = bomb_png(tmp_path / "bomb.png", *size, colour_type=colour_type)
    # refused for its size (Pillow's check or ours, both name the pixels), not for failing to
    # decode: an RGB one must not reach the core's decoder
    with pytest.raises(ValueError, match=rf"^{path}: .*pixels"):
        read_image(path)
    with pytest.raises(ValueError, match=rf"^{path}: .*pixels"):
        read_png16(bomb_png(path, *size, depth=16))


def test_colour_pngs_are_decoded_by_the_core_with_pillows_pixels(tmp_path, monkeypatch):
    """8-bit RGB PNGs (KITTI's, the simulator's) go to the C++ decoder; the pixels are
    Pillow's. Other kinds (RGBA here, grey and 16-bit above) stay with Pillow."""
    from twistslam._core import io as core_io

    rgb = np.random.default_rng(0).integers(0, 256, (37, 53, 3), dtype=np.uint8)
    Image.fromarray(rgb).save(tmp_path / "rgb.png")
    Image.fromarray(np.dstack([rgb, rgb[..., :1]])).save(tmp_path / "rgba.png")
    calls = []
    decode = core_io.read_png_rgb8
    monkeypatch.setattr(core_io, "read_png_rgb8", lambda p: calls.append(p) or decode(p))
    image = read_image(tmp_path / "rgb.png")
    assert calls == [str(tmp_path / "rgb.png")]
    assert image.dtype == np.uint8 and image.shape == (37, 53, 3) and np.array_equal(image, rgb)
    assert np.array_equal(read_image(tmp_path / "rgba.png"), rgb) and len(calls) == 1


def test_real_kitti_images_decode_to_pillows_pixels():
    """The core's fast path (libdeflate, cpp/io/png_decoder.hpp) takes KITTI's camera PNGs;
    every image of the real frames comes out as Pillow (libpng + zlib) decodes it."""
    from twistslam._core import io as core_io

    images = sorted(p for folder in ("kitti_tracking_lidar", "kitti_object")
                    for p in require_real_data(folder).rglob("image_*/**/*.png"))
    assert len(images) >= 20
    for path in images:
        with Image.open(path) as image:
            assert image.mode == "RGB", path
            expected = np.asarray(image)
        assert np.array_equal(core_io.read_png_rgb8(str(path)), expected), path


def test_a_truncated_colour_png_is_an_error_naming_the_file(tmp_path):
    rgb = np.random.default_rng(1).integers(0, 256, (40, 60, 3), dtype=np.uint8)
    Image.fromarray(rgb).save(tmp_path / "whole.png")
    cut = tmp_path / "cut.png"
    cut.write_bytes((tmp_path / "whole.png").read_bytes()[:200])  # the header and a little data
    with pytest.raises(ValueError, match=rf"^{cut}: "):
        read_image(cut)
    with pytest.raises(FileNotFoundError, match="missing.png"):
        read_image(tmp_path / "missing.png")


# -------------------------------------------------------- sequences that are silently wrong
def variant(src: Path, seq: str, dst: Path, kind: str, frames: int = 3) -> Path:
    """Calibration and the first stereo pairs of ``src``, as they are or made wrong."""
    shutil.copy(src / "training" / "calib" / f"{seq}.txt", _mkdir(dst / "training" / "calib"))
    for i in range(frames):
        left, right = (src / "training" / c / seq / f"{i:06d}.png" for c in ("image_02", "image_03"))
        pair = {"identical": (left, left), "swapped": (right, left)}.get(kind, (left, right))
        for folder, image in zip(("image_02", "image_03"), pair):
            out = _mkdir(dst / "training" / folder / seq) / image.name
            if kind == "half":
                with Image.open(image) as im:
                    im.resize((im.width // 2, im.height // 2)).save(out)
            else:
                shutil.copy(image, out)
    return dst


def _mkdir(path: Path) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    return path


SILENTLY_WRONG = [("identical", "identical to the left one"), ("swapped", "cameras swapped?"),
                  ("half", "do not fit")]


@pytest.mark.parametrize("kind, message", SILENTLY_WRONG)
def test_silently_wrong_sim_sequence_is_refused(sim_root, tmp_path, kind, message):
    root = variant(sim_root, SEQ, tmp_path, kind)
    with pytest.raises(ValueError, match=rf"frame 0 .*{message.replace('?', '[?]')}"):
        run((root, SEQ), progress=False)


@pytest.mark.parametrize("kind, message", SILENTLY_WRONG)
def test_silently_wrong_real_sequence_is_one_error(tmp_path, capsys, kind, message):
    real = require_real_data("kitti_tracking_lidar")
    root = variant(real, "0001", tmp_path / "seq", kind)
    code, err, _ = call(["run", root, "--seq", "0001", "--out", tmp_path / "out",
                         "--no-progress"], capsys)
    assert code == 2 and message in err[-1] and err[-1].startswith("twistslam run: error: frame 0")
    assert not (tmp_path / "out").exists()


def test_blank_identical_frames_are_no_error(sim_root, tmp_path):
    """Two blank images are equal too (a camera dropout): tracked as "lost", not refused."""
    root = variant(sim_root, SEQ, tmp_path, "ok", frames=4)
    for folder in ("image_02", "image_03"):
        Image.new("RGB", (621, 188), (90, 90, 90)).save(root / "training" / folder / SEQ / "000000.png")
    result = run((root, SEQ), progress=False)
    assert result.status[0] == "lost" and (result.status[1:] != "lost").all()


def test_ground_truth_shorter_than_the_run_is_named(sim_root, tmp_path, capsys):
    root = variant(sim_root, SEQ, tmp_path / "seq", "ok")
    poses = read_poses(sim_root / "training" / "poses" / f"{SEQ}.txt")
    write_poses(root / "training" / "poses" / f"{SEQ}.txt", poses[:6])
    write_poses(tmp_path / "res" / "camera_poses.txt", poses)
    code, err, out, warned = call_warned(["eval", root, tmp_path / "res", "--seq", SEQ], capsys)
    assert code == 0 and "evaluated on frames 0-5, the ground truth's; 4 estimated frames" in out
    assert len(warned) == 1 and "evaluated on frames 0-5 only" in warned[0]


# ------------------------------------------------------------------ user errors, outputs
@pytest.fixture
def no_tracking(monkeypatch):
    """Output checks must fail before any frame is tracked or evaluated."""
    def forbidden(*args, **kwargs):
        raise AssertionError("work started before the outputs were checked")

    monkeypatch.setattr("twistslam.pipeline.run", forbidden)
    monkeypatch.setattr("twistslam.eval.sequence.evaluate_sequence", forbidden)


def bad_outputs(tmp_path: Path, monkeypatch) -> dict[str, Path]:
    (tmp_path / "a_file").write_text("x")
    make_read_only(tmp_path / "read_only", monkeypatch)
    return {"a file": tmp_path / "a_file", "under a file": tmp_path / "a_file" / "out",
            "read-only": tmp_path / "read_only" / "out"}


@pytest.mark.parametrize("case", ["a file", "under a file", "read-only"])
def test_unwritable_out_is_one_error_before_tracking(sim_root, tmp_path, capsys, monkeypatch,
                                                     no_tracking, case):
    out = bad_outputs(tmp_path, monkeypatch)[case]
    code, err, _ = call(["run", sim_root, "--seq", SEQ, "--out", out], capsys)
    assert code == 2 and one_error(err, "run").startswith(f"twistslam run: error: --out {out}: ")


@pytest.mark.parametrize("option", ["--json", "--markdown", "--plots"])
@pytest.mark.parametrize("case", ["a file", "under a file", "read-only"])
def test_unwritable_eval_outputs_are_one_error(sim_root, tmp_path, capsys, monkeypatch,
                                               no_tracking, option, case):
    target = bad_outputs(tmp_path, monkeypatch)[case]
    if option != "--plots" and case == "a file":
        target = tmp_path  # a folder where a file is expected
    code, err, _ = call(["eval", sim_root, tmp_path, "--seq", SEQ, option, target], capsys)
    assert code == 2 and one_error(err, "eval").startswith(f"twistslam eval: error: {option} {target}")


@pytest.mark.parametrize("case", ["a file", "read-only"])
def test_unwritable_sim_output_is_one_error(tmp_path, capsys, monkeypatch, case):
    out = bad_outputs(tmp_path, monkeypatch)[case]
    code, err, _ = call(["sim", out, "--frames", 1, "--no-progress"], capsys)
    assert code == 2 and one_error(err, "sim").startswith(f"twistslam sim: error: OUT {out}: ")


def test_existing_results_are_not_overwritten_silently(sim_root, tmp_path, capsys):
    args = ["run", sim_root, "--seq", SEQ, "--out", tmp_path, "--no-progress",
            "--set", "run.max_frames=2"]
    assert call(args, capsys)[0] == 0
    first = (tmp_path / "camera_poses.txt").read_bytes()
    (tmp_path / "camera_poses.txt").write_text("mine\n")
    code, err, _ = call(args, capsys)
    assert code == 2 and "already holds results" in one_error(err, "run") and "--overwrite" in err[0]
    assert (tmp_path / "camera_poses.txt").read_text() == "mine\n"
    assert call([*args, "--overwrite"], capsys)[0] == 0
    assert (tmp_path / "camera_poses.txt").read_bytes() == first


def test_config_naming_a_folder_is_one_error(sim_root, tmp_path, capsys):
    code, err, _ = call(["run", sim_root, "--seq", SEQ, "--out", tmp_path / "o", "--config",
                         tmp_path], capsys)
    assert code == 2 and f"--config {tmp_path}: is a folder" in one_error(err, "run")


@pytest.mark.parametrize("option, value, message", [
    ("--width", "100000", "argument --width: must be at most 8192 px"),  # was 149 GiB
    ("--frames", "100000000", "argument --frames: must be at most 2000"),  # never finished
])
def test_sim_size_options_are_bounded(tmp_path, capsys, option, value, message):
    with pytest.raises(SystemExit) as info:
        cli.main(["sim", str(tmp_path / "out"), option, value])
    assert info.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_sim_api_frames_are_bounded(tmp_path):
    with pytest.raises(ValueError, match=r"frames \(--frames\) = 2001: at most 2000"):
        generate(tmp_path / "out", frames=2001, progress=False)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("args, message", [
    (["--set", "camera.height=9000"], "camera.height (--height) = 9000"),
    (["--width", "8000", "--height", "4000"], "32000000 pixels: at most 4000000"),
    (["--set", "camera.supersample=50"], "camera.supersample = 50"),
])
def test_sim_image_size_settings_are_bounded(tmp_path, capsys, args, message):
    code, err, _ = call(["sim", tmp_path / "out", "--frames", 1, *args], capsys)
    assert code == 2 and message in one_error(err, "sim")
    assert not any((tmp_path / "out").glob("*"))


# ------------------------------------------------------------------- graceful behaviours
def test_two_runs_of_the_demo_slam_are_byte_identical(sim_root, tmp_path):
    """The demo's own settings (one Ceres thread, the default: with two, the BA sums in
    scheduling order and poses land ~1e-15 m apart)."""
    config = demo_config()
    assert config.local_ba.num_threads == 1
    results = [run((sim_root, SEQ), config, progress=False) for _ in range(2)]
    assert results[0].is_keyframe.sum() >= 3 and (results[0].status != "lost").all()
    paths = [r.save(tmp_path / str(k))["camera_poses"] for k, r in enumerate(results)]
    assert paths[0].read_bytes() == paths[1].read_bytes()
    assert results[0].camera_poses.tobytes() == results[1].camera_poses.tobytes()


def test_real_sequence_without_labels_or_detections_runs_and_evaluates_the_camera(tmp_path, capsys):
    real = require_real_data("kitti_tracking_lidar", "training")
    base = tmp_path / "kitti" / "training"
    for folder in ("image_02", "image_03", "velodyne"):
        _mkdir(base / folder).joinpath("0001").symlink_to(real / folder / "0001")
    for folder in ("calib", "oxts"):
        _mkdir(base / folder).joinpath("0001.txt").symlink_to(real / folder / "0001.txt")
    code, err, _, warned = call_warned(["run", base.parent, "--seq", "0001", "--out",
                                        tmp_path / "res", "--no-progress", "--set",
                                        "run.max_frames=6"], capsys)
    assert code == 0 and err == [] and warned == []
    # the run's objects came from the classical LiDAR detector (no detection files); without
    # labels only the camera is evaluated, and one warning says why the objects are not
    assert (tmp_path / "res" / "tracking" / "0001.txt").is_file()
    code, err, out, warned = call_warned(["eval", base.parent, tmp_path / "res", "--seq", "0001"],
                                         capsys)
    assert code == 0 and err == [] and "Camera" in out
    assert len(warned) == 1 and "label" in warned[0] and "objects are not evaluated" in warned[0]
