"""Named scenarios: each is a set of overrides of the default (urban) :class:`SimConfig`."""

from __future__ import annotations

from typing import Any

from .config import SimConfig

#: scenario name -> (one-line description, overrides of the defaults)
SCENARIOS: dict[str, tuple[str, dict[str, Any]]] = {
    "urban": (
        "KITTI-tracking-like city street: one lane each way, parked cars, pedestrians, "
        "an intersection ahead",
        {},
    ),
    "highway": (
        "three lanes each way, guard rails, no buildings, parking or pedestrians, faster traffic",
        {
            "street": {"lanes_per_direction": 3, "parking_width": 0.0, "sidewalk_width": 3.0,
                       "curb_height": 0.1, "intersection": False, "max_curvature": 1.0 / 400.0},
            "side": {"buildings": False, "guard_rails": True, "tree_spacing": 22.0,
                     "pole_spacing": 40.0, "sign_probability": 0.2},
            "traffic": {"moving_density": 2.0, "moving_speed": (12.0, 16.0), "parked_density": 0.0,
                        "pedestrian_density": 0.0, "ego_speed": (12.0, 15.0), "ego_lane": 1,
                        "lane_change_probability": 0.5, "turn_probability": 0.0},
        },
    ),
    "intersection": (
        "the ego car and other cars turn at an intersection just ahead",
        {
            "street": {"intersection_ahead": (20.0, 26.0), "lanes_per_direction": 1},
            "traffic": {"ego_turn": "left", "turn_probability": 0.7, "ego_speed": (7.0, 11.0),
                        "moving_density": 3.0, "lead_car": False},
        },
    ),
    "static": (
        "no moving objects: parked cars only (the whole scene is rigid)",
        {"traffic": {"moving_density": 0.0, "pedestrian_density": 0.0, "cross_traffic": False}},
    ),
    "crowded": (
        "slow dense traffic: columns of cars on three narrow lanes each way cover over 40 % of the image",
        {
            "street": {"lanes_per_direction": 3, "lane_width": 3.0, "parking_width": 0.0, "intersection": False},
            "traffic": {"platoon": True, "platoon_gap": (1.0, 2.5), "ego_lane": 1, "ego_speed": (5.0, 6.0),
                        "moving_speed": (5.0, 6.5), "ego_lead_gap": (1.5, 2.5), "parked_density": 0.0,
                        "car_mix": (0.2, 0.2, 0.6), "idm_headway": 0.5, "idm_min_gap": 1.5,
                        "lane_change_probability": 0.0, "turn_probability": 0.0, "pedestrian_density": 4.0},
        },
    ),
}


def scenario_config(name: str, **overrides: Any) -> SimConfig:
    """The :class:`SimConfig` of scenario ``name`` with ``overrides`` applied on top.

    Raises
    ------
    ValueError
        For an unknown scenario; the message lists the valid names.
    """
    if name not in SCENARIOS:
        valid = ", ".join(SCENARIOS)
        raise ValueError(f"unknown scenario {name!r}; valid scenarios: {valid}")
    cfg = SimConfig(scenario=name).with_overrides(SCENARIOS[name][1])
    return cfg.with_overrides(overrides)
