"""Surface properties at ray hits: dispatch of every hit to its material."""

from __future__ import annotations

import numpy as np

from . import car_material, materials
from .raycast import GROUP, OBJECT, Hits, interpolate
from .world import World


def object_local(world: World, hits: Hits, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Hit points and normals of object hits in each object's vehicle frame at state ``n``."""
    T = world.traj.T_m_v[hits.agent, n]
    R, t = T[:, :3, :3], T[:, :3, 3]
    X = np.einsum("nji,nj->ni", R, hits.point - t)
    N = np.einsum("nji,nj->ni", R, hits.normal)
    return X, N


def surface(world: World, hits: Hits, n: int, fp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Albedo (N, 3) float32 linear RGB and LiDAR reflectivity (N,) of every hit (misses: 0)."""
    N = len(hits.t)
    albedo = np.zeros((N, 3), np.float32)
    reflect = np.zeros(N, np.float32)
    tex, static = world.textures, world.static_scene
    for name, code in GROUP.items():
        idx = np.flatnonzero(hits.group == code)
        if len(idx) == 0:
            continue
        f = fp[idx]
        mesh = static.mesh_of_group.get(code)
        if mesh is not None and mesh.attrs.shape[1]:
            attrs = interpolate(mesh, hits.prim[idx], hits.uv[idx])
            P = None
        else:
            attrs, P = None, hits.point[idx]
        if name == "road":
            a, r = materials.road(tex, world.net, attrs, f)
        elif name == "sidewalk":
            a, r = materials.sidewalk(tex, attrs, f, world.cfg.street.curb_height)
        elif name == "terrain":
            a, r = materials.terrain(tex, P, f)
        elif name == "wall":
            a, r = materials.wall(tex, world.facade_params, attrs, f)
        elif name == "roof":
            a, r = materials.roof(tex, attrs, f)
        elif name == "trunk":
            a, r = materials.trunk(tex, P, f)
        elif name == "canopy":
            a, r = materials.canopy(tex, P, f)
        elif name == "sign":
            a, r = materials.sign(tex, attrs, f)
        else:  # pole, rail
            a, r = materials.metal(tex, P, f, 0.32 if name == "pole" else 0.45)
        albedo[idx], reflect[idx] = a, r
    m = hits.group == OBJECT
    if m.any():
        sub, f = hits.select(m), fp[m]
        X, Nv = object_local(world, sub, n)
        cars = world.is_car[sub.agent]
        a = np.zeros((len(f), 3), np.float32)
        r = np.zeros(len(f), np.float32)
        if cars.any():
            a[cars], r[cars] = car_material.car(tex, world.car_table, sub.agent[cars], sub.prim[cars], X[cars],
                                                Nv[cars], f[cars])
        people = ~cars
        if people.any():
            a[people], r[people] = car_material.person(tex, world.heights, world.colours, sub.agent[people],
                                                       X[people], f[people])
        albedo[m], reflect[m] = a, r
    return albedo, reflect
