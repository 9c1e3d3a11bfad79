"""Procedural family of car shapes: watertight triangle meshes from a handful of parameters.

Importable on its own (the DeepSDF shape model trains on this family)::

    from twistslam.sim.car_mesh import sample_car_shape, car_mesh
    shape = sample_car_shape(np.random.default_rng(0))
    mesh = car_mesh(shape)            # object frame o, origin at the box centre

Frames. The *vehicle* frame ``v`` has x forward, y left, z up, origin on the ground below
the box centre. The *object* frame ``o`` is KITTI's box frame: origin at the geometric box
centre, x forward (length), y down (height), z = x cross y (width axis, pointing left), so a
KITTI box ``[cx, cy, cz, l, w, h, ry]`` maps object points into the camera frame as
``X_c = R_y(ry) X_o + (cx, cy, cz)``. Meshes are returned in ``o``; their bounding box is
exactly ``[-l/2, l/2] x [-h/2, h/2] x [-w/2, w/2]``.

The mesh is one closed body (a loft of cross-sections along x) and four closed wheels
that never touch it (the body has wheel arches): five disjoint watertight components, so
inside/outside and signed distances are well defined.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .mesh import Mesh, cylinder, ring_loft

#: rotation taking vehicle-frame vectors into the object frame: x -> x, z(up) -> -y, y(left) -> z
R_O_V = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
ARCH_GAP = 0.04  # m between tyre and wheel arch, so the components never intersect


@dataclass
class CarShape:
    """Shape parameters (metres or fractions of the named dimension)."""

    length: float
    width: float
    height: float
    hood: float  # fraction of the length from the front bumper to the windshield base
    trunk: float  # fraction of the length from the rear bumper to the rear-window base
    windshield: float  # fraction of the cabin length taken by the windshield slope
    rear_window: float  # fraction of the cabin length taken by the rear-window slope
    belt: float  # beltline (bottom of the windows) as a fraction of the height
    roof_width: float  # roof width as a fraction of the body width
    wheel_radius: float
    wheel_width: float
    clearance: float  # ground clearance of the body
    overhang_front: float  # fraction of the length ahead of the front axle
    overhang_rear: float  # fraction of the length behind the rear axle

    def to_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}

    # derived positions in the vehicle frame (x forward, z up), used by the car material too
    @property
    def x_windshield(self) -> float:
        return self.length / 2 - self.hood * self.length

    @property
    def x_rear_window(self) -> float:
        return -self.length / 2 + self.trunk * self.length

    @property
    def x_roof(self) -> tuple[float, float]:
        """(rear, front) x of the flat roof."""
        cabin = self.x_windshield - self.x_rear_window
        return self.x_rear_window + self.rear_window * cabin, self.x_windshield - self.windshield * cabin

    @property
    def z_belt(self) -> float:
        return self.belt * self.height

    @property
    def axles(self) -> tuple[float, float]:
        """(rear, front) axle x."""
        return (-self.length / 2 + self.overhang_rear * self.length,
                self.length / 2 - self.overhang_front * self.length)


def sample_car_shape(rng: np.random.Generator, mix: tuple[float, float, float] = (0.55, 0.3, 0.15)) -> CarShape:
    """A random car spanning real sizes (KITTI cars: l 3.2-5.2, w 1.4-2.0, h 1.3-2.0 m).

    ``mix``: probabilities of a sedan, a hatchback and an SUV / van-like body."""
    kind = int(rng.choice(3, p=np.asarray(mix) / np.sum(mix)))
    length = float(np.clip(rng.normal([4.3, 3.8, 4.6][kind], 0.3), 3.3, 5.2))
    width = float(np.clip(1.55 + 0.12 * (length - 3.6) + rng.normal(0, 0.05) + 0.1 * (kind == 2), 1.45, 2.0))
    height = float(np.clip(rng.normal([1.45, 1.5, 1.75][kind], 0.06), 1.3, 1.95))
    return CarShape(
        length=length, width=width, height=height,
        hood=float(rng.uniform(0.22, 0.32) if kind != 2 else rng.uniform(0.18, 0.25)),
        trunk=float([rng.uniform(0.14, 0.22), rng.uniform(0.03, 0.07), rng.uniform(0.03, 0.08)][kind]),
        windshield=float(rng.uniform(0.25, 0.38)),
        rear_window=float([rng.uniform(0.2, 0.32), rng.uniform(0.12, 0.2), rng.uniform(0.05, 0.12)][kind]),
        belt=float(rng.uniform(0.55, 0.62)),
        roof_width=float(rng.uniform(0.74, 0.86)),
        wheel_radius=float(np.clip(0.29 + 0.05 * (length - 3.8) + rng.normal(0, 0.015), 0.27, 0.4)),
        wheel_width=float(rng.uniform(0.18, 0.25)),
        clearance=float(rng.uniform(0.13, 0.2) + 0.05 * (kind == 2)),
        overhang_front=float(rng.uniform(0.18, 0.22)),
        overhang_rear=float(rng.uniform(0.17, 0.23)),
    )


def _top(shape: CarShape, x: np.ndarray) -> np.ndarray:
    L, H, zb = shape.length, shape.height, shape.z_belt
    xr, xf = shape.x_roof
    knots = [-L / 2, shape.x_rear_window, xr, xf, shape.x_windshield, L / 2]
    values = [zb - 0.06, zb + 0.02, H, H, zb + 0.02, zb - 0.1]
    return np.interp(x, knots, values)


def _bottom(shape: CarShape, x: np.ndarray) -> np.ndarray:
    L, r = shape.length, shape.wheel_radius
    z = shape.clearance + 0.12 * np.clip((np.abs(x) - (L / 2 - 0.45)) / 0.45, 0, 1)
    for xa in shape.axles:
        d = x - xa
        arch = r + np.sqrt(np.clip((r + ARCH_GAP) ** 2 - d**2, 0, None))
        z = np.where(np.abs(d) <= r + ARCH_GAP + 1e-9, np.maximum(z, arch), z)
    return z


def _stations(shape: CarShape) -> np.ndarray:
    L, r = shape.length, shape.wheel_radius
    xs = [np.linspace(-L / 2 + 0.06, L / 2 - 0.06, 22), [-L / 2, L / 2]]
    xs += [shape.x_windshield, shape.x_rear_window, *shape.x_roof]
    for xa in shape.axles:
        edge = r + ARCH_GAP
        xs += [np.linspace(xa - edge, xa + edge, 13), [xa - edge - 0.01, xa + edge + 0.01]]
    x = np.concatenate([np.atleast_1d(v) for v in xs])
    return np.unique(np.clip(x, -L / 2, L / 2))


def _half_width(shape: CarShape, x: np.ndarray, z: np.ndarray, z_bot: np.ndarray, z_top: np.ndarray) -> np.ndarray:
    """Half-width at stations ``x`` (S,) and heights ``z`` (S, K): rounded plan view, slight
    tumblehome below, greenhouse narrowing to the roof above the beltline."""
    L, W, H, zb = shape.length, shape.width, shape.height, shape.z_belt
    plan = W / 2 * (1 - 0.12 * np.clip((np.abs(x) - (L / 2 - 0.5)) / 0.5, 0, 1) ** 2)
    t_low = np.clip((z - z_bot[:, None]) / 0.12, 0, 1)
    low = 0.94 + 0.06 * t_low
    t_up = np.clip((z - zb) / max(H - zb, 1e-6), 0, 1)
    up = 0.97 + (shape.roof_width - 0.97) * t_up
    factor = np.where(z > zb, up, low)
    # the top edge of hood and trunk is rounded too
    factor = factor * (1 - 0.06 * (z >= z_top[:, None] - 1e-9) * (z_top[:, None] < zb + 0.1))
    return plan[:, None] * factor


def car_vehicle_mesh(shape: CarShape) -> tuple[Mesh, int]:
    """Mesh in the vehicle frame (x forward, y left, z up, ground at z = 0) and the number
    of body faces (the wheel faces follow them)."""
    x = _stations(shape)
    z_bot, z_top = _bottom(shape, x), _top(shape, x)
    crown = np.minimum(0.04, 0.1 * (z_top - z_bot))
    z_edge = z_top - crown  # where the sides meet the (crowned) top
    z_mid = np.minimum(shape.z_belt, z_edge)
    low = z_bot[:, None] + (z_mid - z_bot)[:, None] * np.array([0.0, 0.06, 0.25, 0.5, 0.75, 1.0])[None]
    high = z_mid[:, None] + (z_edge - z_mid)[:, None] * np.array([0.3, 0.6, 0.85, 1.0])[None]
    z_side = np.concatenate([low, high], 1)  # (S, 10) heights up one side
    y_side = _half_width(shape, x, z_side, z_bot, z_top)
    y_top = y_side[:, -1]
    top_t = np.linspace(-1, 1, 7)[1:-1]
    bot_t = np.linspace(1, -1, 7)[1:-1]
    S = len(x)
    right = np.stack([np.broadcast_to(x[:, None], z_side.shape), -y_side, z_side], -1)
    left = np.stack([np.broadcast_to(x[:, None], z_side.shape), y_side, z_side], -1)[:, ::-1]
    top = np.stack([np.broadcast_to(x[:, None], (S, 5)), y_top[:, None] * top_t,
                    z_top[:, None] - crown[:, None] * top_t**2], -1)
    y_bot = y_side[:, 0]
    bottom = np.stack([np.broadcast_to(x[:, None], (S, 5)), y_bot[:, None] * bot_t,
                       np.broadcast_to(z_bot[:, None], (S, 5))], -1)
    rings = np.concatenate([right, top, left, bottom], 1)
    # shrink the end sections towards their centre: chamfered bumpers
    for k, scale in ((0, 0.9), (S - 1, 0.9)):
        c = rings[k].mean(0)
        rings[k] = c + (rings[k] - c) * [1.0, scale, scale]
    body = ring_loft(rings)
    n_body = len(body.faces)
    wheels = []
    r, ww = shape.wheel_radius, shape.wheel_width
    y_wheel = shape.width / 2 - 0.03 - ww
    rot = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # cylinder z -> y
    for xa in shape.axles:
        for side in (-1, 1):
            cyl = cylinder(r, ww, 20)  # 20 segments: a vertex touches the ground (z = 0)
            v = cyl.vertices @ rot.T  # a proper rotation: the axis runs along +y from 0 to ww
            v = v + [xa, y_wheel if side > 0 else -(y_wheel + ww), r]
            wheels.append(Mesh(v, cyl.faces))
    return Mesh.concat([body, *wheels]), n_body


def car_mesh(shape: CarShape) -> Mesh:
    """Watertight mesh in the object frame ``o`` (see module docstring)."""
    mesh, _ = car_vehicle_mesh(shape)
    return vehicle_to_object(mesh, shape.height)


def vehicle_to_object(mesh: Mesh, height: float) -> Mesh:
    """Move a vehicle-frame mesh into the object frame of a box of ``height``."""
    v = (mesh.vertices - [0.0, 0.0, height / 2]) @ R_O_V.T
    return Mesh(v, mesh.faces, mesh.attrs)
