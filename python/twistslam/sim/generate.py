"""``twistslam.sim.generate``: build the world, render every frame, write every file."""

from __future__ import annotations

import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from twistslam.datasets import ObjectTable

from . import extras
from .camera_render import Camera, render
from .config import MAX_FRAMES, SimConfig, check_camera
from .labels import frame_labels
from .lidar import Lidar
from .scenario import scenario_config
from .world import World
from .writer import SequenceWriter

FRAME_STREAMS = {"left": 11, "right": 12, "lidar": 13, "oracle": 14}


def generate(out: str | Path, scenario: str = "urban", frames: int = 100, seed: int = 0, seq: str | int = "0000",
             calib_path: str | Path | None = None, overwrite: bool = False, width: int | None = None,
             height: int | None = None, progress: bool = True, **overrides: Any) -> Path:
    """Write a synthetic sequence in the KITTI tracking layout under ``out/training``.

    Parameters
    ----------
    out
        Output root (refused if it exists and is not empty, unless ``overwrite``; then only
        this sequence's files are replaced).
    scenario
        One of :data:`twistslam.sim.SCENARIOS`.
    frames, seed, seq
        Number of frames (> 0), random seed (same seed -> byte-identical files), sequence name.
    calib_path
        KITTI calibration file (default: KITTI tracking training sequence 0000).
    width, height
        Image size (default 1242 x 375); the calibration is scaled to it.
    progress
        Show a progress bar while rendering.
    overrides
        Settings of :class:`SimConfig`: ``lidar__range_noise=0.05``, ``"lidar.range_noise": 0.05``
        or ``lidar={"range_noise": 0.05}``.

    Returns
    -------
    Path
        ``out`` (open it with ``KittiTracking(out, seq)``).
    """
    if int(frames) <= 0:
        raise ValueError(f"frames must be positive, got {frames}")
    if int(frames) > MAX_FRAMES:
        raise ValueError(f"frames (--frames) = {frames}: at most {MAX_FRAMES}")
    seq = f"{int(seq):04d}" if isinstance(seq, int) or str(seq).isdigit() else str(seq)
    if not re.fullmatch(r"\d{4}", seq):
        raise ValueError(f"seq must be a 4-digit sequence number such as 0000, got {seq!r}")
    cfg = scenario_config(scenario, **overrides)
    cfg.frames, cfg.seed, cfg.seq = int(frames), int(seed), seq
    if calib_path is not None:
        cfg.camera.calib_path = str(calib_path)
    if width is not None:
        cfg.camera.width = int(width)
    if height is not None:
        cfg.camera.height = int(height)
    return run(cfg, out, overwrite=overwrite, progress=progress)


def _rng(cfg: SimConfig, stream: str, n: int) -> np.random.Generator:
    return np.random.default_rng([cfg.seed, FRAME_STREAMS[stream], n])


