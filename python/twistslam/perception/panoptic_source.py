"""Choosing a panoptic source, and checking what any source (a user's function too) returns.

A panoptic stage is a callable ``stage(frame)`` returning a :class:`Panoptic` or a pair
``(class_id, instance_id)`` of (H, W) integer arrays; :func:`check_panoptic` turns either into
a checked :class:`Panoptic` of the frame's image size.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from .panoptic import Panoptic
from .panoptic_files import CocoPanopticFiles, SimPanopticFiles
from .panoptic_from_boxes import BoxMaskConfig, PanopticFromBoxes

#: the sources :func:`panoptic_source` builds
PANOPTIC_KINDS = ("auto", "files", "coco", "boxes", "torch")
#: keys of the ``weights`` mapping of the "torch" source (arguments of TorchPanoptic)
TORCH_WEIGHT_KEYS = {"maskrcnn": "maskrcnn_weights", "semantic": "semantic_weights",
                     "semantic_classes": "semantic_classes",
                     "num_semantic_classes": "num_semantic_classes"}


@runtime_checkable
class PanopticStage(Protocol):
    """Panoptic labels of a frame's left image: a :class:`Panoptic` or ``(class_id,
    instance_id)``, both (H, W) integers (Cityscapes ids, 0 = unknown; instance 0 = none)."""

    def __call__(self, frame) -> Panoptic | tuple[np.ndarray, np.ndarray]: ...


def check_panoptic(result, shape: tuple[int, int], source: str) -> Panoptic:
    """``result`` as a :class:`Panoptic` of image ``shape``; ValueError naming ``source``
    when a stage returned something else."""
    if not isinstance(result, Panoptic):
        try:
            class_id, instance_id = result
        except (TypeError, ValueError):
            raise ValueError(f"{source}: a panoptic stage must return a Panoptic or "
                             f"(class_id, instance_id), got {type(result).__name__}") from None
        result = Panoptic(np.asarray(class_id), np.asarray(instance_id), source=source)
    if result.shape != tuple(shape):
        raise ValueError(f"{source}: panoptic labels are {result.shape}, the image is "
                         f"{tuple(shape)} (H, W)")
    return result


def _sim_folder(sequence, labels_dir: str) -> Path | None:
    base, seq = getattr(sequence, "base", None), getattr(sequence, "seq", None)
    if base is None or seq is None:
        return None
    folder = Path(base) / labels_dir / str(seq)
    return folder if folder.is_dir() else None


def panoptic_source(kind: str = "auto", sequence=None, *, boxes=None,
                    coco_folder: str | Path | None = None, coco_json: str | Path | None = None,
                    box_config: BoxMaskConfig | None = None, labels_dir: str = "panoptic",
                    weights: dict | None = None):
    """The panoptic stage of ``kind`` for ``sequence``.

    Parameters
    ----------
    kind : "auto" (the sequence's panoptic files when it has them, else masks from ``boxes``),
        "files" (simulator / Cityscapes ``instanceIds`` PNGs), "coco" (COCO panoptic PNGs +
        JSON), "boxes" (masks from 3D boxes and the LiDAR scan) or "torch" (a Mask R-CNN
        and a semantic network from weight files, :class:`~.panoptic_torch.TorchPanoptic`).
    sequence : a sequence on disk (``base``, ``seq``), needed by "files".
    boxes : :class:`~twistslam.datasets.ObjectTable` of 3D boxes (detections), for "boxes".
    coco_folder, coco_json : the PNG folder and JSON file of "coco".
    weights : the files of "torch": ``{"maskrcnn": FILE, "semantic": FILE}`` (semantic
        optional), plus optionally ``"semantic_classes"`` and ``"num_semantic_classes"``.
    """
    if kind not in PANOPTIC_KINDS:
        raise ValueError(f"panoptic source '{kind}': expected one of {', '.join(PANOPTIC_KINDS)}")
    if kind == "torch":
        return _torch_source(weights)
    folder = _sim_folder(sequence, labels_dir)
    if kind == "files" or (kind == "auto" and folder is not None):
        if folder is None:
            raise FileNotFoundError(f"panoptic source 'files': {sequence} has no {labels_dir}/ "
                                    "folder of panoptic PNGs")
        return SimPanopticFiles(folder)
    if kind == "coco":
        if coco_folder is None or coco_json is None:
            raise ValueError("panoptic source 'coco' needs coco_folder (the PNGs) and coco_json")
        return CocoPanopticFiles(coco_folder, coco_json)
    if boxes is None:
        raise ValueError(f"panoptic source '{kind}': no panoptic files and no 3D boxes "
                         "(pass boxes=detections, or kind='coco' with its files)")
    return PanopticFromBoxes(boxes, box_config or BoxMaskConfig())


def _torch_source(weights: dict | None):
    if not weights or not weights.get("maskrcnn"):
        raise ValueError("panoptic source 'torch' needs weights={'maskrcnn': FILE, 'semantic': "
                         "FILE} (twistslam.run: segmentation_weights=...; command line: "
                         "--maskrcnn-weights FILE --semantic-weights FILE); nothing is downloaded")
    unknown = sorted(set(weights) - set(TORCH_WEIGHT_KEYS))
    if unknown:
        raise ValueError(f"panoptic source 'torch': unknown weights keys {unknown}; expected "
                         f"{', '.join(TORCH_WEIGHT_KEYS)}")
    from .panoptic_torch import TorchPanoptic

    return TorchPanoptic(**{TORCH_WEIGHT_KEYS[k]: v for k, v in weights.items() if v is not None})
