"""twistslam.Config: defaults, YAML round trip, --set overrides, type and range errors."""

from __future__ import annotations

from dataclasses import fields

import pytest

from twistslam import Config
from twistslam.config import SECTIONS

# the options contract with the C++ core (issue 4): section -> key -> default

def test_options_match_the_core_contract():
    # The Python config explains every default; the core must agree with it key for key
    # (no key unknown to either side) and value for value.
    from twistslam._core import slam

    core = slam.default_options()
    options = Config().to_options()
    assert set(options) == set(core)
    for section, values in core.items():
        assert set(options[section]) == set(values), section
        for key, value in values.items():
            assert options[section][key] == pytest.approx(value), f"{section}.{key}"
            # exact Python types, so the C++ side reads ints as ints and floats as floats
            assert type(options[section][key]) is type(value), f"{section}.{key}"


def test_feature_defaults_agree_with_the_features_module():
    # the C++ matcher documents why each default was chosen; the config must not drift from it
    from twistslam import features

    core = features.default_options()
    options = Config().to_options()
    for section in ("orb", "stereo"):
        for key, value in options[section].items():
            if (section, key) == ("orb", "num_features"):
                continue  # the SLAM front end asks for more than the extractor's default
            assert core[key] == pytest.approx(value), f"{section}.{key}"
    assert options["orb"]["num_features"] > core["num_features"]


def test_run_section_is_not_sent_to_the_core():
    config = Config()
    assert "run" not in config.to_options()
    assert (config.run.max_frames, config.run.start_frame) == (None, 0)
    assert config.run.use_labels is True and config.run.labels_dir == "panoptic"


def test_every_setting_has_a_reason():
    for name, section in SECTIONS.items():
        for f in fields(section):
            assert len(f.metadata["why"]) > 10, f"{name}.{f.name} has no reason for its default"


def test_yaml_round_trip_with_comments(tmp_path):
    config = Config().override(["tracking.min_inliers=42", "tracking.dynamic_class_ids=[24, 26]",
                                "run.max_frames=7", "stereo.max_depth=60.5"])
    text = config.to_yaml(tmp_path / "c.yaml")
    assert "min_inliers: 42  # below this the frame is lost" in text
    assert "max_depth: 60.5  # [m]" in text
    assert Config.from_yaml(tmp_path / "c.yaml") == config
    assert Config.from_yaml(tmp_path / "c.yaml") != Config()


def test_partial_and_empty_yaml(tmp_path):
    path = tmp_path / "partial.yaml"
    path.write_text("tracking:\n  min_inliers: 50\nlocal_ba:\n  window: 7\n")
    config = Config.from_yaml(path)
    assert config.tracking.min_inliers == 50 and config.local_ba.window == 7
    assert config.orb == Config().orb
    path.write_text("")
    assert Config.from_yaml(path) == Config()


