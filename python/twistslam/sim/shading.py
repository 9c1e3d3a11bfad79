"""Surface properties at ray hits: dispatch of every hit to its material."""

from __future__ import annotations

import numpy as np

from . import car_material, facade, materials
from .raycast import GROUP, OBJECT, Hits, interpolate
from .world import World


CONSTANT_PERSON = 0.3  # pedestrians' reflectivity


def object_local(world: World, hits: Hits, n: int, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hit points and normals of object hits ``idx`` in each object's vehicle frame at state ``n``."""
    # the poses of the objects present, then one small table gather per hit (gathering 4x4
    # poses per hit from the (agents, frames) table, and mixed-precision einsums, cost 3x more)
    a = hits.agent[idx]
    present = np.bincount(a, minlength=len(world.agents)) > 0
    which = (np.cumsum(present) - 1)[a]
    T = world.traj.T_m_v[np.flatnonzero(present), n]
    R = T[:, :3, :3][which]
    X = np.einsum("nji,nj->ni", R, hits.point[idx] - T[which, :3, 3])
    N = np.einsum("nji,nj->ni", R.astype(np.float32), hits.normal[idx])
    return X, N


#: reflectivity of the materials whose reflectivity is one constant (the LiDAR skips their
#: colour evaluation)
CONSTANT_REFLECT = {"sidewalk": 0.25, "terrain": 0.35, "roof": 0.2, "trunk": 0.3, "canopy": 0.45,
                    "pole": 0.5, "rail": 0.5, "sign": 0.9}


def surface(world: World, hits: Hits, n: int, fp: np.ndarray, colour: bool = True
            ) -> tuple[np.ndarray | None, np.ndarray]:
    """Albedo (N, 3) float32 linear RGB and LiDAR reflectivity (N,) of every hit (misses: 0).
    With ``colour=False`` only the reflectivity is computed (albedo None): the LiDAR needs no
    textures, and most materials' reflectivity is a constant."""
    N = len(hits.t)
    albedo = np.zeros((N, 3), np.float32) if colour else None
    reflect = np.zeros(N, np.float32)
    tex, static = world.textures, world.static_scene
    for name, code in GROUP.items():
        idx = np.flatnonzero(hits.group == code)
        if len(idx) == 0:
            continue
        if not colour and name in CONSTANT_REFLECT:
            reflect[idx] = CONSTANT_REFLECT[name]
            continue
        f = fp[idx]
        if code in static.face_attrs:
            attrs = interpolate(static.face_attrs[code], hits.prim[idx], hits.uv[idx])
            P = None
        else:
            attrs, P = None, hits.point[idx]
        if name == "road":
            a, r = materials.road(tex, world.net, attrs, f, colour)
        elif name == "sidewalk":
            a, r = materials.sidewalk(tex, attrs, f, world.cfg.street.curb_height)
        elif name == "terrain":
            a, r = materials.terrain(tex, P, f)
        elif name == "wall":
            a, r = facade.wall(tex, world.facade_params, attrs, f, colour)
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
        reflect[idx] = r
        if colour:
            albedo[idx] = a
    m = np.flatnonzero(hits.group == OBJECT)
    if len(m):
        sub, f = hits.select(m), fp[m]
        cars = world.is_car[sub.agent]
        r = np.full(len(f), CONSTANT_PERSON, np.float32)
        a = np.zeros((len(f), 3), np.float32) if colour else None
        if cars.any():
            c = np.flatnonzero(cars)
            X, Nv = object_local(world, sub, n, c)
            ac, r[c] = car_material.car(tex, world.car_table, sub.agent[c], sub.prim[c], X, Nv, f[c], colour)
            if colour:
                a[c] = ac
        if colour and not cars.all():
            p = np.flatnonzero(~cars)
            X, _ = object_local(world, sub, n, p)
            a[p], r[p] = car_material.person(tex, world.heights, world.colours, sub.agent[p], X, f[p])
        reflect[m] = r
        if colour:
            albedo[m] = a
    return albedo, reflect
