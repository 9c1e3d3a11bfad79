"""Every tunable of the simulator, grouped by concern, with its unit and why it has its default.

A :class:`SimConfig` is plain data: scenarios (:mod:`twistslam.sim.scenario`) and user
overrides (``generate(..., lidar__range_noise=0.05)`` or ``--set lidar.range_noise=0.05``)
edit its fields; nothing else changes the behaviour of a run.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import Any

from .._settings import coerce, type_hints



@dataclass
class StreetConfig:
    """Road layout: the main street, an optional cross street, sidewalks and terrain."""

    lanes_per_direction: int = 1  # lanes; a KITTI-like city street has one lane each way
    lane_width: float = 3.5  # m; standard urban lane width
    parking_width: float = 2.3  # m; parking lane along each curb (0 = none)
    sidewalk_width: float = 3.5  # m; room for trees, poles and pedestrians
    curb_height: float = 0.15  # m; a typical European curb
    max_curvature: float = 1.0 / 180.0  # 1/m; gentle curves (radius >= 180 m)
    curve_length: tuple[float, float] = (60.0, 160.0)  # m; length of one constant-curvature piece
    intersection: bool = True  # a perpendicular cross street somewhere ahead
    intersection_ahead: tuple[float, float] = (55.0, 95.0)  # m from the ego start to its centre
    cross_lanes_per_direction: int = 1  # lanes of the cross street
    terrain_amplitude: float = 1.0  # m; amplitude of the smooth height field (grades <= ~1.3 %)
    terrain_wavelength: float = 500.0  # m; long hills: grades change < 1 % over 50 m
    behind: float = 90.0  # m of street behind the ego start (the LiDAR sees backwards)
    ahead: float = 160.0  # m of street beyond the farthest ego position (visible range)


@dataclass
class SideConfig:
    """What lines the streets: buildings, trees, poles, barriers."""

    buildings: bool = True  # facades on both sides (off on the highway)
    building_gap: tuple[float, float] = (0.0, 1.5)  # m between sidewalk and facade
    building_front: tuple[float, float] = (9.0, 26.0)  # m of frontage per building
    building_depth: tuple[float, float] = (10.0, 18.0)  # m; deep enough to hide what is behind
    building_height: tuple[float, float] = (7.0, 24.0)  # m; 2-7 storeys
    alley_probability: float = 0.12  # chance of a gap after a building (parallax, sky)
    tree_spacing: float = 14.0  # m between street trees on a sidewalk (0 = none)
    pole_spacing: float = 28.0  # m between lamp posts (0 = none)
    sign_probability: float = 0.35  # chance that a pole carries a sign panel
    guard_rails: bool = False  # highway barriers along the road edge and the median


@dataclass
class TrafficConfig:
    """Objects and their motion; the ego car is one more agent of the same simulation."""

    moving_density: float = 2.5  # cars per 100 m of lane; KITTI streets are sparse-ish
    moving_speed: tuple[float, float] = (6.0, 14.0)  # m/s desired speeds of moving cars
    parked_density: float = 9.0  # cars per 100 m of curb (a parked car takes ~6 m)
    pedestrian_density: float = 3.0  # people per 100 m of sidewalk (0 = none)
    pedestrian_speed: tuple[float, float] = (0.9, 1.6)  # m/s walking speeds
    lane_change_probability: float = 0.3  # per car on a multi-lane road, once per sequence
    turn_probability: float = 0.35  # chance that a car reaching the intersection turns
    cross_traffic: bool = True  # cars on the cross street
    ego_speed: tuple[float, float] = (5.0, 15.0)  # m/s, the range for the ego car
    ego_lane: int = 0  # lane index counted from the centre line (0 = next to it)
    ego_turn: str = "none"  # none | left | right: what the ego does at the intersection
    lead_car: bool = True  # a car ahead of the ego car in its lane, as in most KITTI drives
    ego_lead_gap: tuple[float, float] = (12.0, 40.0)  # m to that car, bumper to bumper
    car_mix: tuple[float, float, float] = (0.55, 0.3, 0.15)  # sedan, hatchback, SUV shares
    platoon: bool = False  # crowded: dense columns of cars driving with the ego car
    platoon_gap: tuple[float, float] = (1.5, 3.5)  # m bumper to bumper inside a platoon
    nonplanar: float = 0.0  # rad; amplitude of roll/pitch perturbation (0 = planar motion)
    max_lateral_accel: float = 3.5  # m/s^2; sets turn speeds (9 m radius -> 5.6 m/s)
    idm_headway: float = 1.2  # s; IDM time gap, typical city driving
    idm_min_gap: float = 2.0  # m; IDM jam distance
    idm_accel: float = 1.5  # m/s^2; IDM maximum acceleration
    idm_decel: float = 2.5  # m/s^2; IDM comfortable deceleration


#: px, largest image side: 6.6x KITTI's 1242 px width (a typo such as --width 100000 asked
#: for a 149 GiB allocation)
MAX_IMAGE_SIDE = 8192
#: pixels of an image: measured peak memory 0.67 GB at KITTI's 0.47 Mpx and 1.4 GB at 1.9 Mpx
#: (about 0.5 GB per Mpx), so 4 Mpx (8.6x KITTI) stays near 2.5 GB
MAX_RENDER_PIXELS = 4_000_000
#: rays per pixel side: the render time grows with its square (4 = 16 rays, 16x the time)
MAX_SUPERSAMPLE = 4
#: frames of a sequence: about twice KITTI tracking's longest (1,059 frames). The whole street
#: is built up front (measured: 40 s for 300 frames; --frames 1e8 never finished), and urban
#: drives past ~1,000 frames exceed the panoptic encoding's 998 objects anyway
MAX_FRAMES = 2000


def check_camera(cam: "CameraConfig") -> None:
    """Refuse an image size or supersampling the renderer cannot afford, naming the setting
    (``--width`` / ``--height`` on the command line)."""
    for name in ("width", "height"):
        value = getattr(cam, name)
        if not 1 <= value <= MAX_IMAGE_SIDE:
            raise ValueError(f"camera.{name} (--{name}) = {value}: must be in [1, "
                             f"{MAX_IMAGE_SIDE}] px")
    if cam.width * cam.height > MAX_RENDER_PIXELS:
        raise ValueError(f"camera.width x camera.height (--width x --height) = {cam.width} x "
                         f"{cam.height} = {cam.width * cam.height} pixels: at most "
                         f"{MAX_RENDER_PIXELS} (about 0.5 GB of memory per million pixels)")
    if not 1 <= cam.supersample <= MAX_SUPERSAMPLE:
        raise ValueError(f"camera.supersample = {cam.supersample}: must be in [1, "
                         f"{MAX_SUPERSAMPLE}] (render time grows with its square)")


@dataclass
class CameraConfig:
    """Stereo pair: calibration, image size, optics and sensor."""

    calib_path: str | None = None  # KITTI calib file; None = tracking sequence 0000
    width: int = 1242  # px, KITTI image width
    height: int = 375  # px, KITTI image height
    camera_height: float = 1.65  # m above the road, KITTI's camera mounting height
    supersample: int = 1  # rays per pixel side (2 = 4 rays/pixel); 1 keeps 2 frames/s
    noise_std: float = 1.5  # 8-bit grey levels of Gaussian sensor noise
    gamma: float = 2.2  # display gamma applied to linear radiance
    exposure: float = 1.1  # linear gain before the gamma curve


@dataclass
class LightConfig:
    """Sun and sky."""

    sun_elevation: tuple[float, float] = (30.0, 60.0)  # deg; a daytime sun
    sun_intensity: float = 1.0  # irradiance of the sun (linear units)
    ambient: float = 0.38  # sky irradiance, so shadows are dark but not black
    shadows: bool = True  # cast shadows (one occlusion ray per hit)


@dataclass
class LidarConfig:
    """Velodyne HDL-64E model."""

    enabled: bool = True  # write velodyne/ scans
    elevation_max: float = 2.0  # deg, upper beam
    elevation_min: float = -24.9  # deg, lower beam
    azimuth_step: float = 0.18  # deg; HDL-64E at 10 Hz: ~2000 points per beam
    max_range: float = 120.0  # m; the HDL-64E's rated range
    min_range: float = 2.5  # m; returns from the ego car body are discarded
    range_noise: float = 0.02  # m, standard deviation along the beam (truncated at 2 sigma)
    dropout: float = 0.02  # fraction of returns lost at random
    glass_dropout: float = 0.6  # fraction of returns lost on glass (windows)


@dataclass
class OracleConfig:
    """Noisy 'oracle' 3D detections derived from ground truth (PointRCNN text format)."""

    enabled: bool = True  # write detections/oracle/SEQ.txt
    center_noise: float = 0.12  # m at 10 m, growing linearly with distance / 10 m
    size_noise: float = 0.05  # relative standard deviation of l, w, h
    yaw_noise: float = 0.04  # rad
    yaw_flip_rate: float = 0.02  # chance of a heading off by pi (a classic detector error)
    miss_rate: float = 0.05  # chance to drop a detectable object
    min_points: int = 8  # LiDAR points in the box below which an object is never detected
    false_positive_rate: float = 0.3  # mean false detections per frame (Poisson)
    score_true: tuple[float, float] = (9.0, 3.0)  # mean, std of true scores (PointRCNN scale)
    score_false: tuple[float, float] = (0.5, 1.5)  # mean, std of false scores


@dataclass
class OutputConfig:
    """Which extras to write, and how."""

    panoptic: bool = True  # panoptic/SEQ/NNNNNN.png
    flow: bool = True  # flow_occ/ and flow_noc/ (KITTI flow PNG)
    disparity: bool = True  # disparity/SEQ/NNNNNN.png (KITTI disparity PNG)
    lidar_labels: bool = True  # velodyne_labels/SEQ/NNNNNN.label (SemanticKITTI)
    meshes: bool = True  # meshes/SEQ/*.ply + shapes.json
    png_compression: int = 1  # zlib level; 1 is fast and still lossless
    min_visible_pixels: int = 12  # px of the visible mask for an object to be labelled


@dataclass
class SimConfig:
    """One simulated sequence."""

    scenario: str = "urban"
    frames: int = 100
    seed: int = 0
    seq: str = "0000"
    frame_period: float = 0.1  # s; KITTI's 10 Hz
    street: StreetConfig = field(default_factory=StreetConfig)
    side: SideConfig = field(default_factory=SideConfig)
    traffic: TrafficConfig = field(default_factory=TrafficConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    light: LightConfig = field(default_factory=LightConfig)
    lidar: LidarConfig = field(default_factory=LidarConfig)
    oracle: OracleConfig = field(default_factory=OracleConfig)
    output: OutputConfig = field(default_factory=OutputConfig)

    def with_overrides(self, overrides: dict[str, Any]) -> "SimConfig":
        """Copy with fields replaced; keys ``"section.field"``, ``"section__field"`` or a
        top-level field name; a section name with a dict value updates several fields."""
        cfg = replace(self, **{f.name: _copy(getattr(self, f.name)) for f in fields(self)})
        for key, value in overrides.items():
            parts = key.replace("__", ".").split(".")
            if len(parts) == 1 and isinstance(value, dict):
                for sub_key, sub_value in value.items():
                    _set(cfg, [parts[0], sub_key], sub_value)
            else:
                _set(cfg, parts, value)
        return cfg


def _copy(value: Any) -> Any:
    return replace(value) if is_dataclass(value) else value


def _set(cfg: Any, parts: list[str], value: Any) -> None:
    target = cfg
    for name in parts[:-1]:
        if not is_dataclass(target) or not hasattr(target, name):
            raise ValueError(f"unknown simulator setting {'.'.join(parts)!r}")
        target = getattr(target, name)
    name = parts[-1]
    if not is_dataclass(target) or name not in {f.name for f in fields(target)}:
        raise ValueError(f"unknown simulator setting {'.'.join(parts)!r}")
    hints = type_hints(type(target))
    value = coerce(value, hints[name], f"simulator setting {'.'.join(parts)!r}")
    setattr(target, name, value)
