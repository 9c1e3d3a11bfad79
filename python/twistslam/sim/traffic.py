"""Who is in the scene and where they go: the ego car, moving cars on lanes (with turns and
lane changes), parked cars along the curbs, pedestrians on the sidewalks."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .car_mesh import CarShape, sample_car_shape
from .config import TrafficConfig
from .path import Path2D, fillet_route
from .person_mesh import PersonShape, sample_person_shape
from .road import Street, StreetNetwork, intervals

RIGHT_TURN_RADIUS = 9.0  # m; fits inside the curb corner of a parking street
LEFT_TURN_RADIUS = 14.0  # m; sweeps through the middle of the intersection
EGO_SIZE = (4.5, 1.8)  # m, length and width of the (unrendered) ego car


@dataclass
class Agent:
    """One object (or the ego car). ``route`` arc length ``s0`` at frame 0."""

    kind: str  # "ego" | "car" | "person"
    route: Path2D
    s0: float
    speed: float  # m/s desired (0: parked)
    shape: CarShape | PersonShape | None = None
    lane_change: tuple[float, float, float] | None = None  # (start s, length m, lateral m)
    stop_at: float | None = None  # route arc length of a red light to wait at (cross street)
    colour: np.ndarray = field(default_factory=lambda: np.zeros(3))
    phase: np.ndarray = field(default_factory=lambda: np.zeros(4))  # non-planar perturbation

    @property
    def size(self) -> tuple[float, float, float]:
        """(length, width, height) of the box."""
        if self.kind == "ego":
            return (*EGO_SIZE, 1.5)
        if isinstance(self.shape, CarShape):
            return (self.shape.length, self.shape.width, self.shape.height)
        return self.shape.size


#: a KITTI street's palette of paint colours (linear RGB): greys, silver, black, white, blues, reds
PAINTS = np.array([
    [0.55, 0.56, 0.58], [0.3, 0.31, 0.33], [0.05, 0.05, 0.06], [0.75, 0.75, 0.74], [0.1, 0.15, 0.35],
    [0.45, 0.06, 0.05], [0.2, 0.25, 0.2], [0.6, 0.5, 0.3], [0.12, 0.12, 0.13], [0.4, 0.42, 0.46],
])


def _turn_route(net: StreetNetwork, st: Street, direction: int, lane: int, turn: str) -> Path2D | None:
    """Route from ``lane`` of ``st`` (driving ``direction``) turning ``left``/``right``."""
    if len(net.streets) < 2:
        return None
    other = net.streets[1 - st.index]
    near = st.centre.pose(st.s_cross)[0][0]
    src = st.lane(direction, lane)
    h_src = src.pose(src.project(near[None]))[1][0]
    want = h_src + (np.pi / 2 if turn == "left" else -np.pi / 2)
    k = 0 if turn == "left" else other.lanes - 1
    for d in (1, -1):
        dst = other.lane(d, k)
        h_dst = dst.pose(dst.project(near[None]))[1][0]
        if np.cos(h_dst - want) > 0.9:
            radius = LEFT_TURN_RADIUS if turn == "left" else RIGHT_TURN_RADIUS
            return fillet_route(src, dst, radius, near)
    return None


def spawn_agents(net: StreetNetwork, cfg: TrafficConfig, rng: np.random.Generator, window: tuple[float, float],
                 margin: float) -> list[Agent]:
    """The ego car first, then every other agent.

    ``window`` is the range of main-street arc length the ego car can see during the
    sequence: parked cars and pedestrians outside it are never spawned; moving cars are
    spawned up to ``margin`` metres beyond it (they may drive into view)."""
    main = net.streets[0]
    agents: list[Agent] = []
    ego_route = main.lane(1, cfg.ego_lane)
    if cfg.ego_turn in ("left", "right"):
        ego_route = _turn_route(net, main, 1, cfg.ego_lane, cfg.ego_turn) or ego_route
    ego_s0 = float(ego_route.project(np.zeros((1, 2)))[0])
    agents.append(Agent("ego", ego_route, ego_s0, rng.uniform(*cfg.ego_speed)))

    def car(route: Path2D, s: float, speed: float) -> Agent:
        shape = sample_car_shape(rng, cfg.car_mix)
        return Agent("car", route, s, speed, shape, colour=PAINTS[rng.integers(len(PAINTS))]
                     * rng.uniform(0.85, 1.15), phase=rng.uniform(0, 2 * np.pi, 4))

    lo, hi = window
    # moving cars: every lane of every street, both directions
    for st in net.streets:
        if st.index == 1 and not cfg.cross_traffic:
            continue
        for direction in (1, -1):
            for lane in range(st.lanes):
                base = st.lane(direction, lane)
                gap_mean = 100.0 / cfg.moving_density if cfg.moving_density > 0 else np.inf
                if not np.isfinite(gap_mean):
                    continue
                s = rng.uniform(0, gap_mean)
                while s < base.length - 5.0:
                    xy = base.pose(s)[0]
                    along = main.centre.project(xy)[0]
                    is_ego_lane = st.index == 0 and direction == 1 and lane == cfg.ego_lane
                    in_window = lo - margin < along < hi + margin
                    near_ego = is_ego_lane and abs(s - ego_s0) < 8.0
                    if in_window and not near_ego:
                        agent = _moving(car, base, s, cfg, rng, net, st, direction, lane)
                        if st.index == 1:
                            # the cross street has a red light for the whole sequence: its
                            # cars queue at the stop line instead of crossing the main street
                            stop = base.project(st.centre.pose(st.s_cross)[0])[0] - st.cross_outer
                            if s > stop + 4.0 and s < stop + 2 * st.cross_outer:
                                s += _gap(cfg, rng, gap_mean)
                                continue  # not inside the intersection at the start
                            agent.route, agent.lane_change = base, None
                            agent.stop_at = stop if s < stop else None
                        agents.append(agent)
                    s += _gap(cfg, rng, gap_mean)
    if cfg.moving_density > 0 and cfg.lead_car:  # a car ahead of the ego car in its lane
        s_lead = ego_s0 + rng.uniform(*cfg.ego_lead_gap) + 4.5
        # inserted right after the ego car so that overlap removal keeps it
        agents.insert(1, car(ego_route, s_lead, max(agents[0].speed, rng.uniform(*cfg.moving_speed))))
        _remove_overlaps(agents)
    # parked cars along the curbs
    if cfg.parked_density > 0 and net.cfg.parking_width > 0:
        for st in net.streets:
            for side in (-1, 1):
                curb = st.curb_path(side, net.cfg.parking_width / 2)
                route = curb if side < 0 else curb.reversed()
                s = rng.uniform(0, 5)
                while s < route.length - 3:
                    agent = car(route, s, 0.0)
                    xy = route.pose(s)[0]
                    along = main.centre.project(xy)[0]
                    gap = [g for g in st.gaps(outer=True)]
                    s_street = st.centre.project(xy)[0]
                    blocked = any(g0 - 6 < s_street < g1 + 6 for g0, g1 in gap)
                    occupied = rng.uniform() < min(1.0, cfg.parked_density * 6.5 / 100)  # ~6.5 m per slot
                    if lo - 20 < along < hi and not blocked and occupied:
                        agents.append(agent)
                    s += agent.shape.length + rng.uniform(0.8, 2.5)
    # pedestrians on the sidewalks: each walks along its own piece of sidewalk (they wait at
    # the curb where it ends instead of crossing in front of cars)
    if cfg.pedestrian_density > 0:
        for st in net.streets:
            for side in (-1, 1):
                path = st.curb_path(side, -st.sidewalk * rng.uniform(0.55, 0.8))
                for c0, c1 in intervals(st.centre.length, st.gaps(outer=True)):
                    p0, p1 = path.project(st.centre.pose([c0, c1])[0])
                    if p1 - p0 < 10.0:
                        continue
                    piece = path.sub(p0, p1)
                    s = rng.uniform(0, 100.0 / cfg.pedestrian_density)
                    while s < piece.length - 1.0:
                        forward = rng.uniform() < 0.5
                        route = piece if forward else piece.reversed()
                        xy = piece.pose(s)[0]
                        along = main.centre.project(xy)[0]
                        if lo - 20 < along < hi:
                            agents.append(Agent("person", route, s if forward else piece.length - s,
                                                rng.uniform(*cfg.pedestrian_speed), sample_person_shape(rng),
                                                colour=rng.uniform(0.05, 0.7, 3), phase=rng.uniform(0, 2 * np.pi, 4)))
                        s += rng.exponential(100.0 / cfg.pedestrian_density) + 1.0
    return agents


def _gap(cfg: TrafficConfig, rng: np.random.Generator, gap_mean: float) -> float:
    if cfg.platoon:
        return 4.8 + rng.uniform(*cfg.platoon_gap)
    return 8.0 + rng.exponential(max(gap_mean - 8.0, 1.0))


def _moving(car, base: Path2D, s: float, cfg: TrafficConfig, rng: np.random.Generator, net: StreetNetwork,
            st: Street, direction: int, lane: int) -> Agent:
    route = base
    if st.s_cross is not None and rng.uniform() < cfg.turn_probability:
        near = st.centre.pose(st.s_cross)[0]
        if base.project(near)[0] > s + 5.0:  # the intersection is still ahead of this car
            turn = "left" if lane == 0 and rng.uniform() < 0.5 else "right"
            if turn == "right" and lane != st.lanes - 1:
                turn = "left" if lane == 0 else "none"
            route = _turn_route(net, st, direction, lane, turn) or base if turn != "none" else base
    agent = car(route, s, rng.uniform(*cfg.moving_speed))
    if st.lanes > 1 and rng.uniform() < cfg.lane_change_probability:
        target = lane + (1 if lane == 0 else -1 if lane == st.lanes - 1 else rng.choice([-1, 1]))
        lateral = -(target - lane) * st.lane_width  # +1 lane index = further right
        agent.lane_change = (s + rng.uniform(10.0, 80.0), rng.uniform(35.0, 60.0), lateral)
    return agent


def _remove_overlaps(agents: list[Agent]) -> None:
    """Drop cars whose start box overlaps an earlier agent's (keeps the ego car)."""
    keep, placed = [], []
    for a in agents:
        xy, h = a.route.pose(a.s0)
        f = np.array([np.cos(h[0]), np.sin(h[0])])
        length, width = a.size[:2]
        clear = True
        for p, L, W in placed:
            d = p - xy[0]
            along, across = abs(d @ f), abs(d[0] * f[1] - d[1] * f[0])
            if along < 0.5 * (length + L) + 0.5 and across < 0.5 * (width + W) + 0.2:
                clear = False
                break
        if clear:
            keep.append(a)
            placed.append((xy[0], length, width))
    agents[:] = keep