def run(cfg: SimConfig, out: str | Path, overwrite: bool = False, progress: bool = True) -> Path:
    """Generate the sequence described by ``cfg`` (see :func:`generate`)."""
    check_camera(cfg.camera)  # before anything is written or allocated
    writer = SequenceWriter(out, cfg.seq, overwrite, cfg.output.png_compression)
    world = World(cfg)
    left = Camera(world.calib.P2, world.width, world.height)
    right = Camera(world.calib.P3, world.width, world.height)
    lidar = Lidar(cfg.lidar) if cfg.lidar.enabled else None
    shape = (world.height, world.width)
    tables, detections, object_poses = [], [], []
    frames = range(cfg.frames)
    if progress:
        from tqdm import tqdm

        frames = tqdm(frames, desc=f"sim {cfg.scenario} {cfg.seq}", unit="frame")
    # files are encoded and written by one background thread (zlib releases the GIL),
    # overlapping with the rendering of the next frame; each file's bytes are unchanged
    pool = ThreadPoolExecutor(max_workers=1)
    renderer = ThreadPoolExecutor(max_workers=1)
    pending = []

    def later(fn, *args) -> None:
        pending.append(pool.submit(fn, *args))

    def write_flow(n: int, hits, objects_next, hits_next) -> None:
        fl, occ, noc = extras.flow(world, left, hits, n, objects_next, hits_next)
        later(writer.png16, "flow_occ", n, extras.encode_flow(fl, occ))
        later(writer.png16, "flow_noc", n, extras.encode_flow(fl, noc))

    flow_wait = None  # (frame, its hits, frame + 1's moving objects) of the flow still to write
    objects_next = world.moving_objects(0)
    for n in frames:
        objects, objects_next = objects_next, world.moving_objects(n + 1)
        # the right image and the LiDAR scan render in a second thread while this one does
        # the left image and its ground truth (numpy and Open3D release the GIL)
        right_job = renderer.submit(render, world, right, objects, n, _rng(cfg, "right", n))
        if lidar is not None:
            lidar_job = renderer.submit(lidar.scan, world, objects, n, _rng(cfg, "lidar", n))
        image, hits = render(world, left, objects, n, _rng(cfg, "left", n))
        later(writer.image, "image_02", n, image)
        labels = frame_labels(world, left, hits, n)
        tables.append(labels)
        if cfg.output.panoptic:
            later(writer.png16, "panoptic", n, extras.panoptic(world, hits, shape))
        if cfg.output.disparity:
            later(writer.png16, "disparity", n, extras.encode_disparity(extras.disparity(world, left, right, hits, n)))
        if cfg.output.flow:
            # frame n-1's flow is finished now: its visibility in frame n is read from this
            # frame's hits (depth and surfaces), with rays only where that is ambiguous
            if flow_wait is not None:
                write_flow(*flow_wait, hits)
            flow_wait = (n, hits, objects_next)
        later(writer.image, "image_03", n, right_job.result()[0])
        counts = np.zeros(len(world.agents), dtype=np.int64)
        if lidar is not None:
            scan = lidar_job.result()
            later(writer.scan, n, scan.points, scan.labels if cfg.output.lidar_labels else None)
            counts = np.bincount(scan.agent[scan.agent >= 0], minlength=len(world.agents))
        if cfg.oracle.enabled:
            detections += extras.oracle_detections(world, labels, counts, left, cfg.oracle, _rng(cfg, "oracle", n), n)
        object_poses += _object_pose_lines(world, n)
        pending = [f for f in pending if not f.done() or f.result() is not None]  # raise early
    if flow_wait is not None:
        write_flow(*flow_wait, None)  # the last frame's visibility: rays only
    for f in pending:
        f.result()
    pool.shutdown()
    renderer.shutdown()
    writer.sequence(world.calib, world.T_w_c[: cfg.frames], ObjectTable.concat(tables), object_poses, cfg)
    if cfg.oracle.enabled:
        writer.detections(detections)
    if cfg.output.meshes:
        writer.meshes(_mesh_entries(world))
    return Path(out)


def _object_pose_lines(world: World, n: int) -> list[str]:
    """``frame track_id class l w h`` + row-major 3x4 ``T_w_o`` of every tracked object."""
    T_w_m = np.linalg.inv(world.T_m_c[0])
    lines = []
    for a in np.flatnonzero(world.near[:, n] & (world.track_id >= 0)):
        T = T_w_m @ world.traj.T_m_o[a, n]
        cls = "Car" if world.is_car[a] else "Pedestrian"
        size = world.agents[a].size
        values = " ".join(f"{v:.9f}" for v in (*size, *T[:3].ravel()))
        lines.append(f"{n} {world.track_id[a]} {cls} {values}")
    return lines


def _mesh_entries(world: World) -> list[tuple[int, str, object, dict]]:
    entries = []
    for a in np.flatnonzero(world.track_id >= 0):
        agent = world.agents[a]
        cls = "Car" if world.is_car[a] else "Pedestrian"
        params = agent.shape.to_dict()
        params["moving"] = bool(world.moving[a])
        entries.append((int(world.track_id[a]), cls, world.meshes[a], params))
    return entries
