"""Motion of every agent: intelligent-driver-model car following along routes, then poses.

Cars move on the road surface (planar motion along the local road plane, docs/design.md's
mechanical link) unless ``TrafficConfig.nonplanar`` adds a small roll/pitch/heave.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .car_mesh import R_O_V
from .config import TrafficConfig
from .terrain import Terrain
from .traffic import Agent

SUBSTEPS = 2  # IDM integration steps per frame (0.05 s): stable for these accelerations
GEOMETRIC_REACH = 25.0  # m; leaders on other routes are searched this far ahead
SAME_ROUTE_REACH = 120.0  # m; leaders on the same route are searched this far ahead
MAX_DECEL = 8.0  # m/s^2; physical braking limit


@dataclass
class Trajectories:
    """Per agent (axis 0, same order as the agent list) and per state (axis 1, frames + 1)."""

    T_m_o: np.ndarray  # (A, N, 4, 4) object frame (box centre, KITTI axes) -> map
    T_m_v: np.ndarray  # (A, N, 4, 4) vehicle frame (ground, x fwd, z up) -> map
    active: np.ndarray  # (A, N) bool: agent exists (has not left its route)
    speed: np.ndarray  # (A, N) m/s


def _lateral(agent: Agent, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lateral offset (m, left positive) and its derivative d/ds along the route."""
    if agent.lane_change is None:
        return np.zeros_like(s), np.zeros_like(s)
    s0, length, offset = agent.lane_change
    t = np.clip((s - s0) / length, 0, 1)
    return offset * t * t * (3 - 2 * t), offset * 6 * t * (1 - t) / length


