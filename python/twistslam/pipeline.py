"""``twistslam.run``: a whole sequence through the SLAM system, frame by frame.

>>> result = twistslam.run("data/sim", config=None)        # doctest: +SKIP
>>> result.camera_poses.shape, result.status[:3]           # doctest: +SKIP
((100, 4, 4), array(['initialized', 'ok', 'ok'], dtype='<U11'))
>>> result.save("results/0000")                            # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import os
import threading
import time
import warnings
from dataclasses import dataclass
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from .config import Config
from .config_detection import detector_options
from .datasets import Frame, Sequence, open_sequence
from .inputs import PanopticLabels, check_stereo, load_frame
from .input_checks import check_first_frames
from .progress import RateBar
from .objects.camera_boxes import CameraBoxRules
from .objects.visual import visual_objects
from .result import Result
from .perception.detection import Detections3D
from .perception.run_stages import Perception, perception_stages
from .slam import Slam
from .timings import Timings

SequenceLike = Sequence | str | Path | tuple[Any, Any]


def _open(seq_or_path: SequenceLike) -> Sequence:
    if isinstance(seq_or_path, tuple):
        if len(seq_or_path) != 2:
            raise ValueError(f"expected (root, seq), got a tuple of {len(seq_or_path)} items")
        return open_sequence(*seq_or_path)
    return open_sequence(seq_or_path)


def _config(config: Config | str | Path | dict | None) -> Config:
    if config is None:
        return Config()
    if isinstance(config, Config):
        return Config.from_dict(config.to_dict())  # a copy: the run never edits the caller's
    if isinstance(config, dict):
        return Config.from_dict(config)
    return Config.from_yaml(config)


@dataclass
class _Loaded:
    """One frame and what the perception stages made of it."""

    frame: Frame
    class_ids: np.ndarray | None
    instance_ids: np.ndarray | None
    flow: np.ndarray | None
    stage_ms: dict[str, float]
    detections: Detections3D | None = None


def _lower_priority(nice: int) -> None:
    """Add ``nice`` to the calling thread's niceness (Linux threads have their own); a
    platform without per-thread niceness keeps it."""
    if nice <= 0 or not hasattr(os, "setpriority"):
        return
    try:
        tid = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, tid, os.getpriority(os.PRIO_PROCESS, tid) + nice)
    except OSError:
        pass


def _prefetched(sequence: Sequence, indices: range, labels: PanopticLabels | None,
                perception: Perception, lidar: bool = False, nice: int = 0) -> Iterator[_Loaded]:
    """Each frame with its detections, segmentation and flow; frame i+1 is read, detected and
    segmented, and its flow computed, in a background thread while the caller tracks frame i
    (the PNG decoder, OpenCV and the core all release the GIL). The detector runs once per
    frame: its boxes make the masks from boxes and feed the LiDAR fusion."""
    previous: list[Frame | None] = [None]
    previous_instances: list[np.ndarray | None] = [None]
    first_shape: list[tuple[int, int] | None] = [None]

    def load(i: int) -> _Loaded:
        start = time.perf_counter()
        # the first frame's scan also serves the "auto" disparity offset (twistslam.camera_lidar)
        frame = load_frame(sequence, i, lidar=lidar or perception.needs_lidar or i == indices[0])
        class_ids = labels.read(i) if labels is not None else None
        ms = {"load": (time.perf_counter() - start) * 1e3}
        instance_ids = flow = None
        shape = np.asarray(frame.image_left).shape[:2] if frame.image_left is not None else None
        if first_shape[0] is None:
            first_shape[0] = shape
        if shape != first_shape[0]:  # a resized frame: Slam.track names it, no stage runs
            return _Loaded(frame, None, None, None, ms)
        detections = None
        if perception.detector is not None:  # first: masks from boxes may be made of them
            start = time.perf_counter()
            detections = perception.detect(frame)
            ms["detection"] = (time.perf_counter() - start) * 1e3
        if perception.segmentation is not None:
            start = time.perf_counter()
            panoptic = perception.panoptic(frame, detections)
            if panoptic is not None:
                class_ids, instance_ids = panoptic.class_id, panoptic.instance_id
            ms["segmentation"] = (time.perf_counter() - start) * 1e3
        if perception.flow is not None:
            start = time.perf_counter()
            # the flow serves the object search: DIS runs on the box around both frames'
            # instances (DisOptions.object_region)
            flow = perception.optical_flow(previous[0], frame, (previous_instances[0], instance_ids))
            ms["flow"] = (time.perf_counter() - start) * 1e3
        previous[0], previous_instances[0] = frame, instance_ids
        return _Loaded(frame, class_ids, instance_ids, flow, ms,
                       detections if perception.fuse_detections else None)

    with ThreadPoolExecutor(max_workers=1, initializer=_lower_priority, initargs=(nice,)) as pool:
        pending = pool.submit(load, indices[0]) if len(indices) else None
        for k in range(len(indices)):
            item = pending.result()  # re-raises a loading error, naming the frame
            if k + 1 < len(indices):
                pending = pool.submit(load, indices[k + 1])
            yield item


def frame_range(config: Config, length: int) -> range:
    """Dataset frame indices a run covers (``run.start_frame``, ``run.max_frames``)."""
    start = config.run.start_frame
    if start >= length:
        raise ValueError(f"run.start_frame = {start} but the sequence has {length} frames")
    stop = length if config.run.max_frames is None else min(length, start + config.run.max_frames)
    return range(start, stop)


def run(seq_or_path: SequenceLike, config: Config | str | Path | dict | None = None,
        progress: bool = True, *, segmentation: Any = "auto", flow: Any = "auto",
        detections: Any = None, flow_weights: str | Path | None = None,
        segmentation_weights: dict | None = None, viz: bool = False,
        viz_save: str | Path | None = None, detector: Any = "auto",
        detector_weights: str | Path | None = None) -> Result:
    """Track the camera and every object cluster through a stereo sequence.

    Parameters
    ----------
    seq_or_path
        An opened sequence (e.g. :class:`~twistslam.datasets.KittiTracking`), a path into
        one (``.../training/image_02/0001``), or a ``(root, seq)`` pair.
    config
        A :class:`Config`, a YAML file of overrides, a nested dict, or ``None`` (defaults).
    progress
        Show a progress bar with the running rate in Hz.
    segmentation
        Panoptic source for the object clusters and the static / dynamic split (eq. 3):
        ``"auto"`` (the sequence's panoptic files, else masks from 3D boxes and its scans,
        else none), ``"files"``, ``"boxes"``, ``"torch"`` (with ``segmentation_weights``),
        ``"none"``, or a callable ``frame -> Panoptic`` (:mod:`twistslam.perception.run_stages`).
        The boxes are the ``detector``'s of the same frame (``Result.segmentation`` e.g.
        ``"boxes:classical"``), or with ``detector="none"`` the precomputed ``detections``
        (``"boxes:files"``).
    flow
        Optical flow source for the object search: ``"auto"`` (files, else DIS), ``"files"``,
        ``"dis"``, ``"raft"`` (with ``flow_weights``), ``"none"``, or a callable.
    detections
        Precomputed 3D detections (a file, folder or ObjectTable) for ``detector="files"`` and
        for ``segmentation="boxes"`` with ``detector="none"``; default: the sequence's
        ``detections/<name>/SEQ.txt``.
    detector
        3D detections of the LiDAR fusion of object tracking (``config.lidar_objects``:
        canonical pose, size, e_det, e_reg): ``"auto"`` (the precomputed detections when
        there are any, else the classical LiDAR detector when the sequence has scans, else
        none), ``"files"``, ``"classical"``, ``"3dssd"`` (with ``detector_weights``, a 3DSSD
        checkpoint), ``"none"``, or a callable ``frame -> Detections3D``. Only runs with a
        segmentation; its boxes also make the masks of ``segmentation="boxes"`` (then it runs
        even with ``config.lidar_objects.use_detections`` off, for the masks alone).
    flow_weights
        RAFT state-dict file for ``flow="raft"``.
    segmentation_weights
        Files of ``segmentation="torch"``: ``{"maskrcnn": FILE, "semantic": FILE}``
        (torchvision-layout state dicts; semantic optional), optionally ``"semantic_classes"``
        (:class:`twistslam.perception.TorchPanoptic`).
    viz, viz_save
        Log the run to a rerun viewer (``pip install twistslam[viz]``) / to an ``.rrd`` file.

    Returns
    -------
    Result
        Poses, per-frame status, timings, keyframes, map points and the resolved config.

    Raises
    ------
    FileNotFoundError
        A whole camera is missing (before any frame is tracked), or an image of one frame.
    ValueError
        An unreadable file, an image of the wrong size (both naming the frame), or a bad
        config value. A blank or textureless frame is not an error: it is flagged ``"lost"``,
        its pose predicted, and tracking restarts from the next good frame.
    """
    sequence = _open(seq_or_path)
    config = _config(config)
    check_stereo(sequence)
    indices = frame_range(config, len(sequence))
    check_first_frames(sequence, indices)  # resized images, identical or swapped cameras
    if isinstance(segmentation, str) and segmentation == "auto" and not config.run.use_labels:
        segmentation = "none"
    perception = perception_stages(sequence, segmentation, flow, detections=detections,
                                   flow_weights=flow_weights,
                                   segmentation_weights=segmentation_weights,
                                   detector=detector, detector_weights=detector_weights,
                                   fuse_detections=config.lidar_objects.use_detections,
                                   detector_options=detector_options(config.detection))
    if (perception.segmentation is not None and config.visual_objects.enabled
            and not config.tracking.dynamic_class_ids):
        # eq. 3: object classes track their clusters, never the camera
        config.tracking.dynamic_class_ids = list(config.visual_objects.object_class_ids)
    labels = None
    if (perception.segmentation is None and config.run.use_labels
            and config.tracking.dynamic_class_ids):
        # only worth reading when some classes are masked
        labels = PanopticLabels.find(sequence, config.run.labels_dir)
        if labels is None:
            warnings.warn(f"{sequence}: tracking.dynamic_class_ids is set but the sequence has "
                          f"no {config.run.labels_dir}/ labels; frames are tracked unmasked",
                          stacklevel=2)
    slam = Slam(config, sequence.calib)
    name = getattr(sequence, "seq", None)

    viewer = None
    if viz or viz_save is not None:
        from .viz.run_logger import RunViewer

        viewer = RunViewer(sequence, spawn=viz, save=viz_save,
                           box_rules=CameraBoxRules.from_config(config),
                           road_class_id=config.visual_objects.road_class_id)
    tracked, stages, frame_ms = [], [], []
    with RateBar(len(indices), f"seq {name}" if name else "run", enabled=progress) as bar:
        last = time.perf_counter()
        # the scans serve keypoint depth and the registration of object scans (e_reg)
        lidar = config.lidar.use_depth or (perception.fuse_detections
                                           and config.lidar_objects.use_registration)
        for item in _prefetched(sequence, indices, labels, perception, lidar=lidar,
                                nice=config.run.loader_nice):
            out = slam.track(item.frame, item.class_ids, instances=item.instance_ids,
                             flow=item.flow, detections=item.detections)
            now = time.perf_counter()
            frame_ms.append((now - last) * 1e3)
            last = now
            stages.append({**item.stage_ms, **out.timings_ms})
            tracked.append(out)
            bar.step(frame_ms[-1], out.status)
            if viewer is not None:
                viewer.log(item, out, slam)
    if viewer is not None:
        viewer.close()
    after_loop_ms = {}
    if perception.segmentation is not None and config.visual_objects.enabled and tracked:
        # once, after the last frame, outside the per-frame loop (timed apart from it); without
        # final_smoothing it only takes the output's LiDAR verdicts again on the final poses and
        # whole tracks (see-through boxes, tracks nearer than the LiDAR sees them)
        start = time.perf_counter()
        slam.smooth_objects()
        step = "object_smoothing" if config.visual_objects.final_smoothing else "object_verdicts"
        after_loop_ms[step] = (time.perf_counter() - start) * 1e3

    tracked_poses = np.stack([t.T_w_c for t in tracked])
    frames = [t.index for t in tracked]
    camera_poses = _refined(slam.trajectory(), frames, tracked_poses)
    camera_poses = dict(zip(frames, camera_poses))
    return Result(
        camera_poses=np.stack([camera_poses[f] for f in frames]),
        tracked_poses=tracked_poses,
        status=np.array([t.status for t in tracked]),
        frames=np.array([t.index for t in tracked], dtype=np.int64),
        is_keyframe=np.array([t.is_keyframe for t in tracked], dtype=bool),
        num_inliers=np.array([t.num_inliers for t in tracked], dtype=np.int64),
        timings=dataclasses.replace(Timings.from_frames(stages, frame_ms), after_loop_ms=after_loop_ms),
        keyframes=slam.keyframes(),
        disparity_offset=slam.disparity_offset,
        disparity_offset_source=slam.disparity_offset_source,
        map_points=slam.map_points(),
        config=config,
        seq=name,
        objects=(visual_objects(slam.objects(), sequence, camera_poses, period=_period(sequence),
                                box_rules=CameraBoxRules.from_config(config))
                 if perception.segmentation is not None else None),
        segmentation=perception.segmentation_name,
        flow=perception.flow_name,
        detector=perception.detector_name if perception.fuse_detections else "none",
    )


def _refined(trajectory: dict | None, frames: list[int], tracked: np.ndarray) -> np.ndarray:
    """The core's final trajectory (poses after bundle adjustment) in the run's frame order;
    frames it does not hold keep their tracked pose."""
    poses = tracked.copy()
    if trajectory is None:
        return poses
    row = {int(f): k for k, f in enumerate(trajectory["frame_index"])}
    for k, f in enumerate(frames):
        if f in row and np.isfinite(trajectory["T_w_c"][row[f]]).all():
            poses[k] = trajectory["T_w_c"][row[f]]
    return poses


def _period(sequence: Sequence) -> float:
    """Seconds between frames (KITTI's 10 Hz unless the sequence says otherwise)."""
    return float(getattr(sequence, "period", 0.1) or 0.1)
