"""Velodyne HDL-64E model: 64 beams in two blocks (as the real sensor: finer spacing in the
upper block), a full turn of azimuth steps, range noise, dropouts and an intensity from the
material reflectivity and the incidence angle. The scan is instantaneous at the frame time
(no rolling-shutter motion distortion), mounted with the calibration's ``Tr_velo_to_cam``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .config import LidarConfig
from .mesh import rotate
from .objects import MovingObjects
from .raycast import GROUP, OBJECT, cast
from .shading import surface
from .world import World

BEAM_DIVERGENCE = 0.002  # rad; sets the footprint used for texture filtering
UPPER_SHARE = 0.385  # fraction of the field of view covered by the 32 upper beams (HDL-64E)

#: SemanticKITTI label ids of the material groups (lower 16 bits of a .label entry)
SEMANTIC_KITTI = {"terrain": 72, "road": 40, "sidewalk": 48, "wall": 50, "roof": 50, "trunk": 71,
                  "canopy": 70, "pole": 80, "sign": 81, "rail": 51, "car": 10, "person": 30}


@dataclass
class Scan:
    points: np.ndarray  # (M, 4) float32 x y z intensity in the LiDAR frame
    labels: np.ndarray  # (M,) uint32 SemanticKITTI: semantic | instance << 16 (instance = track + 1)
    agent: np.ndarray  # (M,) int32 agent index of object points, -1 otherwise


class Lidar:
    def __init__(self, cfg: LidarConfig) -> None:
        self.cfg = cfg
        span = cfg.elevation_max - cfg.elevation_min
        elevation = np.concatenate([
            np.linspace(cfg.elevation_max, cfg.elevation_max - UPPER_SHARE * span, 32),
            np.linspace(cfg.elevation_max - (UPPER_SHARE + 0.02) * span, cfg.elevation_min, 32),
        ])
        azimuth = np.radians(np.arange(0.0, 360.0, cfg.azimuth_step))
        el, az = np.meshgrid(np.radians(elevation), azimuth, indexing="ij")
        # the ray grid, for finding the rays that may hit an object (row-major (beam, azimuth))
        self.elevation, self.azimuth_step = np.radians(elevation), np.radians(cfg.azimuth_step)
        self.n_azimuth = len(azimuth)
        self.dirs = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1).reshape(-1, 3)
        self.dirs32 = self.dirs.astype(np.float32)

    def scan(self, world: World, objects: MovingObjects, n: int, rng: np.random.Generator) -> Scan:
        cfg = self.cfg
        T = world.T_m_c[n] @ world.T_c_velo
        dirs = rotate(self.dirs32, T[:3, :3].astype(np.float32))  # the ray caster takes float32
        origins = np.broadcast_to(T[:3, 3], dirs.shape)
        candidates = objects.grid_candidates(T, self.elevation, self.azimuth_step, self.n_azimuth)
        hits = cast(world.static_scene, objects, origins, dirs, candidates)
        keep = np.isfinite(hits.t) & (hits.t > cfg.min_range) & (hits.t < cfg.max_range)
        idx = np.flatnonzero(keep)
        sub = hits.select(keep)
        _, reflect = surface(world, sub, n, sub.t * BEAM_DIVERGENCE, colour=False)  # no textures needed
        u = rng.uniform(size=(2, len(idx)))
        alive = (u[0] >= cfg.dropout) & ~((reflect < 0.06) & (u[1] < cfg.glass_dropout))
        # Gaussian range noise truncated at 2 sigma: the HDL-64E's "< 2 cm (1 sigma)" accuracy
        # without the unbounded tails that would put points far off their surface
        t = sub.t + cfg.range_noise * np.clip(rng.normal(size=len(idx)), -2.0, 2.0)
        cos = np.abs(np.einsum("ij,ij->i", sub.normal, dirs[idx]))
        intensity = np.round(np.clip(reflect * (0.35 + 0.65 * cos), 0, 1), 2)
        xyz = self.dirs[idx] * t[:, None]
        points = np.concatenate([xyz, intensity[:, None]], 1)[alive].astype(np.float32)
        group, agent = sub.group[alive], sub.agent[alive]
        semantic = np.zeros(len(group), dtype=np.uint32)
        for name, code in GROUP.items():
            semantic[group == code] = SEMANTIC_KITTI[name]
        obj = group == OBJECT
        semantic[obj] = np.where(world.is_car[agent[obj]], SEMANTIC_KITTI["car"], SEMANTIC_KITTI["person"])
        instance = np.where(obj, world.track_id[np.maximum(agent, 0)] + 1, 0).astype(np.uint32)
        return Scan(points, semantic | (instance << np.uint32(16)), np.where(obj, agent, -1).astype(np.int32))
