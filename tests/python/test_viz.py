"""The rerun view: a 3-frame recording holds every entity; no rerun -> a clear ImportError;
bad shapes -> a ValueError naming the field; the ``run`` command's new flags."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from twistslam import cli
from twistslam.viz import ObjectView, RerunLogger, track_color
from twistslam.viz.colors import rotation_to_quaternion_xyzw

HEIGHT, WIDTH = 48, 64
K = np.array([[50.0, 0.0, 32.0], [0.0, 50.0, 24.0], [0.0, 0.0, 1.0]])

#: entity -> components the recording must hold for it
EXPECTED = {
    "/world": {"ViewCoordinates:xyz"},
    "/world/camera": {"Pinhole:image_from_camera", "Pinhole:resolution",
                      "Transform3D:translation", "Transform3D:mat3x3"},
    "/world/camera/image": {"Image:buffer"},
    "/world/camera/image/segmentation": {"SegmentationImage:buffer",
                                         "AnnotationContext:context"},
    "/world/camera/image/instances": {"SegmentationImage:buffer", "AnnotationContext:context"},
    "/world/camera/image/boxes": {"Boxes2D:half_sizes", "Boxes2D:labels"},
    "/world/static_points": {"Points3D:positions", "Points3D:colors"},
    "/world/lidar/scan": {"Points3D:positions", "Points3D:colors"},
    "/world/lidar/road": {"Points3D:positions", "Points3D:colors"},
    "/world/objects/points": {"Points3D:positions", "Points3D:colors"},
    "/world/objects/boxes": {"Boxes3D:centers", "Boxes3D:half_sizes", "Boxes3D:quaternions",
                             "Boxes3D:labels"},
    "/world/objects/trajectories": {"LineStrips3D:strips"},
    "/world/camera_trajectory": {"LineStrips3D:strips"},
    "/scalars/inliers": {"Scalars:scalars"},
    "/scalars/stage_ms/tracking": {"Scalars:scalars"},
}


def yaw(angle: float) -> np.ndarray:
    """Rotation about the camera's y (down) axis."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def pose(rotation: np.ndarray, translation) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rotation, translation
    return T


def synthetic_frame(index: int) -> dict:
    """A frame with one car (track 12) and a pedestrian (track 3), a car mask and a map."""
    rng = np.random.default_rng(index)
    image = rng.integers(0, 255, (HEIGHT, WIDTH, 3), dtype=np.uint8)
    class_ids = np.full((HEIGHT, WIDTH), 7, np.int32)  # road
    class_ids[:10] = 23  # sky
    instance_ids = np.zeros((HEIGHT, WIDTH), np.int32)
    class_ids[20:30, 10:30], instance_ids[20:30, 10:30] = 26, 1
    car = ObjectView(track_id=12, cls="car", T_w_o=pose(yaw(0.1 * index), [2.0, 1.5, 10.0 + index]),
                     size=np.array([4.0, 1.8, 1.5]), velocity_kmh=34.2,
                     points_w=rng.normal([2.0, 1.5, 10.0 + index], 0.5, (20, 3)),
                     box2d=np.array([10.0, 20.0, 30.0, 30.0]))
    person = ObjectView(track_id=3, cls="person", T_w_o=pose(np.eye(3), [-2.0, 1.0, 8.0]),
                        size=np.array([0.6, 0.6, 1.7]), velocity_kmh=4.0)
    return dict(image_left=image, T_w_c=pose(yaw(0.02 * index), [0.0, 0.0, 1.0 * index]),
                class_ids=class_ids, instance_ids=instance_ids, objects=[car, person],
                static_points_w=rng.normal(0.0, 5.0, (100, 3)),
                lidar_points_w=rng.normal(0.0, 20.0, (200, 3)),
                road_lidar_points_w=rng.normal([0.0, 1.65, 10.0], [5.0, 0.02, 8.0], (50, 3)),
                scalars={"inliers": 120 + index, "stage_ms/tracking": 8.5})


class Recording:
    """What an .rrd file holds, read back with ``rerun.chunk.RrdReader``: per entity, the
    component columns and their values on the ``frame`` timeline."""

    def __init__(self, path: Path) -> None:
        from rerun.chunk import RrdReader

        self.rows: dict[str, list[dict]] = {}
        for chunk in RrdReader(path).stream():
            rows = chunk.to_record_batch().to_pylist()
            self.rows.setdefault(chunk.entity_path, []).extend(rows)

    def components(self, entity: str) -> set[str]:
        return {key for row in self.rows.get(entity, []) for key in row if ":" in key}

    def frames(self, entity: str) -> set[int]:
        return {row["frame"] for row in self.rows.get(entity, []) if row.get("frame") is not None}

    def at(self, entity: str, component: str, frame: int) -> list:
        """The component's value logged at ``frame`` (a list: one item per instance)."""
        values = [row[component] for row in self.rows.get(entity, [])
                  if row.get("frame") == frame and row.get(component) is not None]
        assert len(values) == 1, f"{entity} {component} at frame {frame}: {len(values)} values"
        return values[0]


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Recording:
    pytest.importorskip("rerun", reason="rerun-sdk (the viz extra) is not installed")
    path = tmp_path_factory.mktemp("viz") / "rec.rrd"
    with RerunLogger("twistslam-test", save=path) as viz:
        viz.log_camera(K, WIDTH, HEIGHT)
        for index in range(3):
            viz.log_frame(index, **synthetic_frame(index))
    assert path.stat().st_size > 0
    return Recording(path)


@pytest.mark.parametrize("entity", sorted(EXPECTED))
def test_recording_holds_entity(recording, entity):
    assert entity in recording.rows, f"{entity} missing; recorded: {sorted(recording.rows)}"
    assert EXPECTED[entity] <= recording.components(entity), entity