def test_yaml_errors_name_the_file_and_the_valid_keys(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("tracking:\n  min_inlier: 50\n")
    with pytest.raises(ValueError, match=r"bad\.yaml: unknown key 'tracking\.min_inlier'; keys of "
                       r"section 'tracking': min_inliers, min_init_points, search_radius_px"):
        Config.from_yaml(path)
    path.write_text("trackin:\n  min_inliers: 50\n")
    with pytest.raises(ValueError, match="unknown config section 'trackin'; sections: orb, stereo"):
        Config.from_yaml(path)
    path.write_text("tracking: [1, 2\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        Config.from_yaml(path)
    path.write_text("tracking:\n  min_inliers: many\n")
    with pytest.raises(ValueError, match="tracking.min_inliers: expected int, got 'many'"):
        Config.from_yaml(path)
    with pytest.raises(FileNotFoundError):
        Config.from_yaml(tmp_path / "missing.yaml")


@pytest.mark.parametrize("item, key, expected", [
    ("tracking.min_inliers=40", ("tracking", "min_inliers"), 40),
    ("tracking.min_inliers=4e1", ("tracking", "min_inliers"), 40),
    ("tracking.ratio_test=0.8", ("tracking", "ratio_test"), 0.8),
    ("stereo.max_depth=100", ("stereo", "max_depth"), 100.0),
    ("run.use_labels=false", ("run", "use_labels"), False),
    ("run.use_labels=Yes", ("run", "use_labels"), True),
    ("run.max_frames=20", ("run", "max_frames"), 20),
    ("run.max_frames=none", ("run", "max_frames"), None),
    ("run.labels_dir=seg", ("run", "labels_dir"), "seg"),
    ("tracking.dynamic_class_ids=[24, 26]", ("tracking", "dynamic_class_ids"), [24, 26]),
    ("tracking.dynamic_class_ids=24,26", ("tracking", "dynamic_class_ids"), [24, 26]),
    ("tracking.dynamic_class_ids=[]", ("tracking", "dynamic_class_ids"), []),
    (" tracking.min_inliers = 41 ", ("tracking", "min_inliers"), 41),
])
def test_override_converts_with_the_field_type(item, key, expected):
    config = Config()
    assert config.override(item) is config  # in place, chainable
    value = getattr(getattr(config, key[0]), key[1])
    assert value == expected and type(value) is type(expected)


def test_override_list_and_mapping():
    config = Config().override({"tracking.min_inliers": 12, "orb.num_features": "1000"})
    assert (config.tracking.min_inliers, config.orb.num_features) == (12, 1000)
    config.override(["keyframes.max_frames_between=3", "map.max_points=1000"])
    assert (config.keyframes.max_frames_between, config.map.max_points) == (3, 1000)


@pytest.mark.parametrize("item, message", [
    ("tracking.min_inlier=3", "unknown key 'tracking.min_inlier'; keys of section 'tracking': "
                              "min_inliers"),
    ("track.min_inliers=3", "unknown config section 'track'; sections: orb"),
    ("min_inliers=3", "expected section.key=value"),
    ("tracking.min_inliers", "expected section.key=value"),
    ("tracking.min_inliers=3.5", "tracking.min_inliers: expected int, got '3.5'"),
    ("tracking.min_inliers=true", "tracking.min_inliers: expected int"),
    ("tracking.min_inliers=0", r"tracking.min_inliers = 0 is out of range \[1, 100000\]"),
    ("tracking.ratio_test=1.5", r"tracking.ratio_test = 1.5 is out of range \[0, 1\]"),
    ("tracking.chi2_mono=nan", "tracking.chi2_mono = nan is out of range"),
    ("run.use_labels=maybe", "run.use_labels: expected bool, got 'maybe'"),
    ("run.start_frame=none", "run.start_frame: expected int, got 'none'"),
    ("tracking.dynamic_class_ids=[car]", r"tracking.dynamic_class_ids\[0\]: expected int"),
    ("stereo.min_depth=90", "stereo.min_depth .* must be below stereo.max_depth"),
    # values that used to overflow into the core (a TypeError, or UBSan float-to-int casts)
    ("orb.num_features=3e9", r"orb.num_features = 3000000000 is out of range \[0, 100000\]"),
    (f"orb.num_features={2**32}", r"orb.num_features = 4294967296 is out of range"),
    (f"orb.num_features={2**70}", rf"orb.num_features = {2**70} is out of range"),
    ("orb.num_features=2**32", r"orb.num_features: expected int, got '2\*\*32'"),
    ("orb.num_features=1e400", "orb.num_features: expected int"),
    ("stereo.row_radius=1e30", r"stereo.row_radius = 1e\+30 is out of range \[0, 64\]"),
    ("tracking.search_radius_px=inf", r"tracking.search_radius_px = inf is out of range \[0, 2000\]"),
    ("tracking.dynamic_class_ids=[24, -1]", r"tracking.dynamic_class_ids = -1 is out of range"),
    ("local_ba.huber_mono=0", r"local_ba.huber_mono = 0.0 is out of range \[0.01, 1000\]"),
])
def test_bad_overrides_raise_and_change_nothing(item, message):
    config = Config()
    with pytest.raises(ValueError, match=message):
        config.override(["tracking.min_inliers=55", item])
    assert config == Config()  # all or nothing


def test_construction_is_validated():
    from twistslam.config import OrbConfig

    with pytest.raises(ValueError, match="orb.num_features = -1 is out of range"):
        Config(orb=OrbConfig(num_features=-1))
    with pytest.raises(ValueError, match="must not exceed orb.fast_threshold"):
        Config().override("orb.min_fast_threshold=30")


@pytest.mark.parametrize("section, key, value", [
    ("orb", "num_features", 3_000_000_000), ("orb", "num_features", 2**32),
    ("stereo", "row_radius", 1e30), ("tracking", "search_radius_px", float("inf")),
    ("orb", "cell_size", 5), ("stereo", "min_depth", 0.0), ("keyframes", "min_tracked_ratio", -0.1),
])
def test_config_and_core_refuse_a_value_with_the_same_message(section, key, value):
    # one set of range checks: the core's, whether it is reached through a Config or directly
    from twistslam._core import slam

    with pytest.raises(ValueError) as through_config:
        Config().override({f"{section}.{key}": value})
    with pytest.raises(ValueError) as directly:
        slam.check_options({section: {key: value}})
    assert f"{section}.{key} = " in str(directly.value)
    assert str(directly.value) == "options: " + str(through_config.value)


def test_core_refuses_wrong_types_by_name():
    from twistslam._core import slam

    with pytest.raises(TypeError, match="options: tracking.min_inliers: expected an integer, got float"):
        slam.check_options({"tracking": {"min_inliers": 30.0}})
    with pytest.raises(TypeError, match="options: orb.scale_factor: expected a number, got str"):
        slam.check_options({"orb": {"scale_factor": "1.2"}})
    with pytest.raises(TypeError, match="options: orb.num_features: expected an integer, got bool"):
        slam.check_options({"orb": {"num_features": True}})
    with pytest.raises(ValueError, match="unknown key 'orb.num_feature'"):
        slam.check_options({"orb": {"num_feature": 10}})
    slam.check_options(Config().to_options())  # the defaults pass


def test_every_numeric_core_option_has_a_finite_range_that_holds_its_default():
    from twistslam._core import slam

    ranges = slam.option_ranges()
    for section, values in Config().to_options().items():
        for key, default in values.items():
            if isinstance(default, bool) or not isinstance(default, (int, float, list)):
                continue
            lo, hi = ranges[section][key]
            assert lo <= hi < float("inf"), f"{section}.{key}"
            for v in default if isinstance(default, list) else [default]:
                assert lo <= v <= hi, f"{section}.{key} = {v} outside [{lo}, {hi}]"
            # integer options have integer bounds (an int range reads as one)
            if isinstance(default, int):
                assert type(lo) is int and type(hi) is int, f"{section}.{key}"


def test_copies_do_not_share_lists():
    a = Config()
    b = Config.from_dict(a.to_dict())
    b.tracking.dynamic_class_ids.append(26)
    assert a.tracking.dynamic_class_ids == [] and Config().tracking.dynamic_class_ids == []


def test_describe():
    d = Config.describe("stereo.max_depth")
    assert d["default"] == 80.0 and d["unit"] == "m" and "disparity" in d["why"]
    assert (d["lo"], d["hi"]) == (0.01, 10000.0)  # the core's range
    assert (Config.describe("orb.num_features")["lo"], Config.describe("orb.num_features")["hi"]) == (0, 100000)
    with pytest.raises(ValueError, match="unknown key"):
        Config.describe("stereo.nope")
