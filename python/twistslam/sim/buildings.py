"""Static street furniture: buildings (textured by facade parameters), trees, poles with
signs, guard rails. Each builder returns meshes in the map frame plus the per-instance
parameters the materials need."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .config import SideConfig
from .mesh import Mesh, box, cylinder, ring_loft
from .road import Street, StreetNetwork, intervals
from .terrain import Terrain


@dataclass
class StaticMeshes:
    """Map-frame meshes of one material group each."""

    walls: Mesh  # attrs (u, v, building, 0): u along the facade, v above the sidewalk (m)
    roofs: Mesh  # attrs (u, v, building, 1)
    trunks: Mesh
    canopies: Mesh
    poles: Mesh
    signs: Mesh  # attrs (u, v, sign index, 0) on the panel face
    rails: Mesh
    facade_params: np.ndarray  # (B, 8) per building, see FACADE_COLUMNS


#: columns of ``facade_params``
FACADE_COLUMNS = ("floor_h", "pitch", "win_w", "win_h", "hue", "brick", "shop", "seed")


def _building(front0: np.ndarray, front1: np.ndarray, outward: np.ndarray, depth: float, base: float,
              height: float, index: int, street_level: float) -> tuple[Mesh, Mesh]:
    """Box on the front edge ``front0 -> front1`` extruded by ``depth`` along ``outward``."""
    along = front1 - front0
    width = float(np.linalg.norm(along))
    ex = along / width
    T = np.eye(4)
    T[:3, 0] = [ex[0], ex[1], 0.0]
    T[:3, 1] = [outward[0], outward[1], 0.0]
    T[:3, 2] = [0.0, 0.0, 1.0]
    T[:3, 3] = [front0[0], front0[1], base]
    local = box((width, depth, height), bottom=False)
    # texture coordinates per face: horizontal distance along the wall, height above street
    v = local.vertices
    perimeter_u = np.select(
        [np.isclose(v[:, 1], 0), np.isclose(v[:, 0], width), np.isclose(v[:, 1], depth)],
        [v[:, 0], width + v[:, 1], width + depth + (width - v[:, 0])],
        2 * width + depth + (depth - v[:, 1]),
    )
    world = local.transformed(T)
    above = world.vertices[:, 2] - street_level
    n_wall = 16  # 4 wall quads x 4 vertices come first in box(); the roof quad is last
    attrs = np.stack([perimeter_u, above, np.full(len(v), index), np.zeros(len(v))], -1)
    attrs[n_wall:, 0], attrs[n_wall:, 1], attrs[n_wall:, 3] = v[n_wall:, 0], v[n_wall:, 1], 1.0
    # box() lists the first triangle of every quad, then the second ones: quads 0-3 are the
    # walls, quad 4 the roof (slicing faces[:8] took half the roof and left a hole in a wall,
    # with vertex indices outside both meshes)
    walls = Mesh(world.vertices[:n_wall], world.faces[[0, 1, 2, 3, 5, 6, 7, 8]], attrs[:n_wall])
    roof = Mesh(world.vertices[n_wall:], world.faces[[4, 9]] - n_wall, attrs[n_wall:])
    return walls, roof


def build_static(net: StreetNetwork, terrain: Terrain, cfg: SideConfig, rng: np.random.Generator) -> StaticMeshes:
    walls, roofs, trunks, canopies, poles, signs, rails = [], [], [], [], [], [], []
    params = []
    for st in net.streets:
        for side in (-1, 1):
            pieces = intervals(st.centre.length, st.gaps(outer=True))
            if cfg.buildings:
                for s0, s1 in pieces:
                    _line_buildings(st, side, s0, s1, terrain, cfg, rng, walls, roofs, params)
            for s0, s1 in pieces:
                if cfg.tree_spacing > 0:
                    _line_trees(st, side, s0, s1, terrain, cfg, rng, trunks, canopies)
                if cfg.pole_spacing > 0:
                    _line_poles(st, side, s0, s1, terrain, cfg, rng, poles, signs)
        if cfg.guard_rails:
            _rails(st, terrain, rails)
    return StaticMeshes(
        Mesh.concat(walls), Mesh.concat(roofs), Mesh.concat(trunks), Mesh.concat(canopies),
        Mesh.concat(poles), Mesh.concat(signs), Mesh.concat(rails),
        np.array(params, dtype=np.float64).reshape(-1, len(FACADE_COLUMNS)),
    )


def _line_buildings(st: Street, side: int, s0: float, s1: float, terrain: Terrain, cfg: SideConfig,
                    rng: np.random.Generator, walls: list, roofs: list, params: list) -> None:
    s = s0 + 1.0
    while s < s1 - 6.0:
        width = min(rng.uniform(*cfg.building_front), s1 - 1.0 - s)
        setback = st.half_width + st.sidewalk + rng.uniform(*cfg.building_gap)
        p, h = st.centre.pose([s, s + width])
        normal = np.stack([-np.sin(h), np.cos(h)], -1) * side
        front = p + setback * normal
        outward = normal.mean(0) / np.linalg.norm(normal.mean(0))
        a, b = (front[0], front[1]) if side < 0 else (front[1], front[0])  # walls face the street
        ground = terrain.height(np.stack([a, b]))
        base = float(ground.min()) - 0.6
        street_level = float(ground.mean()) + st.curb
        height = rng.uniform(*cfg.building_height)
        index = len(params)
        w, r = _building(a, b, outward, rng.uniform(*cfg.building_depth), base, height + street_level - base,
                         index, street_level)
        walls.append(w)
        roofs.append(r)
        params.append([rng.uniform(2.9, 3.6), rng.uniform(2.3, 3.6), rng.uniform(0.9, 1.5),
                       rng.uniform(1.2, 1.8), rng.uniform(0, 1), float(rng.uniform() < 0.45),
                       float(rng.uniform() < 0.6), rng.integers(0, 2**20)])
        s += width + (rng.uniform(4.0, 9.0) if rng.uniform() < cfg.alley_probability else 0.0)


def _positions(s0: float, s1: float, spacing: float, rng: np.random.Generator) -> np.ndarray:
    s = np.arange(s0 + rng.uniform(1.0, spacing), s1 - 1.0, spacing)
    return s + rng.uniform(-0.2, 0.2, len(s)) * spacing


def _line_trees(st: Street, side: int, s0: float, s1: float, terrain: Terrain, cfg: SideConfig,
                rng: np.random.Generator, trunks: list, canopies: list) -> None:
    for s in _positions(s0, s1, cfg.tree_spacing, rng):
        xy, _ = st.centre.offset(side * (st.half_width + 0.9)).pose(s)
        base = terrain.lift(xy)[0] + [0.0, 0.0, st.curb - 0.05]
        trunk_h = rng.uniform(2.2, 3.4)
        trunk = cylinder(rng.uniform(0.1, 0.18), trunk_h + 0.5, 10)
        trunks.append(Mesh(trunk.vertices + base, trunk.faces))
        radius = rng.uniform(1.4, 2.4)
        canopies.append(_canopy(rng, radius, base + [0.0, 0.0, trunk_h + 0.75 * radius]))


def _canopy(rng: np.random.Generator, radius: float, centre: np.ndarray) -> Mesh:
    """A lumpy closed blob: latitude rings with a smooth random radius."""
    lat = np.linspace(-np.pi / 2 + 0.15, np.pi / 2 - 0.15, 9)
    lon = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    L, O = np.meshgrid(lat, lon, indexing="ij")
    freq = rng.integers(2, 5, 3)
    phase = rng.uniform(0, 2 * np.pi, 3)
    bump = 1 + 0.12 * (np.sin(freq[0] * O + phase[0]) + np.sin(freq[1] * L + phase[1])
                       + np.sin(freq[2] * (O + L) + phase[2]))
    r = radius * bump
    rings = np.stack([r * np.cos(L) * np.cos(O), r * np.cos(L) * np.sin(O), 0.8 * r * np.sin(L)], -1)
    mesh = ring_loft(rings)
    return Mesh(mesh.vertices + centre, mesh.faces)


def _line_poles(st: Street, side: int, s0: float, s1: float, terrain: Terrain, cfg: SideConfig,
                rng: np.random.Generator, poles: list, signs: list) -> None:
    for s in _positions(s0, s1, cfg.pole_spacing, rng):
        xy, h = st.centre.offset(side * (st.half_width + 0.45)).pose(s)
        base = terrain.lift(xy)[0] + [0.0, 0.0, st.curb - 0.05]
        height = rng.uniform(6.0, 8.0)
        pole = cylinder(0.07, height, 10)
        poles.append(Mesh(pole.vertices + base, pole.faces))
        # lamp arm reaching over the road
        arm = box((1.6, 0.12, 0.1))
        ang = h[0] + (np.pi / 2 if side < 0 else -np.pi / 2)
        poles.append(_place(arm, base + [0.0, 0.0, height - 0.3], ang, [0.0, -0.06, 0.0]))
        if rng.uniform() < cfg.sign_probability:
            panel = box((0.06, 0.7, 0.7))
            k = len(signs)
            face_ang = h[0] if side < 0 else h[0] + np.pi  # panel faces oncoming traffic
            m = _place(panel, base + [0.0, 0.0, 2.3], face_ang, [0.07, -0.35, 0.0])
            # texture coordinates (u, v) = panel-local (y, z), then the sign index
            m.attrs = np.concatenate([panel.vertices[:, 1:], np.full((len(panel.vertices), 1), k),
                                      np.zeros((len(panel.vertices), 1))], 1).astype(np.float32)
            signs.append(m)


def _place(mesh: Mesh, origin: np.ndarray, yaw: float, local_offset: list[float]) -> Mesh:
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return Mesh((mesh.vertices + local_offset) @ R.T + origin, mesh.faces, mesh.attrs)


def _rails(st: Street, terrain: Terrain, rails: list) -> None:
    """Concrete median barrier and metal guard rails at both road edges."""
    s = np.arange(0.0, st.centre.length, 2.0)
    p, h = st.centre.pose(s)
    normal = np.stack([-np.sin(h), np.cos(h)], -1)
    profiles = []
    if st.median > 0:
        profiles.append(np.array([[-0.3, -0.05], [-0.12, 0.85], [0.12, 0.85], [0.3, -0.05]]))
    for side in (-1, 1):
        lat = side * (st.half_width + 0.6)
        profiles.append(np.array([[lat - 0.05, 0.45], [lat - 0.05, 0.8], [lat + 0.05, 0.8], [lat + 0.05, 0.45]]))
        for k in range(0, len(s), 2):  # posts every 4 m
            post = box((0.1, 0.1, 0.8))
            base = terrain.lift(p[k] + lat * normal[k])[0] + [0.0, 0.0, -0.05]
            rails.append(_place(post, base, h[k], [-0.05, -0.05, 0.0]))
    for prof in profiles:
        xy = p[:, None] + prof[None, :, 0, None] * normal[:, None]
        z = terrain.height(xy.reshape(-1, 2)).reshape(len(s), len(prof)) + prof[None, :, 1]
        rails.append(ring_loft(np.concatenate([xy, z[..., None]], -1)))