def test_recording_is_on_the_frame_timeline(recording):
    for entity in set(EXPECTED) - {"/world"}:
        assert recording.frames(entity) == {0, 1, 2}, entity


def test_recording_holds_the_frames_content(recording):
    assert recording.at("/world/camera/image/boxes", "Boxes2D:labels", 2) == ["id 12 car 34 km/h"]
    assert len(recording.at("/world/objects/boxes", "Boxes3D:centers", 2)) == 2
    half_sizes = recording.at("/world/objects/boxes", "Boxes3D:half_sizes", 2)[0]
    np.testing.assert_allclose(half_sizes, [2.0, 0.75, 0.9])  # l, h, w along the box's x, y, z
    assert len(recording.at("/world/objects/points", "Points3D:positions", 1)) == 20
    assert len(recording.at("/world/static_points", "Points3D:positions", 1)) == 100
    assert len(recording.at("/world/lidar/scan", "Points3D:positions", 1)) == 200
    road = recording.at("/world/lidar/road", "Points3D:positions", 1)
    np.testing.assert_allclose(road, synthetic_frame(1)["road_lidar_points_w"], atol=1e-5)
    assert len(recording.at("/world/camera_trajectory", "LineStrips3D:strips", 2)[0]) == 3
    strips = recording.at("/world/objects/trajectories", "LineStrips3D:strips", 2)
    assert sorted(len(strip) for strip in strips) == [3, 3]  # two tracks, three frames each
    assert recording.at("/scalars/inliers", "Scalars:scalars", 2) == [122.0]
    translation = recording.at("/world/camera", "Transform3D:translation", 2)
    np.testing.assert_allclose(np.ravel(translation), [0.0, 0.0, 2.0])


def test_spawn_and_save_are_keyword_only():
    with pytest.raises(TypeError):
        RerunLogger("app", True)  # noqa: FBT003 -- the point of the test


def test_missing_rerun_is_a_clear_import_error(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "rerun", None)
    with pytest.raises(ImportError, match=r"twistslam\[viz\].*rerun-sdk"):
        RerunLogger(save=tmp_path / "rec.rrd")


def test_twistslam_imports_without_rerun():
    code = "import sys; sys.modules['rerun'] = None; import twistslam, twistslam.viz, twistslam.cli"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


@pytest.fixture
def logger(tmp_path):
    pytest.importorskip("rerun", reason="rerun-sdk (the viz extra) is not installed")
    with RerunLogger(save=tmp_path / "rec.rrd") as viz:
        yield viz


def _with(field: str, value) -> dict:
    frame = synthetic_frame(0)
    if field.startswith("objects[0]."):
        setattr(frame["objects"][0], field.split(".", 1)[1], value)
    else:
        frame[field] = value
    return frame


@pytest.mark.parametrize("field, value", [
    ("image_left", np.zeros((HEIGHT, WIDTH), np.uint8)),
    ("image_left", np.zeros((HEIGHT, WIDTH, 3), np.float32)),
    ("T_w_c", np.eye(4)[:3]),
    ("T_w_c", np.diag([2.0, 1.0, 1.0, 1.0])),
    ("class_ids", np.zeros((HEIGHT, WIDTH + 1), np.int32)),
    ("class_ids", np.zeros((HEIGHT, WIDTH), np.float32)),
    ("instance_ids", np.zeros((HEIGHT - 1, WIDTH), np.int32)),
    ("static_points_w", np.zeros((10, 2))),
    ("lidar_points_w", np.zeros((10, 4))),
    ("road_lidar_points_w", np.zeros(3)),
    ("objects[0].T_w_o", np.eye(3)),
    ("objects[0].size", np.ones(2)),
    ("objects[0].points_w", np.zeros(3)),
    ("objects[0].box2d", np.zeros((2, 2))),
    ("scalars", {"inliers": "many"}),
])
def test_bad_shapes_name_the_field(logger, field, value):
    with pytest.raises(ValueError, match=field.split(".")[-1].replace("[", r"\[")):
        logger.log_frame(0, **_with(field, value))


def test_bad_intrinsics_name_the_field(logger):
    with pytest.raises(ValueError, match="K must be"):
        logger.log_camera(np.eye(4), WIDTH, HEIGHT)
    with pytest.raises(ValueError, match="width and height"):
        logger.log_camera(K, 0, HEIGHT)


def test_track_colours_are_stable_and_distinct():
    assert track_color(12) == track_color(12)
    assert len({track_color(t) for t in range(10)}) == 10


@pytest.mark.parametrize("angle", [0.0, 0.5, np.pi - 1e-3, np.pi])
def test_quaternion_rotates_like_the_matrix(angle):
    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    skew = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rotation = np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew
    x, y, z, w = rotation_to_quaternion_xyzw(rotation)
    back = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    np.testing.assert_allclose(back, rotation, atol=1e-9)


def test_run_parser_defaults():
    args = cli.build_parser().parse_args(["run", "data", "--out", "out"])
    assert (args.segmentation, args.flow, args.viz, args.viz_save) == ("auto", "auto", False, None)


def test_run_parser_viz_flags():
    args = cli.build_parser().parse_args([
        "run", "data", "--out", "out", "--segmentation", "boxes", "--flow", "dis", "--viz",
        "--viz-save", "rec.rrd"])
    assert (args.segmentation, args.flow, args.viz) == ("boxes", "dis", True)
    assert args.viz_save == Path("rec.rrd")


@pytest.mark.parametrize("option, value", [("--segmentation", "detectron"), ("--flow", "farneback")])
def test_run_parser_rejects_unknown_sources(option, value, capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.build_parser().parse_args(["run", "data", "--out", "out", option, value])
    assert exit_info.value.code == 2 and option in capsys.readouterr().err
