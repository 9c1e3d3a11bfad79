"""``Slam``: the frame-by-frame face of the C++ SLAM system (``twistslam._core.slam``).

>>> slam = Slam(Config(), seq.calib)                       # doctest: +SKIP
>>> for frame in seq:                                      # doctest: +SKIP
...     out = slam.track(frame)
...     print(out.index, out.status, out.T_w_c[:3, 3])
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import geometry
from .config import Config
from .datasets import Calibration, Frame
from .perception.detection import Detections3D
from .perception.panoptic_from_boxes import KITTI_TO_CITYSCAPES

#: what the core reports per frame
STATUSES = ("initialized", "ok", "lost", "relocalized")


@dataclass
class TrackedFrame:
    """The system's output for one frame.

    ``status`` is ``"initialized"`` (map started here), ``"ok"``, ``"lost"`` (too few inliers
    or no usable image: ``T_w_c`` is a prediction) or ``"relocalized"`` (the first frame
    tracked after a loss: found again in the last local map, or the start of a new map
    segment). ``timings_ms`` holds the core's stages plus ``"track"``, the wall time of the
    whole call.
    """

    index: int
    status: str
    T_w_c: np.ndarray  # (4, 4) float64, camera -> world (world = camera at the first frame)
    is_keyframe: bool = False
    num_inliers: int = 0
    num_map_points: int = 0
    num_keyframes: int = 0
    num_lidar_depth: int = 0  # keypoints that took their depth from the LiDAR scan
    timings_ms: dict[str, float] = field(default_factory=dict)
    num_objects_tracked: int = 0  # object clusters with a valid twist in this frame
    num_object_points: int = 0    # their matched inlier points


def _detection_arrays(detections: Detections3D) -> tuple[np.ndarray, ...]:
    """Boxes, scores, panoptic class ids, open ends, point-extent and heading-known flags of
    the detections whose KITTI type has a panoptic class (``KITTI_TO_CITYSCAPES``)."""
    if not isinstance(detections, Detections3D):
        raise TypeError(f"detections: expected Detections3D, got {type(detections).__name__}")
    class_ids = np.array([KITTI_TO_CITYSCAPES.get(str(c), -1) for c in detections.classes],
                         dtype=np.int64)
    keep = class_ids >= 0
    return (detections.boxes[keep], detections.scores[keep], class_ids[keep],
            detections.open_end[keep], detections.point_extent[keep], detections.heading_known[keep])


def _new_system(camera, options: dict[str, Any]):
    """Construct the C++ system (imported here: ``import twistslam`` must not need it)."""
    from twistslam._core import slam as _slam

    return _slam.System(camera, options)


def _as_image(image: Any, name: str, index: int) -> np.ndarray:
    if image is None:
        raise ValueError(f"frame {index}: no {name} image; stereo SLAM needs both images")
    image = np.asarray(image)
    if image.dtype != np.uint8:
        raise ValueError(f"frame {index}: {name} image must be uint8, got {image.dtype}")
    if not (image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 3)):
        raise ValueError(f"frame {index}: {name} image must be (H, W) or (H, W, 3), "
                         f"got shape {image.shape}")
    return np.ascontiguousarray(image)


class Slam:
    """Stereo SLAM on a stream of frames.

    Parameters
    ----------
    config
        Settings (``None``: the defaults); copied, later changes to it have no effect.
    calibration
        The sequence's :class:`~twistslam.datasets.Calibration` (cameras 2 and 3), or a
        ``twistslam.geometry.StereoCamera`` with its image size set.
    image_size
        ``(width, height)`` in pixels. Default: the camera's, or else the first frame's.
        Every frame must have this size.
    """

    def __init__(self, config: Config | None = None, calibration: Calibration | Any = None,
                 *, image_size: tuple[int, int] | None = None) -> None:
        if calibration is None:
            raise ValueError("Slam needs the stereo calibration (a Calibration or StereoCamera)")
        self.config = Config.from_dict(config.to_dict()) if config is not None else Config()
        self.calibration = calibration
        if image_size is None and not isinstance(calibration, Calibration):
            if getattr(calibration, "width", 0) > 0 and getattr(calibration, "height", 0) > 0:
                image_size = (int(calibration.width), int(calibration.height))
        self.image_size = tuple(image_size) if image_size is not None else None
        self._system = None
        self._last: list[np.ndarray] = []  # the last two poses, for a fallback prediction
        #: the stereo pair's disparity offset the run uses (px; config ``lidar.disparity_offset``,
        #: "auto" resolved at the first frame) and how it was obtained
        self.disparity_offset: float | None = self.config.lidar.fixed_disparity_offset()
        self.disparity_offset_source = "config" if self.disparity_offset is not None else ""

    @property
    def camera(self):
        """The ``StereoCamera`` the core uses (``None`` before the image size is known), with
        the disparity offset once it is known."""
        if self.image_size is None:
            return None
        if isinstance(self.calibration, Calibration):
            camera = self.calibration.stereo_camera(*self.image_size)
        else:
            camera = self.calibration
        if self.disparity_offset is not None and self.disparity_offset != camera.disparity_offset:
            camera = camera.with_disparity_offset(self.disparity_offset)
        return camera

    def _resolve_disparity_offset(self, frame: Frame, labels: np.ndarray | None) -> None:
        """``lidar.disparity_offset = "auto"``: estimated from the first frame when it has a
        scan (docs/camera_scale.md), else the camera's own (0 from a calibration: trusted)."""
        if self.disparity_offset is not None:
            return
        from .camera_lidar import estimate_offset

        estimate = estimate_offset(frame, self.camera, self.config, labels)
        if estimate.valid:
            self.disparity_offset = estimate.offset_px
            self.disparity_offset_source = (
                f"LiDAR, frame {frame.index}: median of {estimate.num_samples} keypoints, "
                f"MAD {estimate.mad_px:.2f} px")
        else:
            self.disparity_offset = float(self.camera.disparity_offset)
            self.disparity_offset_source = f"none ({estimate.reason}): calibration trusted"

    def _system_for(self, frame: Frame, labels: np.ndarray | None):
        if self._system is None:
            if self.image_size is None:
                height, width = np.asarray(frame.image_left).shape[:2]
                self.image_size = (width, height)
            self._resolve_disparity_offset(frame, labels)
            self._system = _new_system(self.camera, self.config.to_options())
        return self._system

    def track(self, frame: Frame, labels: np.ndarray | None = None, *,
              instances: np.ndarray | None = None, flow: np.ndarray | None = None,
              detections: Detections3D | None = None) -> TrackedFrame:
        """Track one stereo frame.

        Parameters
        ----------
        frame
            Needs ``index``, ``timestamp``, ``image_left`` and ``image_right`` (uint8,
            ``(H, W)`` grey or ``(H, W, 3)`` RGB, both of the calibrated size).
        labels
            Optional ``(H, W)`` panoptic class ids of the left image; pixels of
            ``config.tracking.dynamic_class_ids`` give no points to camera tracking.
        instances
            Optional ``(H, W)`` panoptic instance ids (0: none): instances of
            ``config.visual_objects.object_class_ids`` become tracked object clusters.
        flow
            Optional ``(H, W, 2)`` float32 optical flow from the previous frame's left image
            (NaN: unknown), where object tracking starts its search.
        detections
            Optional 3D detections of the frame (boxes in its camera frame): the LiDAR fusion
            of object tracking (``config.lidar_objects``) gives the clusters their canonical
            pose, size and the e_det twist. KITTI types map to the panoptic classes (a van is
            a car); a type without one is ignored.

        Raises
        ------
        ValueError
            A missing image, a wrong dtype or shape, a size other than the calibrated one.
            A blank or textureless frame is not an error: it comes back ``"lost"``.
        """
        i = int(frame.index)
        left = _as_image(frame.image_left, "left", i)
        right = _as_image(frame.image_right, "right", i)
        if left.shape != right.shape:
            raise ValueError(f"frame {i}: left image {left.shape} and right image {right.shape} "
                             "differ in shape")
        height, width = left.shape[:2]
        if self.image_size is not None and (width, height) != tuple(self.image_size):
            raise ValueError(f"frame {i}: image size {width}x{height} differs from "
                             f"{self.image_size[0]}x{self.image_size[1]}, the size the system "
                             "was started with (calibration or first frame)")
        if labels is not None:
            labels = np.ascontiguousarray(labels, dtype=np.int32)
            if labels.shape != (height, width):
                raise ValueError(f"frame {i}: labels of shape {labels.shape}, expected "
                                 f"{(height, width)}")
        if instances is not None:
            instances = np.ascontiguousarray(instances, dtype=np.int32)
            if instances.shape != (height, width):
                raise ValueError(f"frame {i}: instances of shape {instances.shape}, expected "
                                 f"{(height, width)}")
        if flow is not None:
            flow = np.ascontiguousarray(flow, dtype=np.float32)
            if flow.shape != (height, width, 2):
                raise ValueError(f"frame {i}: flow of shape {flow.shape}, expected "
                                 f"{(height, width, 2)}")
        system = self._system_for(frame, labels)
        scan = None
        # the scan serves keypoint depth, the registration of object scans (e_reg) and the
        # road returns of the road plane fit
        registration = detections is not None and self.config.lidar_objects.use_registration
        wanted = (self.config.lidar.use_depth or registration
                  or self.config.visual_objects.road_lidar_points)
        if wanted and frame.points_c is not None:
            scan = np.asarray(frame.points_c)[:, :3]

        boxes = scores = class_ids = open_ends = point_extents = headings_known = None
        if detections is not None:
            boxes, scores, class_ids, open_ends, point_extents, headings_known = _detection_arrays(detections)

        start = time.perf_counter()
        out = system.track(i, float(frame.timestamp), left, right, labels, scan, instances, flow,
                           boxes, scores, class_ids, open_ends, point_extents, headings_known)
        track_ms = (time.perf_counter() - start) * 1e3

        T_w_c = np.asarray(out["T_w_c"], dtype=np.float64).reshape(4, 4)
        if not np.isfinite(T_w_c).all():
            # the core predicts lost frames itself; this only guards the output arrays
            T_w_c = self._predict()
        self._last = [*self._last[-1:], T_w_c]
        timings = {str(k): float(v) for k, v in dict(out.get("timings_ms", {})).items()}
        timings["track"] = track_ms
        return TrackedFrame(
            index=i,
            status=str(out["status"]),
            T_w_c=T_w_c,
            is_keyframe=bool(out.get("is_keyframe", False)),
            num_inliers=int(out.get("num_inliers", 0)),
            num_map_points=int(out.get("num_map_points", 0)),
            num_keyframes=int(out.get("num_keyframes", 0)),
            num_lidar_depth=int(out.get("num_lidar_depth", 0)),
            timings_ms=timings,
            num_objects_tracked=int(out.get("num_objects_tracked", 0)),
            num_object_points=int(out.get("num_object_points", 0)),
        )

    def _predict(self) -> np.ndarray:
        """Constant-velocity prediction from the last two poses (identity at the start), the
        core's own formula (``geometry.predict_constant_velocity``)."""
        if not self._last:
            return np.eye(4)
        if len(self._last) == 1:
            return self._last[-1].copy()
        prev, last = self._last
        return geometry.predict_constant_velocity(prev, last)

    def trajectory(self) -> dict[str, np.ndarray] | None:
        """``frame_index`` (N,) and ``T_w_c`` (N, 4, 4) of every frame tracked so far,
        re-expressed through their keyframes so that bundle adjustment reaches them; ``None``
        when the core keeps no trajectory (then the per-frame ``track`` poses are final)."""
        if self._system is None or not hasattr(self._system, "trajectory"):
            return None
        traj = self._system.trajectory()
        return {"frame_index": np.asarray(traj["frame_index"], dtype=np.int64),
                "T_w_c": np.asarray(traj["T_w_c"], dtype=np.float64).reshape(-1, 4, 4)}

    def keyframes(self) -> dict[str, np.ndarray]:
        """``frame_index`` (K,) and ``T_w_c`` (K, 4, 4) of the keyframes (after local BA)."""
        if self._system is None:
            return {"frame_index": np.zeros(0, np.int64), "T_w_c": np.zeros((0, 4, 4))}
        return {k: np.asarray(v) for k, v in self._system.keyframes().items()}

    def map_points(self) -> dict[str, np.ndarray]:
        """``X_w`` (M, 3), ``cluster_id`` (M,), ``num_observations`` (M,) of the map."""
        if self._system is None:
            return {"X_w": np.zeros((0, 3)), "cluster_id": np.zeros(0, np.int64),
                    "num_observations": np.zeros(0, np.int64)}
        return {k: np.asarray(v) for k, v in self._system.map_points().items()}

    def objects(self) -> list[dict]:
        """Every object cluster the core started: its track (``id``, ``class_id``, ``link``,
        ``frames``, ``T_w_o`` (K, 4, 4) world frame, ``twist``, ``detected`` = tracked that frame,
        ...) and ``points_o`` (M, 3), its points in the object frame."""
        if self._system is None:
            return []
        return list(self._system.objects())

    def smooth_objects(self) -> dict[str, int]:
        """The final smoothing of the object tracks, once the sequence ends
        (``config.visual_objects.final_smoothing``; ``twistslam.run`` calls it): per track,
        all its rows and every observation of its points, e_const, e_link, e_head and the
        LiDAR terms in one problem, the cameras fixed at the refined trajectory. Afterwards
        :meth:`objects` gives the smoothed ``T_w_o`` and the online poses as
        ``T_w_o_online``. Without ``final_smoothing`` only the output's LiDAR verdicts are
        taken again (rows hidden online because the LiDAR saw through a box or a whole track's
        points lay nearer than the LiDAR sees them). Returns ``num_tracks`` (smoothed),
        ``num_rejected`` (kept online: a smoothed step beyond ``max_step_m``) and
        ``num_residuals``."""
        if self._system is None:
            return {"num_tracks": 0, "num_rejected": 0, "num_residuals": 0}
        return dict(self._system.smooth_objects())

    def road_plane(self) -> dict | None:
        """The road plane of the planar link (``valid``, ``plane`` (4,) = (n, d) with
        n . X_w + d = 0, ``num_points``, ``num_fits``, ``last_inliers``); None before the first
        frame."""
        if self._system is None:
            return None
        return dict(self._system.road_plane())

    def reset(self) -> None:
        """Forget the map and the trajectory; the next frame initialises a new map."""
        if self._system is not None:
            self._system.reset()
        self._last = []
