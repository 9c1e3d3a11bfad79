"""Ground-truth extras of the left image: panoptic ids, disparity, forward optical flow, and
noisy 'oracle' 3D detections. Formats are documented in docs/sim.md."""

from __future__ import annotations

import numpy as np

from twistslam.datasets import ObjectTable
from twistslam.geometry import project_boxes

from .camera_render import Camera
from .config import OracleConfig
from .mesh import rotate
from .raycast import GROUP, OBJECT, Hits, ObjectScene, occluded
from .world import World

#: Cityscapes label ids of the material groups (and of things / sky)
CITYSCAPES = {"road": 7, "sidewalk": 8, "wall": 11, "roof": 11, "rail": 14, "pole": 17, "sign": 20,
              "canopy": 21, "trunk": 21, "terrain": 22, "sky": 23, "person": 24, "car": 26}
FLOW_SCALE = 64.0  # KITTI flow PNG: value = flow * 64 + 2^15
DISPARITY_SCALE = 256.0  # KITTI disparity PNG: value = disparity * 256, 0 = invalid


def panoptic(world: World, hits: Hits, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) uint16 Cityscapes ``instanceIds`` encoding: stuff = class id, things =
    class id * 1000 + track id + 1."""
    out = np.full(len(hits.t), CITYSCAPES["sky"], dtype=np.uint16)
    for name, code in GROUP.items():
        out[hits.group == code] = CITYSCAPES[name]
    obj = hits.group == OBJECT
    a = hits.agent[obj]
    cls = np.where(world.is_car[a], CITYSCAPES["car"], CITYSCAPES["person"])
    out[obj] = cls * 1000 + world.track_id[a] + 1
    return out.reshape(shape)


def disparity(world: World, left: Camera, right: Camera, hits: Hits, n: int) -> np.ndarray:
    """(H, W) float64 disparity u_left - u_right of the surface seen at each pixel (0 = sky)."""
    X_c = _to_camera(world, hits.point, n)
    uv_r, _ = right.project(X_c)
    u = np.tile(np.arange(left.width, dtype=np.float64), left.height)
    d = np.where(np.isfinite(hits.t), u - uv_r[:, 0], 0.0)
    return d.reshape(left.height, left.width)


def _to_camera(world: World, X_m: np.ndarray, n: int) -> np.ndarray:
    return rotate(X_m - world.T_m_c[n, :3, 3], world.T_m_c[n, :3, :3].T)


def flow(world: World, camera: Camera, hits: Hits, n: int, next_objects: list[ObjectScene]):
    """Forward flow (H, W, 2) of the left image from frame n to n+1, ``valid_occ`` (every
    pixel with a surface in front of camera n+1) and ``valid_noc`` (also inside image n+1 and
    not hidden there)."""
    H, W = camera.height, camera.width
    hit = np.isfinite(hits.t)
    X = hits.point.copy()
    obj = np.flatnonzero(hits.group == OBJECT)
    if len(obj):
        a = hits.agent[obj]
        T_rel = world.traj.T_m_o[a, n + 1] @ np.linalg.inv(world.traj.T_m_o[a, n])
        X[obj] = np.einsum("nij,nj->ni", T_rel[:, :3, :3], X[obj]) + T_rel[:, :3, 3]
    uv1, z1 = camera.project(_to_camera(world, X, n + 1))
    v0, u0 = np.divmod(np.arange(H * W), W)
    fl = uv1 - np.stack([u0, v0], -1)
    valid_occ = hit & (z1 > 0.1)
    inside = (uv1[:, 0] > -0.5) & (uv1[:, 0] < W - 0.5) & (uv1[:, 1] > -0.5) & (uv1[:, 1] < H - 0.5)
    check = np.flatnonzero(valid_occ & inside)
    T = world.T_m_c[n + 1]
    origin = T[:3, :3] @ camera.centre + T[:3, 3]
    ray = X[check] - origin
    dist = np.linalg.norm(ray, axis=1)
    hidden = occluded(world.static_scene, next_objects, np.broadcast_to(origin, ray.shape), ray / dist[:, None],
                      dist * 0.997 - 0.02)
    valid_noc = np.zeros(H * W, bool)
    valid_noc[check[~hidden]] = True
    return fl.reshape(H, W, 2), valid_occ.reshape(H, W), valid_noc.reshape(H, W)


def encode_flow(fl: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """KITTI flow PNG channels (H, W, 3) uint16: u*64+2^15, v*64+2^15, valid."""
    v = np.clip(np.rint(fl * FLOW_SCALE + 2**15), 0, 2**16 - 1).astype(np.uint16)
    out = np.dstack([v, valid.astype(np.uint16)])
    out[~valid, :2] = 0
    return out


def encode_disparity(d: np.ndarray) -> np.ndarray:
    """KITTI disparity PNG (H, W) uint16: d*256, 0 where invalid (sky, d <= 0)."""
    ok = (d > 0) & (d < 255.99)
    return np.where(ok, np.clip(np.rint(d * DISPARITY_SCALE), 1, 2**16 - 1), 0).astype(np.uint16)


def oracle_detections(world: World, labels: ObjectTable, lidar_counts: np.ndarray, camera: Camera,
                      cfg: OracleConfig, rng: np.random.Generator, n: int) -> list[str]:
    """PointRCNN-format lines ``frame, type, x1, y1, x2, y2, score, h, w, l, x, y, z, ry, alpha``
    for the labelled objects of frame ``n`` (with noise and misses) plus false positives."""
    rows = []
    agents = {int(t): a for a, t in enumerate(world.track_id) if t >= 0}
    for i in range(len(labels)):
        a = agents[int(labels.track_id[i])]
        u = rng.uniform(size=4)
        noise = rng.normal(size=6)
        if lidar_counts[a] < cfg.min_points or u[0] < cfg.miss_rate:
            continue
        b = labels.box_3d[i].copy()
        dist = np.hypot(b[0], b[2])
        b[:3] += noise[:3] * cfg.center_noise * max(dist, 5.0) / 10.0 * np.array([1.0, 0.3, 1.0])
        b[3:6] *= 1.0 + cfg.size_noise * noise[3:6].clip(-3, 3)
        b[6] += cfg.yaw_noise * rng.normal() + (np.pi if u[1] < cfg.yaw_flip_rate else 0.0)
        score = rng.normal(*cfg.score_true) - 0.04 * dist
        rows.append((2 if labels.cls[i] == "Car" else 1, b, score))
    for _ in range(rng.poisson(cfg.false_positive_rate)):
        z = rng.uniform(6.0, 45.0)
        b = np.array([rng.uniform(-0.4, 0.4) * z, 1.65 - 0.75, z, rng.uniform(3.5, 4.6), rng.uniform(1.5, 1.8),
                      rng.uniform(1.4, 1.6), rng.uniform(-np.pi, np.pi)])
        rows.append((2, b, rng.normal(*cfg.score_false)))
    lines = []
    for cls, b, score in rows:
        box2d = project_boxes(b[None], camera.P, camera.width, camera.height)[0]
        if box2d[2] <= box2d[0] or box2d[3] <= box2d[1]:
            continue
        ry = np.arctan2(np.sin(b[6]), np.cos(b[6]))
        alpha = np.arctan2(np.sin(ry - np.arctan2(b[0], b[2])), np.cos(ry - np.arctan2(b[0], b[2])))
        values = [*box2d, score, b[5], b[4], b[3], b[0], b[1] + b[5] / 2, b[2], ry, alpha]
        lines.append(f"{n},{cls}," + ",".join(f"{v:.4f}" for v in values))
    return lines
