"""Synthetic driving sequences in the KITTI tracking layout, with exact ground truth.

    from twistslam.sim import generate
    generate("data/sim", scenario="urban", frames=100, seed=0, seq="0000")
    seq = twistslam.datasets.KittiTracking("data/sim", "0000")

See docs/sim.md for the scene, the sensors and the format of every file written.
"""

from .car_mesh import CarShape, car_mesh, sample_car_shape
from .config import SimConfig
from .generate import generate, run
from .scenario import SCENARIOS, scenario_config

__all__ = ["SCENARIOS", "CarShape", "SimConfig", "car_mesh", "generate", "run", "sample_car_shape", "scenario_config"]
