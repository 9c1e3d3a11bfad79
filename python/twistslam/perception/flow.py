"""Optical-flow sources between consecutive left images, and the ``flow_source`` factory.

Every source is a :class:`~twistslam.perception.stage.FlowStage`: called with the previous and
the current :class:`~twistslam.datasets.Frame`, it returns (H, W, 2) float32 (u, v) pixels.

- ``files``: the sequence's own flow files, ``<split>/flow_noc/<seq>/NNNNNN.png`` (KITTI flow
  PNG; ``.flo`` is read too). File N holds the flow from frame N to frame N + 1, as the
  simulator writes it (and as KITTI's ``NNNNNN_10.png`` is the flow from image 10 to 11).
- ``dis``: OpenCV DIS in the C++ core, the default classical source (no weights).
- ``raft``: RAFT (``raft_small`` / ``raft_large``, plain torch, torchvision's state-dict layout) from a
  weight file the user names (:mod:`.flow_raft`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from twistslam import _core
from twistslam.datasets import Frame

from .flow_files import read_flo, read_kitti_flow
from .flow_raft import RaftFlow
from .stage import check_flow

FLOW_KINDS = ("auto", "files", "dis", "raft")


@dataclass
class DisOptions:
    """Options of OpenCV DIS (see ``twistslam._core.perception.dis_flow``); -1 keeps the
    preset's value. ``medium`` is the preset measured in docs / tests: ~0.3 px median error
    on the simulator's urban scenes, ~30 ms at 1242x375 on one core."""

    preset: str = "medium"
    finest_scale_level: int = -1  # 0 = full resolution
    patch_size_px: int = -1
    patch_stride_px: int = -1
    gradient_descent_iterations: int = -1
    variational_refinement_iterations: int = -1
    use_spatial_propagation: bool = True


class DisFlow:
    """Flow from OpenCV DIS between the left images of two frames."""

    def __init__(self, options: DisOptions | None = None, **overrides) -> None:
        self.options = DisOptions(**{**asdict(options or DisOptions()), **overrides})

    def __call__(self, previous: Frame, current: Frame) -> np.ndarray:
        for name, frame in (("previous", previous), ("current", current)):
            if frame.image_left is None:
                raise ValueError(f"DIS flow: frame {frame.index} ({name}) has no left image")
        return _core.perception.dis_flow(previous.image_left, current.image_left, **asdict(self.options))


class FileFlow:
    """Flow read from ``folder/NNNNNN.png`` (KITTI flow PNG) or ``NNNNNN.flo``: file N is the
    flow from frame N to frame N + 1."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise FileNotFoundError(f"flow files: {self.folder} is not a folder")

    def path(self, index: int) -> Path:
        for ext in (".png", ".flo"):
            path = self.folder / f"{index:06d}{ext}"
            if path.is_file():
                return path
        raise FileNotFoundError(f"flow files: neither {index:06d}.png nor {index:06d}.flo in {self.folder}")

    def __call__(self, previous: Frame, current: Frame) -> np.ndarray:
        if current.index != previous.index + 1:
            raise ValueError(f"flow files hold the flow between consecutive frames, not {previous.index} -> "
                             f"{current.index}")
        path = self.path(previous.index)
        flow = read_flo(path) if path.suffix == ".flo" else read_kitti_flow(path)
        if previous.image_left is not None:
            flow = check_flow(flow, previous.image_left.shape[:2], str(path))
        return flow


def flow_folder(sequence, occlusions: str = "noc") -> Path | None:
    """``<split>/flow_<occlusions>/<seq>`` of a KITTI-layout sequence when it holds files."""
    base, seq = getattr(sequence, "base", None), getattr(sequence, "seq", None)
    if base is None or seq is None:
        return None
    folder = Path(base) / f"flow_{occlusions}" / str(seq)
    return folder if folder.is_dir() and any(folder.iterdir()) else None


def flow_source(kind: str = "auto", sequence=None, *, occlusions: str = "noc", dis: DisOptions | None = None,
                weights: str | Path | None = None, raft_model: str = "raft_small"):
    """The flow stage of ``kind`` for ``sequence``.

    Parameters
    ----------
    kind : "auto" (files when the sequence has them, else DIS), "files", "dis" or "raft".
    sequence : a :class:`~twistslam.datasets.KittiTracking` (needed for "files").
    occlusions : "noc" (pixels visible in both images; the default) or "occ" (also the
        pixels hidden in the next image), the KITTI flow folder read by "files".
    dis : options of the DIS source.
    weights, raft_model : the RAFT source's state-dict file and architecture
        ("raft_small" / "raft_large"); "raft" requires ``weights``.
    """
    if kind not in FLOW_KINDS:
        raise ValueError(f"flow source '{kind}': expected one of {', '.join(FLOW_KINDS)}")
    if occlusions not in ("noc", "occ"):
        raise ValueError(f"flow occlusions '{occlusions}': expected 'noc' or 'occ'")
    folder = flow_folder(sequence, occlusions) if sequence is not None else None
    if kind == "files" or (kind == "auto" and folder is not None):
        if folder is None:
            raise FileNotFoundError(f"flow source 'files': {sequence} has no flow_{occlusions}/ files")
        return FileFlow(folder)
    if kind == "raft":
        return RaftFlow(weights, raft_model)
    return DisFlow(dis)
