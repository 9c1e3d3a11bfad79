"""The simulator's interface: argument checks, overwrite rules, settings, CLI, scenarios."""

import argparse
import json

import numpy as np
import pytest

from twistslam.datasets import KittiTracking
from twistslam.sim.cli import add_sim_parser, main
from twistslam.sim.config import SimConfig
from twistslam.sim.generate import generate
from twistslam.datasets.png16 import read_png16
from twistslam.sim.scenario import SCENARIOS, scenario_config

TINY = dict(width=138, height=42, progress=False)


def test_scenarios_are_listed_and_unknown_names_rejected(tmp_path):
    assert set(SCENARIOS) == {"urban", "highway", "intersection", "static", "crowded"}
    with pytest.raises(ValueError, match="valid scenarios: urban, highway, intersection, static, crowded"):
        generate(tmp_path / "x", "downtown", frames=1, **TINY)
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("frames", [0, -3])
def test_non_positive_frames_is_an_error(tmp_path, frames):
    with pytest.raises(ValueError, match="frames must be positive"):
        generate(tmp_path / "x", frames=frames, **TINY)


def test_non_empty_output_is_refused_without_overwrite(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="overwrite"):
        generate(out, frames=1, **TINY)
    generate(out, frames=1, seq="0001", overwrite=True, **TINY)
    generate(out, frames=2, seq="0002", overwrite=True, **TINY)
    generate(out, frames=1, seq="0002", overwrite=True, **TINY)  # replaces 0002 only
    assert (out / "keep.txt").read_text() == "mine"
    assert len(KittiTracking(out, "0001")) == 1
    assert len(list((out / "training" / "image_02" / "0002").iterdir())) == 1


def test_overrides_and_config_record(tmp_path):
    cfg = SimConfig().with_overrides({"lidar.range_noise": 0.05, "camera__noise_std": "0",
                                      "traffic": {"ego_speed": [6, 7]}})
    assert cfg.lidar.range_noise == 0.05 and cfg.camera.noise_std == 0.0 and cfg.traffic.ego_speed == (6.0, 7.0)
    assert SimConfig().lidar.range_noise == 0.02  # defaults untouched
    with pytest.raises(ValueError, match="unknown simulator setting"):
        SimConfig().with_overrides({"lidar.range_nosie": 1.0})
    # strings from --set are converted with the field's type, as twistslam.Config does
    cfg = SimConfig().with_overrides({"output.flow": "off", "frames": "12", "oracle.score_true": "8, 2"})
    assert (cfg.output.flow, cfg.frames, cfg.oracle.score_true) == (False, 12, (8.0, 2.0))
    with pytest.raises(ValueError, match=r"simulator setting 'frames': expected int, got 'many'"):
        SimConfig().with_overrides({"frames": "many"})
    with pytest.raises(ValueError, match=r"'traffic.ego_speed': expected 2 values"):
        SimConfig().with_overrides({"traffic.ego_speed": [1, 2, 3]})
    out = generate(tmp_path / "o", frames=1, lidar__enabled=False, output__flow=False, **TINY)
    record = json.loads((out / "training" / "sim" / "0000.json").read_text())
    assert record["lidar"]["enabled"] is False and record["scenario"] == "urban"
    assert not (out / "training" / "velodyne").exists()


def test_cli_parser_and_errors(tmp_path, capsys):
    parser = argparse.ArgumentParser()
    add_sim_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["sim", str(tmp_path / "c"), "--frames", "2", "--seed", "4", "--set", "lidar.dropout=0.1"])
    assert args.frames == 2 and args.seed == 4 and args.scenario == "urban"
    assert args.settings == [("lidar.dropout", "0.1")]
    with pytest.raises(SystemExit):
        parser.parse_args(["sim", "o", "--frames", "0"])
    with pytest.raises(SystemExit):
        parser.parse_args(["sim", "o", "--scenario", "moon"])
    assert "valid scenarios" in capsys.readouterr().err
    out = tmp_path / "c"
    assert main([str(out), "--frames", "1", "--width", "138", "--height", "42", "--no-progress"]) == 0
    assert main([str(out), "--frames", "1", "--no-progress"]) == 2
    assert "not empty" in capsys.readouterr().err


def _moving_tracks(out):
    shapes = json.loads((out / "training" / "meshes" / "0000" / "shapes.json").read_text())
    return {int(k) for k, v in shapes.items() if v["moving"]}


def test_static_scenario_has_no_moving_objects(tmp_path):
    out = generate(tmp_path / "s", "static", frames=2, **TINY)
    assert _moving_tracks(out) == set()
    lines = (out / "training" / "object_poses" / "0000.txt").read_text().splitlines()
    poses = {}
    for line in lines:
        f = line.split()
        poses.setdefault(f[1], []).append(np.array(f[6:], float))
    assert all(np.allclose(p[0], p[-1]) for p in poses.values())


def test_crowded_scenario_moving_cars_cover_40_percent(tmp_path):
    out = generate(tmp_path / "c", "crowded", frames=1, width=414, height=125, progress=False,
                   lidar__enabled=False, output__flow=False)
    moving = _moving_tracks(out)
    pan = read_png16(out / "training" / "panoptic" / "0000" / "000000.png").astype(np.int64)
    track = np.where(pan >= 26000, pan - 26001, -1)
    assert np.isin(track, list(moving)).mean() > 0.4


@pytest.mark.filterwarnings("ignore::twistslam.datasets.MissingDataWarning")  # no LiDAR rendered
def test_intersection_scenario_turns_the_ego_car(tmp_path):
    cfg = scenario_config("intersection")
    assert cfg.traffic.ego_turn in ("left", "right")
    out = generate(tmp_path / "i", "intersection", frames=80, width=46, height=14, progress=False,
                   lidar__enabled=False, output__flow=False, output__disparity=False)
    poses = KittiTracking(out, "0000").gt_poses
    heading = np.degrees(np.arctan2(poses[-1, 0, 2], poses[-1, 2, 2]))  # camera z axis in the world x-z plane
    assert abs(heading) > 60.0
    speed = np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1) / 0.1
    assert speed.min() > 4.5 and speed.max() < 15.5


@pytest.mark.parametrize("scenario", ["highway"])
def test_other_scenarios_render(tmp_path, scenario):
    out = generate(tmp_path / scenario, scenario, frames=1, **TINY)
    seq = KittiTracking(out, "0000")
    assert seq[0].image_left.shape == (42, 138, 3)
    assert len(seq.gt_objects) > 0
