"""Shared pytest fixtures.

Real KITTI data is found through :func:`twistslam.datasets.data_root` (``$TWISTSLAM_DATA``,
default ``shared/data`` beside the repository). Without it a real-data test skips with one
line naming the variable -- unless ``TWISTSLAM_REQUIRE_DATA=1`` (set by ``.ci/run``), which
turns the skip into a failure so that CI always runs them.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from twistslam.datasets.data_root import DATA_ENV, data_root

REQUIRE_ENV = "TWISTSLAM_REQUIRE_DATA"


def require_real_data(*parts: str) -> Path:
    """Path of real data under the data root; skips (or fails under TWISTSLAM_REQUIRE_DATA=1)
    when it is missing. Usable at module level and inside tests."""
    path = data_root().joinpath(*parts)
    if path.exists():
        return path
    message = f"real KITTI data not found: {path} (set {DATA_ENV})"
    if os.environ.get(REQUIRE_ENV, "") not in ("", "0"):
        pytest.fail(message + f"; {REQUIRE_ENV} is set, so this is a failure", pytrace=False)
    pytest.skip(message, allow_module_level=True)


@pytest.fixture(scope="session")
def kitti_tracking() -> Path:
    """Root of the real KITTI tracking files (labels, calibration, detections, oxts of 0001)."""
    return require_real_data("kitti_tracking")


@pytest.fixture(scope="session")
def kitti_tracking_lidar() -> Path:
    """Root of real sequence 0001 frames 0-26 with stereo, LiDAR, labels and oxts."""
    return require_real_data("kitti_tracking_lidar")


@pytest.fixture(scope="session")
def kitti_object() -> Path:
    """Root of the real KITTI object frames 000000-000010 (scan, image, calib, labels)."""
    return require_real_data("kitti_object")


@pytest.fixture(scope="session")
def ab3dmot_outputs() -> Path:
    """AB3DMOT's tracking outputs on the validation sequences (raw/ and thresholded/)."""
    return require_real_data("ab3dmot")
