"""Ground-truth extras of the left image: panoptic ids, disparity, forward optical flow, and
noisy 'oracle' 3D detections. Formats are documented in docs/sim.md."""

from __future__ import annotations

import numpy as np

from twistslam.datasets import ObjectTable
from twistslam.geometry import project_boxes

from .camera_render import Camera
from .config import OracleConfig
from .objects import MovingObjects
from .raycast import GROUP, OBJECT, Hits, occluded
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
    """(H, W) float64 disparity u_left - u_right of the surface seen at each pixel (0 = sky).

    The point seen at a pixel is ``left.centre + t d`` in the reference frame (``t`` along the
    pixel's unit ray ``d``), so its right-image projection is ``a + t (P3 d)`` with ``P3 d``
    fixed for the sequence: no per-frame change of frame for every pixel."""
    hit = np.isfinite(hits.t)
    x = left.projected_directions(right.P) * np.where(hit, hits.t, 0.0)[:, None]
    x += right.P[:, :3] @ left.centre + right.P[:, 3]
    with np.errstate(divide="ignore", invalid="ignore"):  # sky pixels: masked below
        return np.where(hit, left.pixel_centres()[:, 0] - x[:, 0] / x[:, 2], 0.0).reshape(left.height, left.width)


def flow(world: World, camera: Camera, hits: Hits, n: int, next_objects: MovingObjects,
         next_hits: Hits | None = None):
    """Forward flow (H, W, 2) of the left image from frame n to n+1, ``valid_occ`` (every
    pixel with a surface in front of camera n+1) and ``valid_noc`` (also inside image n+1 and
    not hidden there). ``next_hits``, the pixel-centre hits of frame n+1's left image, spare
    most of the visibility rays (see :func:`_hidden`)."""
    H, W = camera.height, camera.width
    hit = np.isfinite(hits.t)
    X = hits.point
    obj = np.flatnonzero(hits.group == OBJECT)
    if len(obj):
        X = X.copy()
        # each object's motion from n to n+1, once per object (not once per pixel)
        a = hits.agent[obj]
        present = np.bincount(a, minlength=len(world.agents)) > 0
        agents, which = np.flatnonzero(present), (np.cumsum(present) - 1)[a]
        T_rel = world.traj.T_m_o[agents, n + 1] @ np.linalg.inv(world.traj.T_m_o[agents, n])
        X[obj] = np.einsum("nij,nj->ni", T_rel[which, :3, :3], X[obj]) + T_rel[which, :3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):  # sky pixels (no hit): not valid below
        uv1, z1 = camera.project_map(X, world.T_m_c[n + 1])
    fl = uv1 - camera.pixel_centres()
    valid_occ = hit & (z1 > 0.1)
    inside = (uv1[:, 0] > -0.5) & (uv1[:, 0] < W - 0.5) & (uv1[:, 1] > -0.5) & (uv1[:, 1] < H - 0.5)
    check = valid_occ & inside
    hidden = _hidden(world, camera, n + 1, next_objects, next_hits, X, uv1, z1, _surface_id(hits), check)
    valid_noc = check & ~hidden
    return fl.reshape(H, W, 2), valid_occ.reshape(H, W), valid_noc.reshape(H, W)


def _surface_id(hits: Hits) -> np.ndarray:
    """One integer per hit naming its surface: material group, or the object it belongs to."""
    return hits.group.astype(np.int32) * 1024 + hits.agent + 1


def _hidden(world: World, camera: Camera, m: int, objects: MovingObjects, hits_m: Hits | None,
            X: np.ndarray, uv: np.ndarray, z: np.ndarray, surface: np.ndarray, check: np.ndarray) -> np.ndarray:
    """Whether something lies between camera ``m`` and map points ``X`` (projected at ``uv``
    with depth ``z``, on surface ``surface``) where ``check``, ignoring hits within 0.3 % +
    2 cm of the point.

    Where the four pixel centres around ``uv`` in frame m's hits ``hits_m`` all see the point's
    own surface at the point's depth (inverse depth, linear across a plane, interpolated), the
    point is visible; where all four see something well in front of it, it is hidden. Only the
    rest (occlusion edges, surface borders) are tested with a ray from camera m to the point:
    the same answer as rays everywhere, except for occluders thinner than a pixel."""
    H, W = camera.height, camera.width
    hidden = np.zeros(len(X), bool)
    todo = check
    if hits_m is not None:
        u, v = uv[:, 0], uv[:, 1]
        g = np.flatnonzero(check & (u >= 0) & (u <= W - 1) & (v >= 0) & (v <= H - 1))
        ug, vg = u[g], v[g]
        x0 = np.minimum(ug.astype(np.int32), W - 2)  # u, v >= 0: truncation is the floor
        y0 = np.minimum(vg.astype(np.int32), H - 2)
        fx, fy = (ug - x0).astype(np.float32), (vg - y0).astype(np.float32)
        corner = y0 * W + x0
        with np.errstate(divide="ignore"):  # the sky: 1 / inf = 0
            inv_depth = (1.0 / (hits_m.t * camera.directions()[:, 2])).astype(np.float32)
        ids, sg = _surface_id(hits_m), surface[g]
        inv = [inv_depth[corner + k] for k in (0, 1, W, W + 1)]
        inv_at = (inv[0] * (1 - fx) + inv[1] * fx) * (1 - fy) + (inv[2] * (1 - fx) + inv[3] * fx) * fy
        same = ids[corner] == sg
        for k in (1, W, W + 1):
            same &= ids[corner + k] == sg
        limit = 0.997 * z[g] - 0.02  # nearer hits hide the point (the ray test's tolerance)
        visible = same & (inv_at * limit <= 1.0)
        in_front = np.minimum(np.minimum(inv[0], inv[1]), np.minimum(inv[2], inv[3])) * (0.99 * limit) > 1.0
        hidden[g[in_front & ~visible]] = True
        todo = check.copy()
        todo[g[visible | in_front]] = False
    todo = np.flatnonzero(todo)
    if len(todo) == 0:
        return hidden
    T = world.T_m_c[m]
    origin = T[:3, :3] @ camera.centre + T[:3, 3]
    ray = X[todo] - origin
    dist = np.linalg.norm(ray, axis=1)
    hidden[todo] = occluded(world.static_scene, objects, np.broadcast_to(origin, ray.shape), ray / dist[:, None],
                            dist * 0.997 - 0.02, objects.point_candidates(camera.P, T, uv[todo]))
    return hidden


def encode_flow(fl: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """KITTI flow PNG channels (H, W, 3) uint16: u*64+2^15, v*64+2^15, valid."""
    # NaN where nothing was hit (sky): such pixels are never valid, and zeroed below
    v = np.clip(np.rint(np.where(valid[..., None], fl, 0.0) * FLOW_SCALE + 2**15), 0, 2**16 - 1).astype(np.uint16)
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
