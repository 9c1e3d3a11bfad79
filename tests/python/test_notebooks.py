"""Every notebook runs top to bottom: its code cells are executed in order in one namespace.

A notebook that reads real KITTI data names the data folder's sub-folders it needs in its
metadata (``"twistslam": {"real_data": ["kitti_tracking"]}``); without them it is skipped (or
failed under TWISTSLAM_REQUIRE_DATA=1) like every real-data test, see conftest.py.
"""

import json
from pathlib import Path

import matplotlib
import pytest

from conftest import require_real_data

matplotlib.use("Agg")

NOTEBOOKS = sorted((Path(__file__).parents[2] / "notebooks").glob("*.ipynb"))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path, monkeypatch):
    monkeypatch.chdir(path.parent)  # notebooks use paths relative to their folder
    notebook = json.loads(path.read_text())
    for folder in notebook["metadata"].get("twistslam", {}).get("real_data", []):
        require_real_data(folder)
    cells = notebook["cells"]
    namespace = {"__name__": "__notebook__"}
    for i, cell in enumerate(c for c in cells if c["cell_type"] == "code"):
        source = "".join(cell["source"])
        exec(compile(source, f"{path.name}[code cell {i}]", "exec"), namespace)


def test_there_is_a_notebook():
    assert NOTEBOOKS, "notebooks/ holds no notebook"
