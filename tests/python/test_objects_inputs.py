"""Bad input to the 3D object tracker: detection files (errors name file and line, documented
skips warn once), the C++ tracker's checks and the CLI's one-line errors.

Every case edits a copy of the real PointRCNN detections of KITTI 0001 (4418 lines, frames
0-446) and tracks the real sequence.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from twistslam import _core
from twistslam.cli import main as cli_main
from twistslam.config import Config
from twistslam.datasets import MissingDataWarning, open_sequence
from twistslam.objects import DetectionWarning, load_detections, track_detections

pytestmark = pytest.mark.filterwarnings("ignore::twistslam.datasets.MissingDataWarning")

DETECTIONS = ("detections", "pointrcnn_car_val")
BAD_LINE = 10  # 1-based line of the edited detection
COLUMNS = {"frame": 0, "score": 6, "h": 7, "w": 8, "l": 9, "x": 10, "y": 11, "z": 12, "ry": 13}


@pytest.fixture(scope="module")
def seq(kitti_tracking):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingDataWarning)
        return open_sequence(kitti_tracking, "0001")


@pytest.fixture(scope="module")
def lines(kitti_tracking) -> list[str]:
    return (kitti_tracking.joinpath(*DETECTIONS) / "0001.txt").read_text().splitlines()


@pytest.fixture(scope="module")
def reference(seq, kitti_tracking):
    """The run on the untouched detections."""
    return track_detections(seq, kitti_tracking.joinpath(*DETECTIONS))


def _write(folder: Path, lines: list[str]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "0001.txt").write_text("".join(line + "\n" for line in lines), encoding="utf-8")
    return folder


def _edit(lines: list[str], column: str, value: str, line_no: int = BAD_LINE) -> list[str]:
    out = list(lines)
    tokens = out[line_no - 1].split(",")
    tokens[COLUMNS[column]] = value
    out[line_no - 1] = ",".join(tokens)
    return out


def _detection_warnings(record) -> list[str]:
    return [str(w.message) for w in record if issubclass(w.category, DetectionWarning)]


def _same_tracks(a, b) -> None:
    assert len(a.objects) == len(b.objects)
    assert np.array_equal(a.tracking.frame, b.tracking.frame)
    assert np.array_equal(a.tracking.track_id, b.tracking.track_id)
    assert np.allclose(a.tracking.box_3d, b.tracking.box_3d, atol=1e-9)


# ------------------------------------------------------------------------ detection files


@pytest.mark.parametrize("column, value",
                         [("x", "nan"), ("z", "inf"), ("l", "-inf"), ("score", "NaN")])
def test_non_finite_value_names_file_and_line(seq, lines, tmp_path, column, value):
    folder = _write(tmp_path / "det", _edit(lines, column, value))
    with pytest.raises(ValueError) as info:
        track_detections(seq, folder)
    assert str(info.value).startswith(f"{folder / '0001.txt'}:{BAD_LINE}: ")
    assert "not finite" in str(info.value)


def test_non_finite_line_number_counts_blank_lines(seq, lines, tmp_path):
    edited = _edit(lines, "y", "nan")
    edited.insert(3, "")  # the bad detection is now on line BAD_LINE + 1
    folder = _write(tmp_path / "det", edited)
    with pytest.raises(ValueError, match=rf"0001\.txt:{BAD_LINE + 1}: "):
        track_detections(seq, folder)


@pytest.mark.parametrize("column, value", [("w", "-1.6"), ("h", "0"), ("l", "0.0000")])
def test_non_positive_size_skipped_with_one_warning(seq, lines, reference, tmp_path, column, value):
    folder = _write(tmp_path / "det", _edit(lines, column, value))
    with pytest.warns(DetectionWarning) as record:
        result = track_detections(seq, folder)
    messages = _detection_warnings(record)
    assert len(messages) == 1, messages
    assert str(folder / "0001.txt") in messages[0]
    assert re.search(rf"skipped 1 detection\(s\).*lines {BAD_LINE}\b", messages[0]), messages[0]
    # the row is gone, the rest is tracked
    with pytest.warns(DetectionWarning):
        table = load_detections(folder, "0001", num_frames=len(seq))
    assert len(table) == len(lines) - 1
    assert len(result.objects) >= 0.9 * len(reference.objects)
    assert len(result.tracking) >= 0.95 * len(reference.tracking)


def test_non_positive_sizes_counted_in_one_warning(seq, lines, tmp_path):
    edited = _edit(_edit(lines, "w", "-1", 10), "h", "0", 20)
    folder = _write(tmp_path / "det", edited)
    with pytest.warns(DetectionWarning) as record:
        table = load_detections(folder, "0001", num_frames=len(seq))
    messages = _detection_warnings(record)
    assert len(messages) == 1, messages
    assert "skipped 2 detection(s)" in messages[0] and "lines 10, 20" in messages[0]
    assert len(table) == len(lines) - 2


@pytest.mark.parametrize("frame", ["447", "5000", "-1"])
def test_frame_outside_the_sequence_names_file_and_line(seq, lines, tmp_path, frame):
    folder = _write(tmp_path / "det", _edit(lines, "frame", frame))
    with pytest.raises(ValueError) as info:
        track_detections(seq, folder)
    message = str(info.value)
    assert message.startswith(f"{folder / '0001.txt'}:{BAD_LINE}: ")
    assert f"frame {frame}" in message and "0-446" in message


def test_unsorted_frames_sorted_with_one_warning(seq, lines, reference, tmp_path):
    frames = np.array([int(line.split(",")[0]) for line in lines])
    block = (frames >= 100) & (frames <= 110)
    shuffled = ([line for line, b in zip(lines, block) if not b]
                + [line for line, b in zip(lines, block) if b])
    folder = _write(tmp_path / "det", shuffled)
    with pytest.warns(DetectionWarning, match="not in order") as record:
        result = track_detections(seq, folder)
    assert len(_detection_warnings(record)) == 1
    _same_tracks(result, reference)


def test_sorted_input_does_not_warn(seq, kitti_tracking):
    with warnings.catch_warnings():
        warnings.simplefilter("error", DetectionWarning)
        load_detections(kitti_tracking.joinpath(*DETECTIONS), "0001", num_frames=len(seq))


def test_empty_file_warns_and_gives_no_tracks(seq, tmp_path):
    folder = _write(tmp_path / "det", [])
    with pytest.warns(DetectionWarning, match="no detections") as record:
        result = track_detections(seq, folder)
    messages = _detection_warnings(record)
    assert len(messages) == 1 and str(folder / "0001.txt") in messages[0]
    assert len(result.objects) == 0 and len(result.tracking) == 0
    assert result.num_frames == len(seq)
    paths = result.save(tmp_path / "out")
    assert paths["tracking"].read_text() == ""


def test_empty_object_result_folder_warns(seq, tmp_path):
    (tmp_path / "det" / "0001").mkdir(parents=True)
    with pytest.warns(DetectionWarning, match="no detections"):
        result = track_detections(seq, tmp_path / "det")
    assert len(result.objects) == 0


@pytest.mark.parametrize("where", ["folder", "file"])
def test_missing_detections_name_the_path(seq, tmp_path, where):
    missing = tmp_path / "nowhere" if where == "folder" else tmp_path / "0002.txt"
    if where == "file":
        _write(tmp_path, [])  # a folder with 0001.txt, but the file given does not exist
    with pytest.raises(FileNotFoundError) as info:
        track_detections(seq, missing)
    assert str(missing) in str(info.value)


def _object_result_folder(lines: list[str], folder: Path, num_frames: int) -> Path:
    """The comma file rewritten as KITTI object results ``0001/NNNNNN.txt`` (15 + score
    columns, same tokens), one file per frame, frames without detections as empty files."""
    names = {"1": "Pedestrian", "2": "Car", "3": "Cyclist"}
    per_frame: dict[int, list[str]] = {}
    for line in lines:
        tokens = [t.strip() for t in line.split(",")]
        f, cls, x1, y1, x2, y2, score, h, w, l, x, y, z, ry, alpha = tokens
        per_frame.setdefault(int(f), []).append(
            f"{names[cls]} -1 -1 {alpha} {x1} {y1} {x2} {y2} {h} {w} {l} {x} {y} {z} {ry} {score}")
    seq_dir = folder / "0001"
    seq_dir.mkdir(parents=True)
    for f in range(num_frames):
        (seq_dir / f"{f:06d}.txt").write_text("".join(r + "\n" for r in per_frame.get(f, [])))
    return folder


def test_object_result_folder_works_like_the_comma_file(seq, lines, reference, tmp_path):
    folder = _object_result_folder(lines, tmp_path / "det", len(seq))
    with warnings.catch_warnings():
        warnings.simplefilter("error", DetectionWarning)
        result = track_detections(seq, folder)
    _same_tracks(result, reference)
    assert np.allclose(result.tracking.score, reference.tracking.score)


def test_object_result_folder_error_names_its_file_and_line(seq, lines, tmp_path):
    frames = [int(line.split(",")[0]) for line in lines]
    second = frames.index(3) + 2  # 1-based line of the second detection of frame 3
    assert frames[second - 1] == 3
    folder = _object_result_folder(_edit(lines, "z", "nan", second), tmp_path / "det", len(seq))
    with pytest.raises(ValueError, match=re.escape(f"{folder / '0001' / '000003.txt'}:2: ")):
        track_detections(seq, folder)


# ---------------------------------------------------------------------- C++ tracker checks


@pytest.fixture
def tracker():
    t = _core.objects.Tracker(Config().objects.tracker_options())
    t.step(0, np.eye(4), np.array([[0.0, 1.0, 10.0, 4.0, 1.8, 1.5, 0.0]]), np.array([9.0]),
           np.array([0]), np.array([True]))
    return t


# one detection of frame 1: boxes, scores, class ids, planar
ONE = (np.array([[0.0, 1.0, 10.5, 4.0, 1.8, 1.5, 0.0]]), np.array([9.0]), np.array([0]),
       np.array([True]))


@pytest.mark.parametrize("frame", [0, -3])
def test_tracker_frame_not_increasing(tracker, frame):
    with pytest.raises(ValueError, match=f"frame {frame} is not after the previous frame 0"):
        tracker.step(frame, np.eye(4), *ONE)
    assert tracker.last_frame == 0
    tracker.step(1, np.eye(4), *ONE)  # the tracker is still usable
    assert tracker.last_frame == 1


@pytest.mark.parametrize("boxes", [np.zeros((1, 6)), np.zeros(7), np.zeros((1, 7, 1))])
def test_tracker_boxes_of_wrong_shape(tracker, boxes):
    with pytest.raises(ValueError, match="boxes"):
        tracker.step(1, np.eye(4), boxes, *ONE[1:])
    assert tracker.last_frame == 0


def test_tracker_scores_of_wrong_length(tracker):
    with pytest.raises(ValueError, match=r"scores.*\(1,\)"):
        tracker.step(1, np.eye(4), ONE[0], np.array([9.0, 8.0]), *ONE[2:])
    with pytest.raises(ValueError, match="class_ids"):
        tracker.step(1, np.eye(4), ONE[0], ONE[1], np.array([0, 0]), ONE[3])
    assert tracker.last_frame == 0


@pytest.mark.parametrize("bad", ["nan", "not rigid"])
def test_tracker_bad_camera_pose(tracker, bad):
    T = np.eye(4)
    if bad == "nan":
        T[1, 3] = np.nan
    else:
        T[:3, :3] *= 2.0
    with pytest.raises(ValueError, match="T_w_c"):
        tracker.step(1, T, *ONE)
    assert tracker.last_frame == 0 and tracker.num_live == 1


# ------------------------------------------------------------------------------------- CLI


def _stderr_lines(capsys) -> list[str]:
    """stderr of the CLI call: one ``twistslam run: error: ...`` line and nothing else (the
    missing images / scans of --no-images are not warned about)."""
    return capsys.readouterr().err.strip().splitlines()


def test_cli_no_images_needs_detections(kitti_tracking, tmp_path, capsys):
    code = cli_main(["run", str(kitti_tracking), "--seq", "0001", "--no-images",
                     "--out", str(tmp_path / "res")])
    assert code == 2
    errors = _stderr_lines(capsys)
    assert len(errors) == 1 and "--detections" in errors[0], errors
    assert errors[0].startswith("twistslam run: error: ")
    assert not (tmp_path / "res").exists()


def test_cli_missing_detections_dir(kitti_tracking, tmp_path, capsys):
    missing = tmp_path / "no_such_detections"
    code = cli_main(["run", str(kitti_tracking), "--seq", "0001", "--no-images",
                     "--detections", str(missing), "--out", str(tmp_path / "res")])
    assert code == 2
    errors = _stderr_lines(capsys)
    assert len(errors) == 1 and str(missing) in errors[0], errors
    assert errors[0].startswith("twistslam run: error: ")


def test_cli_bad_detection_line(kitti_tracking, lines, tmp_path, capsys):
    folder = _write(tmp_path / "det", _edit(lines, "x", "nan"))
    code = cli_main(["run", str(kitti_tracking), "--seq", "0001", "--no-images",
                     "--detections", str(folder), "--out", str(tmp_path / "res")])
    assert code == 2
    errors = _stderr_lines(capsys)
    assert len(errors) == 1 and f"0001.txt:{BAD_LINE}:" in errors[0], errors
