"""Optical-flow sources between consecutive left images, and the ``flow_source`` factory.

Every source is a :class:`~twistslam.perception.stage.FlowStage`: called with the previous and
the current :class:`~twistslam.datasets.Frame`, it returns (H, W, 2) float32 (u, v) pixels.

- ``files``: the sequence's own flow files, ``<split>/flow_noc/<seq>/NNNNNN.png`` (KITTI flow
  PNG; ``.flo`` is read too). File N holds the flow from frame N to frame N + 1, as the
  simulator writes it (and as KITTI's ``NNNNNN_10.png`` is the flow from image 10 to 11).
- ``dis``: OpenCV DIS in the C++ core, the default classical source (no weights). In a run it
  is computed only over the box around both frames' object instances (:func:`object_region`;
  ``DisOptions.object_region``): the flow serves the object search alone.
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


#: Pixels added around the instances' box by :func:`object_region`. 32: on the simulator's
#: urban seeds 0 / 2 and crowded seed 1 (frames 1-59, every other one), DIS on the box gave
#: about the whole image's endpoint error on the previous frame's instance pixels (share above
#: 3 px 0.157 / 0.162 / 0.042 against 0.149 / 0.165 / 0.041) in 61-70 % of its time; 8-16 px
#: raised the share above 3 px (0.161-0.181 on urban: DIS lacks context at the crop's edge).
DIS_REGION_MARGIN_PX = 32
#: A region narrower or lower than this is widened to it (within the image): OpenCV DIS
#: refuses images under its patch size, and the coarse-to-fine pyramid needs a few levels.
DIS_REGION_MIN_SIDE_PX = 64


def _widened(lo: int, hi: int, size: int, min_side: int) -> tuple[int, int]:
    """[lo, hi) grown about its centre to at least min(min_side, size) pixels inside [0, size)."""
    side = min(min_side, size)
    if hi - lo >= side:
        return lo, hi
    lo = min(max(0, (lo + hi - side) // 2), size - side)
    return lo, lo + side


def object_region(instance_images, margin_px: int = DIS_REGION_MARGIN_PX
                  ) -> tuple[int, int, int, int] | None:
    """The box ``(x0, y0, x1, y1)`` (pixels, ends exclusive) around every pixel with an
    instance (id > 0) in any of ``instance_images`` (equal-shape int arrays; ``None`` entries
    are skipped), widened by ``margin_px`` and clipped to the image; ``None`` when no image
    has an instance pixel (or all are ``None``)."""
    box, shape = None, None
    for ids in instance_images:
        if ids is None:
            continue
        ids = np.asarray(ids)
        shape = ids.shape[:2]
        on = ids > 0
        rows, cols = np.flatnonzero(on.any(axis=1)), np.flatnonzero(on.any(axis=0))
        if not len(rows):
            continue
        this = (cols[0], rows[0], cols[-1] + 1, rows[-1] + 1)
        box = this if box is None else (min(box[0], this[0]), min(box[1], this[1]),
                                        max(box[2], this[2]), max(box[3], this[3]))
    if box is None:
        return None
    height, width = shape
    return (max(0, int(box[0]) - margin_px), max(0, int(box[1]) - margin_px),
            min(width, int(box[2]) + margin_px), min(height, int(box[3]) + margin_px))


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
    #: 0 skips the refinement (the preset's 5): measured on 24 simulated sequences (2026-12-07,
    #: docs/visual_objects.md) a third less flow time (55 -> 35 ms), better error means, one
    #: more ghost and no loop rate gained (the main thread bounds it): kept at the preset's
    variational_refinement_iterations: int = -1
    use_spatial_propagation: bool = True
    #: Given both frames' instance images (a run gives them), DIS runs only on the box around
    #: their instances (:func:`object_region`, ``region_margin_px`` around). Measured on the
    #: simulator's urban and crowded seeds 0-4 (``bench_objects.py --rows dis``): flow 53-59
    #: -> 29-43 ms, the loop 6.0-7.8 -> 6.1-10.4 Hz (urban +15-33 %, crowded +3-5 %), the same
    #: cars tracked (44 of 49) and ghosts (5), mean object RPE_r 0.213 -> 0.218 deg/m and
    #: aligned ATE 0.090 -> 0.097 m: DIS fails more often on fast oncoming cars without the
    #: whole image around them (endpoint error above 10 px on 11 -> 14 % of their pixels).
    #: False: the whole image, the most accurate flow.
    object_region: bool = True
    region_margin_px: int = DIS_REGION_MARGIN_PX

    def core_options(self) -> dict:
        """The keyword arguments of ``_core.perception.dis_flow``."""
        options = asdict(self)
        del options["object_region"], options["region_margin_px"]
        return options


class DisFlow:
    """Flow from OpenCV DIS between the left images of two frames.

    ``region=(x0, y0, x1, y1)`` (pixels, ends exclusive) limits DIS to that box of both
    images, widened to at least :data:`DIS_REGION_MIN_SIDE_PX` a side: the flow outside it is
    NaN (no value), what the object search reads as "no flow" (it then searches around the
    motion model's prediction). ``instances=(previous, current)`` instance images: with
    ``options.object_region`` and no ``region``, the region is :func:`object_region` of them
    (the whole image when neither has an instance)."""

    #: A run passes both frames' instance images (:meth:`Perception.optical_flow`).
    accepts_instances = True

    def __init__(self, options: DisOptions | None = None, **overrides) -> None:
        self.options = DisOptions(**{**asdict(options or DisOptions()), **overrides})
        if self.options.region_margin_px < 0:
            raise ValueError(f"DisOptions.region_margin_px = {self.options.region_margin_px}: "
                             "expected pixels >= 0")

    def __call__(self, previous: Frame, current: Frame,
                 region: tuple[int, int, int, int] | None = None,
                 instances: tuple[np.ndarray | None, np.ndarray | None] | None = None) -> np.ndarray:
        for name, frame in (("previous", previous), ("current", current)):
            if frame.image_left is None:
                raise ValueError(f"DIS flow: frame {frame.index} ({name}) has no left image")
        a, b = previous.image_left, current.image_left
        if region is None and instances is not None and self.options.object_region:
            region = object_region(instances, self.options.region_margin_px)
        if region is None:
            return _core.perception.dis_flow(a, b, **self.options.core_options())
        height, width = np.asarray(a).shape[:2]
        x0, y0, x1, y1 = (int(v) for v in region)
        if not (0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height):
            raise ValueError(f"DIS flow: region {tuple(region)} is not a non-empty box inside the "
                             f"{width}x{height} image (x0, y0, x1, y1; ends exclusive)")
        x0, x1 = _widened(x0, x1, width, DIS_REGION_MIN_SIDE_PX)
        y0, y1 = _widened(y0, y1, height, DIS_REGION_MIN_SIDE_PX)
        flow = np.full((height, width, 2), np.nan, np.float32)
        flow[y0:y1, x0:x1] = _core.perception.dis_flow(
            np.ascontiguousarray(np.asarray(a)[y0:y1, x0:x1]),
            np.ascontiguousarray(np.asarray(b)[y0:y1, x0:x1]), **self.options.core_options())
        return flow


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
