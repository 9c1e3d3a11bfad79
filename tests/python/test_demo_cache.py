"""The demo's sequence cache is keyed by the simulator: its configuration and its code."""

import json
import shutil
from pathlib import Path

import pytest

from twistslam import demo
from twistslam.sim import SCENARIOS


@pytest.fixture
def calls(monkeypatch):
    """Stand-in for the simulator: records each generation, writes a minimal sequence."""
    made = []

    def fake_generate(out, **kwargs):
        made.append(kwargs)
        (Path(out) / "training").mkdir(parents=True)
        return Path(out)

    monkeypatch.setattr("twistslam.sim.generate", fake_generate)
    return made


def test_the_marker_records_the_simulator_configuration_and_code(tmp_path, calls):
    root = demo.cached_sequence(tmp_path, frames=5, progress=False)
    marker = json.loads((root / demo.MARKER).read_text())
    assert marker == demo.sequence_key(frames=5)
    assert marker["sim_code"] == demo.sim_code_version()
    assert marker["sim_config"] == demo.sim_config_digest("urban", 5, 0, "0000")
    assert demo.cached_sequence(tmp_path, frames=5, progress=False) == root
    assert len(calls) == 1  # reused


def test_a_changed_simulator_setting_regenerates(tmp_path, calls, monkeypatch, capsys):
    root = demo.cached_sequence(tmp_path, frames=5, progress=False)
    before = demo.sim_config_digest("urban", 5, 0, "0000")
    description, overrides = SCENARIOS["urban"]
    changed = {**overrides, "lidar": {"range_noise": 0.05}}
    monkeypatch.setitem(SCENARIOS, "urban", (description, changed))
    assert demo.sim_config_digest("urban", 5, 0, "0000") != before
    assert demo.cached_sequence(tmp_path, frames=5, progress=False) == root
    assert len(calls) == 2
    assert "another simulator configuration or code" in capsys.readouterr().out
    assert json.loads((root / demo.MARKER).read_text())["sim_config"] != before
    # every argument is part of the configuration too
    variants = [("urban", 5, 0, "0000"), ("urban", 6, 0, "0000"), ("urban", 5, 1, "0000"),
                ("static", 5, 0, "0000")]
    assert len({demo.sim_config_digest(*v) for v in variants}) == 4


def test_a_changed_simulator_code_regenerates(tmp_path, calls, monkeypatch):
    root = demo.cached_sequence(tmp_path, frames=5, progress=False)
    monkeypatch.setattr(demo, "sim_code_version", lambda folder=None: "edited")
    demo.cached_sequence(tmp_path, frames=5, progress=False)
    assert len(calls) == 2
    assert json.loads((root / demo.MARKER).read_text())["sim_code"] == "edited"


def test_the_code_version_follows_every_simulator_source_file(tmp_path):
    sim = Path(demo.__file__).parent / "sim"
    copy = tmp_path / "sim"
    shutil.copytree(sim, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert demo.sim_code_version(copy) == demo.sim_code_version()
    lidar = copy / "lidar.py"
    lidar.write_text(lidar.read_text() + "\n# edited\n")
    assert demo.sim_code_version(copy) != demo.sim_code_version()
    lidar.unlink()
    assert demo.sim_code_version(copy) != demo.sim_code_version()


def test_an_old_marker_without_the_simulator_key_regenerates(tmp_path, calls):
    root = tmp_path / "urban-seed0-n5"
    (root / "training").mkdir(parents=True)
    old = {"scenario": "urban", "frames": 5, "seed": 0, "seq": "0000"}  # before the key had them
    (root / demo.MARKER).write_text(json.dumps(old) + "\n")
    demo.cached_sequence(tmp_path, frames=5, progress=False)
    assert len(calls) == 1


def test_a_cache_entry_that_is_a_link_without_a_marker_is_replaced_and_its_target_kept(tmp_path, calls):
    elsewhere = tmp_path / "elsewhere"
    (elsewhere / "training").mkdir(parents=True)
    cache = tmp_path / "cache"
    cache.mkdir()
    (cache / "urban-seed0-n5").symlink_to(elsewhere, target_is_directory=True)
    root = demo.cached_sequence(cache, frames=5, progress=False)
    assert len(calls) == 1
    assert not root.is_symlink() and (root / demo.MARKER).is_file()
    assert (elsewhere / "training").is_dir() and not (elsewhere / demo.MARKER).exists()
