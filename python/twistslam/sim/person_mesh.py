"""Pedestrians: a closed loft of elliptical sections (legs, torso, shoulders, head) along z.

Same frames as :mod:`twistslam.sim.car_mesh`: built in the vehicle-like frame (x forward,
y left, z up) and returned in the KITTI object frame (origin at the box centre, y down).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .car_mesh import vehicle_to_object
from .mesh import Mesh, ring_loft

# body profile for a 1.75 m person: height, half-depth (x), half-width (y)
_PROFILE = np.array([
    [0.00, 0.13, 0.14], [0.06, 0.10, 0.15], [0.45, 0.08, 0.15], [0.85, 0.11, 0.19],
    [1.00, 0.10, 0.17], [1.28, 0.12, 0.21], [1.42, 0.11, 0.23], [1.48, 0.05, 0.06],
    [1.54, 0.08, 0.08], [1.64, 0.10, 0.09], [1.73, 0.07, 0.06], [1.75, 0.03, 0.03],
])
HIP, SHOULDER = 0.85 / 1.75, 1.46 / 1.75  # clothing boundaries as fractions of the height


@dataclass
class PersonShape:
    height: float  # m
    girth: float  # width/depth scale (1 = average build)

    def to_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}

    @property
    def size(self) -> tuple[float, float, float]:
        """(length, width, height) of the tight box."""
        return (2 * _PROFILE[:, 1].max() * self.girth, 2 * _PROFILE[:, 2].max() * self.girth, self.height)


def sample_person_shape(rng: np.random.Generator) -> PersonShape:
    return PersonShape(height=float(np.clip(rng.normal(1.72, 0.09), 1.5, 1.95)),
                       girth=float(np.clip(rng.normal(1.0, 0.08), 0.8, 1.25)))


def person_mesh(shape: PersonShape) -> Mesh:
    """Watertight pedestrian mesh in the object frame."""
    scale = shape.height / 1.75
    z = _PROFILE[:, 0] * scale
    ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)  # 16: samples hit the extreme y
    rx = _PROFILE[:, 1:2] * shape.girth
    ry = _PROFILE[:, 2:3] * shape.girth
    rings = np.stack([rx * np.cos(ang), ry * np.sin(ang), np.broadcast_to(z[:, None], (len(z), len(ang)))], -1)
    return vehicle_to_object(ring_loft(rings), shape.height)