def _planar(agent: Agent, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    xy, heading = agent.route.pose(s)
    lat, dlat = _lateral(agent, s)
    normal = np.stack([-np.sin(heading), np.cos(heading)], -1)
    return xy + lat[:, None] * normal, heading + np.arctan(dlat)


def simulate(agents: list[Agent], terrain: Terrain, cfg: TrafficConfig, frames: int, dt: float,
             rng: np.random.Generator) -> Trajectories:
    """Integrate all agents over ``frames + 1`` states (the extra one gives the flow of the
    last frame)."""
    A, N = len(agents), frames + 1
    s = np.array([a.s0 for a in agents], dtype=np.float64)
    v = np.array([a.speed for a in agents], dtype=np.float64)
    v_des = v.copy()
    length = np.array([a.route.length for a in agents])
    size = np.array([a.size for a in agents])
    cars = np.array([a.kind in ("ego", "car") and a.speed > 0 for a in agents])
    route_id = np.array([id(a.route) for a in agents])
    people = np.array([a.kind == "person" for a in agents])
    stop_at = np.array([np.inf if a.stop_at is None else a.stop_at for a in agents])
    signed = [np.gradient(a.route.heading, a.route.s) for a in agents]
    kappa = [(np.abs(k), k) for k in signed]  # (|curvature| for speed limits, signed for paths)
    ego_targets = rng.uniform(*cfg.ego_speed, size=N // 40 + 2)  # new wish every 4 s
    S = np.zeros((A, N))
    V = np.zeros((A, N))
    active = np.ones(A, dtype=bool)
    ACT = np.zeros((A, N), dtype=bool)
    h = dt / SUBSTEPS
    for n in range(N):
        S[:, n], V[:, n], ACT[:, n] = s, v, active
        if n == N - 1:
            break
        v_des[0] = ego_targets[n // 40]
        for _ in range(SUBSTEPS):
            acc = _idm(agents, s, v, v_des, size, cars, active, route_id, kappa, stop_at, cfg)
            v = np.where(cars, np.maximum(v + acc * h, 0.0), v)
            s = s + v * h
        # pedestrians stop at the end of their sidewalk; cars leave the scene at route ends
        stop = people & (s >= length - 0.5)
        s, v = np.where(stop, length - 0.5, s), np.where(stop, 0.0, v)
        active &= people | (s < length - 1.0)
    return _poses(agents, terrain, cfg, S, V, ACT, dt)


def _idm(agents, s, v, v_des, size, cars, active, route_id, kappa, stop_at, cfg: TrafficConfig) -> np.ndarray:
    A = len(agents)
    xy = np.zeros((A, 2))
    heading = np.zeros(A)
    for i, a in enumerate(agents):
        p, h = _planar(a, np.array([min(s[i], a.route.length)]))
        xy[i], heading[i] = p[0], h[0]
    f = np.stack([np.cos(heading), np.sin(heading)], -1)
    left = np.stack([-f[:, 1], f[:, 0]], -1)
    rel = xy[None] - xy[:, None]  # [i, j] = j relative to i
    dx = np.einsum("ijk,ik->ij", rel, f)
    dy = np.einsum("ijk,ik->ij", rel, left)
    curv = np.array([np.interp(si, a.route.s, k[1]) for si, a, k in zip(s, agents, kappa)])
    dy = dy - 0.5 * curv[:, None] * dx**2  # follow the own path's bend
    same = route_id[:, None] == route_id[None]
    ds_route = s[None] - s[:, None]
    half_len = 0.5 * (size[:, 0][:, None] + size[:, 0][None])
    corridor = np.abs(dy) < 0.5 * (size[:, 1][:, None] + size[:, 1][None]) + 0.25
    geometric = (dx > 0) & (dx < GEOMETRIC_REACH) & corridor
    # oncoming cars are not leaders (they are in their own lane; if our paths cross, they
    # see us crossing theirs and yield)
    geometric &= np.cos(heading[None, :] - heading[:, None]) > -0.7
    # right of way: when two cars block each other (crossing paths), the lower agent index
    # goes first (the ego car, index 0, always), so intersections never deadlock
    mutual = geometric & geometric.T
    geometric &= ~(mutual & (np.arange(A)[:, None] < np.arange(A)[None, :]))
    along = same & (ds_route > 0) & (ds_route < SAME_ROUTE_REACH)
    gap = np.where(along, ds_route, np.where(geometric, dx, np.inf)) - half_len
    gap[~active[None].repeat(A, 0)] = np.inf
    np.fill_diagonal(gap, np.inf)
    j = np.argmin(gap, axis=1)
    g = gap[np.arange(A), j]
    cos_rel = np.cos(heading[j] - heading)
    dv = v - v[j] * cos_rel
    # red lights: a standing obstacle at the stop line
    red = stop_at - s - 0.5 * size[:, 0]
    at_red = np.isfinite(stop_at) & (red > -1.0) & (red < g)
    g = np.maximum(np.where(at_red, red, g), 0.1)
    dv = np.where(at_red, v, dv)
    # slow down ahead of bends: v <= sqrt(a_lat / kappa) over the braking distance
    limit = v_des.copy()
    for i, a in enumerate(agents):
        if cars[i]:
            look = s[i] + np.linspace(0.0, v[i] ** 2 / (2 * cfg.idm_decel) + 8.0, 8)
            k = np.interp(look, a.route.s, kappa[i][0]).max()
            limit[i] = min(v_des[i], np.sqrt(cfg.max_lateral_accel / max(k, 1e-6)))
    a_max, b = cfg.idm_accel, cfg.idm_decel
    s_star = cfg.idm_min_gap + np.maximum(0.0, v * cfg.idm_headway + v * dv / (2 * np.sqrt(a_max * b)))
    free = 1 - (v / np.maximum(limit, 0.1)) ** 4
    acc = a_max * (free - np.where(np.isfinite(g), (s_star / g) ** 2, 0.0))
    return np.clip(acc, -MAX_DECEL, a_max)


def _poses(agents, terrain: Terrain, cfg: TrafficConfig, S, V, ACT, dt) -> Trajectories:
    A, N = S.shape
    T_m_v = np.tile(np.eye(4), (A, N, 1, 1))
    t = np.arange(N) * dt
    for i, a in enumerate(agents):
        xy, heading = _planar(a, np.minimum(S[i], a.route.length))
        n = terrain.normal(xy)
        fwd = np.stack([np.cos(heading), np.sin(heading), np.zeros(N)], -1)
        fwd -= np.einsum("ij,ij->i", fwd, n)[:, None] * n
        fwd /= np.linalg.norm(fwd, axis=1, keepdims=True)
        R = np.stack([fwd, np.cross(n, fwd), n], -1)
        if cfg.nonplanar > 0 and a.kind != "person":
            roll = cfg.nonplanar * np.sin(2 * np.pi * 0.9 * t + a.phase[0])
            pitch = cfg.nonplanar * np.sin(2 * np.pi * 1.3 * t + a.phase[1])
            R = R @ _rx(roll) @ _ry(pitch)
        T_m_v[i, :, :3, :3] = R
        T_m_v[i, :, :3, 3] = terrain.lift(xy)
    T_v_o = np.eye(4)
    T_v_o[:3, :3] = R_O_V.T
    heights = np.array([a.size[2] for a in agents])
    T_m_o = T_m_v @ T_v_o
    T_m_o[..., :3, 3] += T_m_v[..., :3, 2] * (heights[:, None, None] / 2)
    return Trajectories(T_m_o, T_m_v, ACT, V)


def _rx(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    R = np.tile(np.eye(3), (len(a), 1, 1))
    R[:, 1, 1], R[:, 1, 2], R[:, 2, 1], R[:, 2, 2] = c, -s, s, c
    return R


def _ry(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    R = np.tile(np.eye(3), (len(a), 1, 1))
    R[:, 0, 0], R[:, 0, 2], R[:, 2, 0], R[:, 2, 2] = c, s, -s, c
    return R
