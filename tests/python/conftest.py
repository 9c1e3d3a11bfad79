"""Shared pytest fixtures.

Real KITTI data is found through :func:`twistslam.datasets.data_root` (``$TWISTSLAM_DATA``,
default ``shared/data`` beside the repository). Without it a real-data test skips with one
line naming the variable -- unless ``TWISTSLAM_REQUIRE_DATA=1`` (set by ``.ci/run``), which
turns the skip into a failure so that CI always runs them.

The paper's tables (``tables.json``, the published numbers printed beside ours by
``twistslam eval --paper``) are not KITTI data and not part of the repository either:
:func:`paper_tables` finds them through ``$TWISTSLAM_PAPER_TABLES``, else at
``paper/tables.json`` beside the data folder (``shared/paper`` on the development machines),
and skips or fails the same way.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from twistslam.datasets.data_root import DATA_ENV, data_root

REQUIRE_ENV = "TWISTSLAM_REQUIRE_DATA"
PAPER_ENV = "TWISTSLAM_PAPER_TABLES"


def _missing(message: str):
    if os.environ.get(REQUIRE_ENV, "") not in ("", "0"):
        pytest.fail(message + f"; {REQUIRE_ENV} is set, so this is a failure", pytrace=False)
    pytest.skip(message, allow_module_level=True)


def require_real_data(*parts: str) -> Path:
    """Path of real data under the data root; skips (or fails under TWISTSLAM_REQUIRE_DATA=1)
    when it is missing. Usable at module level and inside tests."""
    path = data_root().joinpath(*parts)
    if path.exists():
        return path
    _missing(f"real KITTI data not found: {path} (set {DATA_ENV})")


def paper_tables() -> Path:
    """The paper's ``tables.json``: ``$TWISTSLAM_PAPER_TABLES``, else ``paper/tables.json``
    beside the data folder; skips (or fails under TWISTSLAM_REQUIRE_DATA=1) when missing."""
    value = os.environ.get(PAPER_ENV, "").strip()
    path = Path(value).expanduser() if value else data_root().parent / "paper" / "tables.json"
    if path.is_file():
        return path
    _missing(f"the paper's tables.json not found: {path} (set {PAPER_ENV})")


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


#: The longest test files (make test's --durations): collected first, so that with
#: `pytest -n 2 --dist loadfile` they start at once instead of running alone at the end.
SLOW_FILES_FIRST = ("test_notebooks.py", "test_visual_objects.py", "test_lidar_objects.py")


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(SLOW_FILES_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: file order kept
