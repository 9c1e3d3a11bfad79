"""Typed configuration of the SLAM system: every threshold and weight, named, with its default.

A :class:`Config` is one dataclass per section (``orb``, ``stereo``, ``tracking``,
``keyframes``, ``local_ba``, ``map``, ``run``, ``objects``, ``lidar``,
``visual_objects``, ``lidar_objects``). Each field carries its unit and the reason for
its default (``dataclasses.fields(...)[i].metadata``), and both are written as comments into
the YAML that :meth:`Config.to_yaml` saves beside every result. The C++ core receives all
sections but ``run`` and ``objects`` (read by the object tracker) as the nested dictionary
:meth:`Config.to_options`. The ranges of those sections are the core's
(``twistslam._core.slam.option_ranges()``): :meth:`Config.validate` asks the core to check
them, so a value is refused with the same message whether it comes through a ``Config`` or
straight to the core. Their defaults are written here, beside the reason for each, and
``tests/python/test_config.py`` checks them against the core's key for key.

>>> cfg = Config()
>>> cfg.override(["tracking.min_inliers=40", "run.max_frames=20"]).tracking.min_inliers
40
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from typing import Any

from twistslam._core import slam as _core_slam

from ._settings import coerce, param, type_hints
from .config_lidar import PYTHON_ONLY as _LIDAR_PYTHON_ONLY
from .config_lidar import LidarConfig
from .config_objects import ObjectsConfig
from .config_lidar_objects import LidarObjectsConfig
from .config_detection import DetectionConfig
from .config_visual_objects import VisualObjectsConfig




@dataclass
class OrbConfig:
    """ORB feature extraction (per image, on a scale pyramid)."""

    num_features: int = param(3000, "ORB-SLAM2 uses 2000 on KITTI; 3000 cuts the rotation RPE "
                              "by ~20 % on the simulator (urban 0.0139 -> 0.0119, static "
                              "0.0148 -> 0.0123 deg/frame) for ~+2 ms of features and more BA "
                              "points (paid by local_ba's shorter schedule)")
    scale_factor: float = param(1.2, "ORB-SLAM2's pyramid ratio: fine scale steps")
    num_levels: int = param(4, "1.2^3 = 1.7x scale range: enough between frames 2 apart, and "
                            "coarse levels localise to +-2 px (ORB-SLAM2's 8 levels: rotation "
                            "RPE 0.0176 -> 0.0147 deg/frame with 4 on the simulator)")
    fast_threshold: int = param(20, "FAST contrast, ORB-SLAM2's iniThFAST", "grey levels")
    min_fast_threshold: int = param(
        7, "retry threshold in low-texture cells, ORB-SLAM2's minThFAST", "grey levels")
    cell_size: int = param(35, "grid cell that spreads features over the image, as ORB-SLAM2",
                           "px")


@dataclass
class StereoConfig:
    """Left-right matching along the rectified rows (docs/features.md)."""

    max_hamming: int = param(75, "half-way between ORB's strict 50 and loose 100: the views of "
                             "a 0.5 m baseline differ little, the SAD check removes the rest",
                             "bits")
    row_radius: float = param(2.0, "row band searched in the right image: FAST's 1-px "
                              "localisation at coarse levels plus KITTI's vertical offset",
                              "px")
    octave_tolerance: int = param(1, "both views see a surface at almost the same scale",
                                  "levels")
    patch_radius: int = param(7, "half width of the 15x5 SAD window: sub-pixel accurate on "
                              "surfaces slanted in depth such as the road", "px")
    patch_half_height: int = param(2, "half height of the 15x5 SAD window: a tall window smears "
                                   "the disparity change of slanted surfaces", "px")
    refine_range: int = param(5, "SAD search of +-5 px around the descriptor match, room to "
                              "reject minima on the border", "px")
    min_depth: float = param(0.5, "nearer is the ego car's own bonnet", "m")
    max_depth: float = param(80.0, "disparity ~5 px at 80 m on KITTI: depth too uncertain beyond",
                             "m")
    outlier_factor: float = param(2.1, "drop matches whose normalised SAD exceeds 2.1x the "
                                  "frame's median (~1.5 robust sigma)")
    right_features_factor: float = param(
        2.0, "the right image gets 2x keypoints as match candidates: ~63 % -> ~77 % matched")


@dataclass
class TrackingConfig:
    """Camera tracking from static points (paper eq. 3): motion model, then local map."""

    min_inliers: int = param(30, "below this the frame is lost (ORB-SLAM2's local-map test)")
    min_init_points: int = param(
        100, "stereo points needed to start (or restart) a map: fewer cannot carry tracking",
        "points")
    search_radius_px: float = param(
        15.0, "projection search window of the constant-velocity model", "px")
    local_map_search_radius_px: float = param(
        4.0, "the pose is already refined: small window against the local map", "px")
    descriptor_prediction: bool = param(
        True, "the frame after a map start (no velocity yet) is predicted from descriptor "
        "matches to the last frame's points and PnP RANSAC, not as 'no motion': a whole frame "
        "of driving off, where even the 4x window matched mostly far central points that "
        "barely see forward motion. Simulated urban s13 (1.2 m/frame): its first step came "
        "out 0.43 m short; with it camera ATE 0.047 -> 0.014 m, RPE 0.0109 -> 0.0068 m/frame; "
        "the other 18 sequences' first steps within 1 cm as before (docs/slam.md)")
    max_hamming: int = param(40, "stricter than ORB-SLAM2's 50: repetitive facades gave wrong "
                             "matches that survived the chi-square test", "bits")
    ratio_test: float = param(0.7, "best / second-best distance; 0.9 let repetitive texture "
                              "through (simulator: -40 % rotation error at 0.7)")
    pose_rounds: int = param(4, "pose-only optimisation rounds re-classifying outliers, as ORB-SLAM2")
    chi2_stereo: float = param(7.815, "95 % quantile of chi-square, 3 DoF (u_l, v, u_r)")
    chi2_mono: float = param(5.991, "95 % quantile of chi-square, 2 DoF (u, v)")
    close_depth_baselines: float = param(
        40.0, "keypoints nearer than 40 baselines are 'close' for the keyframe rule "
        "(ORB-SLAM's); every stereo match still becomes a map point", "baselines")
    dynamic_class_ids: list[int] = param(
        [], "panoptic classes whose pixels give no points to camera tracking (eq. 3); "
        "none until a segmenter is configured")


@dataclass
class KeyframeConfig:
    """When a frame becomes a keyframe (temporal and spatial, as TwistSLAM)."""

    max_frames_between: int = param(
        2, "temporal keyframe at least every 2 frames: the local BA is what removes the "
        "per-frame tracking noise (simulator: RPE halves from 5 to 2, at ~25 ms per frame)",
        "frames")
    temporal_min_translation_m: float = param(
        0.05, "... once the camera has moved this far from the reference keyframe (or turned "
        "temporal_min_rotation_deg): a stopped camera's keyframes repeat one view and each adds "
        "an observation to every point; stopped 300 frames (simulator), the loop slowed from "
        "170 to 500 ms per frame. 0.05 m is 10x the per-frame tracking noise and skips none of "
        "urban's keyframes (>= 0.9 m per 2 frames)", "m", lo=0.0, hi=1000.0)
    temporal_min_rotation_deg: float = param(
        0.5, "... or turned this much: a camera turning in place still gets its keyframes",
        "deg", lo=0.0, hi=180.0)
    min_tracked_ratio: float = param(
        0.75, "spatial keyframe when tracked points drop below this fraction of the "
        "reference keyframe's (ORB-SLAM2 stereo)")
    min_close_tracked: int = param(
        100, "insert when fewer close points than this are tracked (ORB-SLAM2 stereo)")
    min_new_close: int = param(
        70, "... and at least this many new close points could be created (ORB-SLAM2)")


@dataclass
class LocalBAConfig:
    """Local bundle adjustment after each keyframe."""

    window: int = param(10, "keyframes optimised: bounded cost per keyframe", "keyframes")
    max_fixed: int = param(20, "covisible keyframes held fixed to anchor the gauge", "keyframes")
    iterations_first: int = param(3, "before outlier removal; ORB-SLAM2's 5 + 10 run in a "
                                  "thread of their own, ours share the loop: 3 + 4 gave the "
                                  "same RPE/ATE on the simulator at ~30 % less BA time")
    iterations_second: int = param(4, "after outlier removal (the BA of the next keyframe, 2 "
                                   "frames later, continues from here)")
    huber_stereo: float = param(2.796, "sqrt(7.815): Huber kink at the stereo chi-square gate",
                                "px")
    huber_mono: float = param(2.448, "sqrt(5.991): Huber kink at the mono chi-square gate", "px")
    num_threads: int = param(1, "Ceres threads. 1: runs are bit-for-bit reproducible (Ceres "
                             "sums the threads' parts in scheduling order); 2 makes the simulated "
                             "urban loop ~30 % faster (46 -> 32 ms/frame median) with results "
                             "differing by ~1e-14 m between runs")
    asynchronous: bool = param(
        True, "the BA's solve runs in a thread of its own beside the next frame's features and "
        "stereo, and is applied before that frame is tracked: the same results as the "
        "synchronous BA (tests/python/test_visual_objects.py), the loop faster on 2 cores "
        "(benchmarks/bench_camera.py has the figures)")
    apply_delay_frames: int = param(
        0, "with asynchronous: frames tracked against the map before the BA is applied to it "
        "(a keyframe insertion always applies it first; with dynamic_objects it is 0). 0: the "
        "next frame is tracked on the refined map, the synchronous results. 1 overlaps the "
        "solve with that frame's tracking too, a trade measured on the simulator's urban and "
        "crowded seeds 0-4: classical-detector loop 9.2-9.5 -> 10.0-11.0 Hz (urban s2), but "
        "camera RPE 0.0054 -> 0.0061 m and 0.0124 -> 0.0137 deg per frame, camera-alone "
        "object ATE 0.072 -> 0.085 m and one car fewer tracked", "frames", lo=0, hi=1)
    dynamic_objects: bool = param(
        False, "e_dyna (paper eq. 9): the tracked objects' keypoints and keyframe poses join "
        "the BA, tied by their link and e_const (dynamic_const), with their LiDAR terms "
        "(lidar_objects.keyframe_ba_terms), so that they inform the cameras. Off by default, "
        "measured: crowded seeds 0-2 camera RPE 0.0047 / 0.0050 / 0.0056 m per frame with "
        "it against 0.0047 / 0.0050 / 0.0055 without (no gain), at 7.1-8.3 Hz instead of "
        "10.6-11.3 Hz (the object poses enter the reduced camera system); with e_const too "
        "0.0047 / 0.0049 / 0.0055 against 0.0048 / 0.0050 / 0.0055 (still no gain that pays "
        "for the time), and the objects' aligned ATE on crowded s1-s2 0.036 / 0.023 -> 0.053 / "
        "0.035 m")
    dynamic_points_per_object: int = param(
        20, "each object's most often found points in the BA: every object adds its keyframe "
        "poses to the reduced camera system, and its points past a few tens cost solver time, "
        "not camera information", "points")
    dynamic_link_sigma_translation: float = param(
        0.1, "out-of-plane motion allowed between an object's keyframe poses (e_link). 0.01, "
        "the object window's per-frame value, made the crowded camera RPE worse (0.0047 -> "
        "0.0050 m, 0.0104 -> 0.0114 deg per frame, seed 0): the road normal's error times a "
        "car's travel between keyframes exceeds it", "m")
    dynamic_link_sigma_rotation: float = param(
        0.02, "roll and pitch change allowed between an object's keyframe poses (with the "
        "0.1 m above: crowded seed 0 camera RPE 0.0045 m, 0.0101 deg per frame)", "rad")
    dynamic_const: bool = param(
        True, "e_const (eq. 9) between an object's keyframe poses as well: the mean per-frame "
        "twists of consecutive keyframe intervals agree, within visual_objects.const_sigma_* "
        "times sqrt of the mean gap (with visual_objects.use_const; docs/optim.md). Measured "
        "with dynamic_objects on, crowded seeds 0-2, against without it: camera RPE 0.0047 / "
        "0.0049 / 0.0055 m and 0.0104 / 0.0118 / 0.0134 deg per frame, 0.0048 / 0.0049 / "
        "0.0056 and 0.0104 / 0.0119 / 0.0136 (a hair better); objects mixed (crowded s1 aligned "
        "ATE 0.053 vs 0.038 m, urban s1 0.103 vs 0.070)")


@dataclass
class MapConfig:
    """Map point creation and culling."""

    min_found_ratio: float = param(
        0.25, "cull points found in fewer than 1/4 of the frames that should see them (ORB-SLAM2)")
    cull_after_keyframes: int = param(
        2, "a new point is judged after 2 more keyframes (ORB-SLAM2)", "keyframes")
    max_points: int = param(200000, "memory bound of the map (~100 MB of descriptors and "
                            "observations)", "points")


@dataclass
class RunConfig:
    """The sequence loop in Python (not sent to the core)."""

    max_frames: int | None = param(None, "None: the whole sequence", "frames", lo=1)
    start_frame: int = param(0, "KITTI frame index to start from", lo=0)
    loader_nice: int = param(
        10, "niceness added to the thread that reads the next frame and runs its perception "
        "stages (Linux; 0: as the loop). The loop waits for the local BA's thread, which shares "
        "the second core with this one, while this one only needs to be done by the next frame. "
        "Measured on 2 cores, DIS flow, three paired runs each, 0 -> 10: urban s1 9.9 / 10.0 / "
        "8.1 -> 10.4 / 9.8 / 9.0 Hz, urban s7 10.5 / 9.4 / 8.0 -> 11.3 / 10.5 / 10.0 Hz (the "
        "loop's wait for the BA 18-31 -> 14-25 ms per frame), crowded s1 7.0 / 6.0 -> 7.5 / 6.8 "
        "Hz; the same results (the BA applies before the next frame either way)",
        "nice steps", lo=0, hi=19)
    use_labels: bool = param(
        True, "read the per-frame panoptic image, when present, to mask dynamic_class_ids")
    labels_dir: str = param("panoptic", "folder beside image_02 holding <seq>/NNNNNN.png, "
                            "the simulator's layout")


#: section name -> dataclass, in the order of the YAML file
SECTIONS: dict[str, type] = {
    "orb": OrbConfig,
    "stereo": StereoConfig,
    "tracking": TrackingConfig,
    "keyframes": KeyframeConfig,
    "local_ba": LocalBAConfig,
    "map": MapConfig,
    "run": RunConfig,
    "objects": ObjectsConfig,
    "lidar": LidarConfig,
    "visual_objects": VisualObjectsConfig,
    "lidar_objects": LidarObjectsConfig,
    "detection": DetectionConfig,
}
#: sections the SLAM system does not read (the object tracker reads ``objects`` itself)
_NOT_FOR_CORE = ("run", "objects", "detection")


@dataclass
class Config:
    """Every setting of a run; ``Config()`` holds the defaults.

    Build one from defaults, a YAML file (:meth:`from_yaml`, partial files allowed) or a
    dictionary (:meth:`from_dict`), then adjust it with :meth:`override`. Unknown sections or
    keys and values of the wrong type or out of range raise ``ValueError`` naming the key and
    what is allowed.
    """

    orb: OrbConfig = field(default_factory=OrbConfig)
    stereo: StereoConfig = field(default_factory=StereoConfig)
    tracking: TrackingConfig = field(default_factory=TrackingConfig)
    keyframes: KeyframeConfig = field(default_factory=KeyframeConfig)
    local_ba: LocalBAConfig = field(default_factory=LocalBAConfig)
    map: MapConfig = field(default_factory=MapConfig)
    run: RunConfig = field(default_factory=RunConfig)
    objects: ObjectsConfig = field(default_factory=ObjectsConfig)
    lidar: LidarConfig = field(default_factory=LidarConfig)
    visual_objects: VisualObjectsConfig = field(default_factory=VisualObjectsConfig)
    lidar_objects: LidarObjectsConfig = field(default_factory=LidarObjectsConfig)
    detection: DetectionConfig = field(default_factory=DetectionConfig)

    def __post_init__(self) -> None:
        self.validate()

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> "Config":
        """Defaults updated with a nested ``{section: {key: value}}`` mapping."""
        config = cls()
        if data is None:
            return config
        if not isinstance(data, Mapping):
            raise ValueError(f"config: expected a mapping of sections, got {type(data).__name__}")
        for name, values in data.items():
            _section_type(name)  # unknown section -> ValueError
            if values is None:
                continue
            if not isinstance(values, Mapping):
                raise ValueError(f"config section {name!r}: expected a mapping of keys, "
                                 f"got {values!r}")
            for key, value in values.items():
                config._set(f"{name}.{key}", value)
        config.validate()
        return config

    @classmethod
    def from_yaml(cls, path: str | Path) -> "Config":
        """Defaults updated with the sections and keys a YAML file gives."""
        import yaml

        path = Path(path)
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8"))
        except yaml.YAMLError as exc:
            raise ValueError(f"{path}: not valid YAML: {exc}") from None
        try:
            return cls.from_dict(data)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None

    # ---------------------------------------------------------------------- changes
    def override(self, items: str | Iterable[str] | Mapping[str, Any]) -> "Config":
        """Set values by dotted key, in place; returns ``self`` for chaining.

        Parameters
        ----------
        items
            ``"section.key=value"``, a list of such strings (the command line's ``--set``),
            or a mapping ``{"section.key": value}``. A string value is converted with the
            field's type: ``int``, ``float``, ``bool`` (true/false/yes/no/on/off/1/0),
            ``str``, lists as ``[1, 2]`` or ``1,2``, and ``none``/``null`` where allowed.
        """
        if isinstance(items, str):
            items = [items]
        if isinstance(items, Mapping):
            pairs = list(items.items())
        else:
            pairs = []
            for item in items:
                key, sep, value = str(item).partition("=")
                if not sep or "." not in key:
                    raise ValueError(f"expected section.key=value, got {item!r}")
                pairs.append((key.strip(), value.strip()))
        # applied to a copy first: a bad item leaves this config as it was
        trial = Config.from_dict(self.to_dict())
        for key, value in pairs:
            trial._set(key, value)
        trial.validate()
        for name in SECTIONS:
            setattr(self, name, getattr(trial, name))
        return self

    def _set(self, dotted: str, value: Any) -> None:
        section_name, _, key = dotted.partition(".")
        section_type = _section_type(section_name)
        types_ = type_hints(section_type)
        if key not in types_:
            raise ValueError(
                f"unknown key {dotted!r}; keys of section {section_name!r}: "
                + ", ".join(f.name for f in fields(section_type))
            )
        setattr(getattr(self, section_name), key, coerce(value, types_[key], dotted))

    def validate(self) -> None:
        """Check every value's type and range; raises ``ValueError`` naming the key."""
        for name, section_type in SECTIONS.items():
            section = getattr(self, name)
            if not isinstance(section, section_type):
                raise ValueError(f"config section {name!r}: expected {section_type.__name__}")
            types_ = type_hints(section_type)
            for f in fields(section_type):
                key = f"{name}.{f.name}"
                value = coerce(getattr(section, f.name), types_[f.name], key)
                setattr(section, f.name, value)
                if name in _NOT_FOR_CORE:
                    _check_range(value, f.metadata, key)
        try:  # ranges and cross-field rules of the core's sections: the core's own check
            _core_slam.check_options(self.to_options())
        except ValueError as exc:
            raise ValueError(str(exc).removeprefix("options: ")) from None
        self.lidar.validate()

    # ---------------------------------------------------------------------- output
    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Nested plain dictionary of every section (lists copied)."""
        return {
            name: {f.name: _plain(getattr(getattr(self, name), f.name))
                   for f in fields(SECTIONS[name])}
            for name in SECTIONS
        }

    def to_options(self) -> dict[str, dict[str, Any]]:
        """The nested options dictionary the C++ core reads (every section but ``run``)."""
        options = {k: v for k, v in self.to_dict().items() if k not in _NOT_FOR_CORE}
        for key in _LIDAR_PYTHON_ONLY:  # resolved in Python (twistslam.camera_lidar)
            options["lidar"].pop(key)
        return options

    def to_yaml(self, path: str | Path | None = None) -> str:
        """YAML text of every setting, each with its unit and reason as a comment; written to
        ``path`` when given. :meth:`from_yaml` reads it back to an equal config."""
        lines = ["# twistslam configuration: every setting with its unit and the reason for "
                 "its default", ""]
        for name, section_type in SECTIONS.items():
            lines.append(f"{name}:  # {section_type.__doc__.strip().splitlines()[0]}")
            for f in fields(section_type):
                value = _yaml_scalar(getattr(getattr(self, name), f.name))
                unit = f"[{f.metadata['unit']}] " if f.metadata.get("unit") else ""
                lines.append(f"  {f.name}: {value}  # {unit}{f.metadata.get('why', '')}".rstrip())
            lines.append("")
        text = "\n".join(lines)
        if path is not None:
            path = Path(path)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
        return text

    @staticmethod
    def describe(dotted: str) -> dict[str, Any]:
        """Default, unit, reason and range (``lo``, ``hi``: inclusive; ``None`` = unbounded)
        of one setting, e.g. ``"tracking.min_inliers"``."""
        section_name, _, key = dotted.partition(".")
        for f in fields(_section_type(section_name)):
            if f.name == key:
                default = f.default if f.default is not MISSING else f.default_factory()
                info = {"default": default, **f.metadata}
                if section_name not in _NOT_FOR_CORE:
                    info["lo"], info["hi"] = _core_ranges()[section_name].get(key, (None, None))
                return info
        raise ValueError(f"unknown key {dotted!r}")


# ------------------------------------------------------------------------- helpers
def _core_ranges() -> dict[str, dict[str, tuple[float, float]]]:
    """``{section: {key: (lo, hi)}}`` of the core's options (inclusive, in each unit)."""
    return _core_slam.option_ranges()


def _section_type(name: str) -> type:
    if name not in SECTIONS:
        raise ValueError(f"unknown config section {name!r}; sections: {', '.join(SECTIONS)}")
    return SECTIONS[name]


def _plain(value: Any) -> Any:
    return list(value) if isinstance(value, (list, tuple)) else value


def _yaml_scalar(value: Any) -> str:
    """Flow-style YAML of the value types a config holds (JSON strings are valid YAML)."""
    import json

    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_yaml_scalar(v) for v in value) + "]"
    if isinstance(value, float):
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    return json.dumps(str(value))


def _check_range(value: Any, meta: Mapping[str, Any], key: str) -> None:
    lo, hi = meta.get("lo"), meta.get("hi")
    items = value if isinstance(value, list) else [value]
    for v in items:
        if v is None or isinstance(v, (str, bool)):
            continue
        if (lo is not None and v < lo) or (hi is not None and v > hi) or v != v:
            bounds = f"[{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}]"
            raise ValueError(f"{key} = {v} is out of range {bounds}")
