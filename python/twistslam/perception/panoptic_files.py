"""Panoptic labels from files: the simulator's 16-bit PNGs and the COCO panoptic format.

- Simulator / Cityscapes ``instanceIds``: one single-channel PNG per frame,
  ``<base>/panoptic/<seq>/NNNNNN.png``; stuff = class id, things = ``class * 1000 + k``.
- COCO panoptic (what Detectron2-style tools write): an RGB PNG whose colour encodes a segment
  id ``R + 256 G + 256^2 B`` (0 = no segment), and a JSON file whose ``annotations[].
  segments_info`` give each segment's ``category_id``; ``categories`` name those ids. Names
  map to the Cityscapes vocabulary through :data:`COCO_TO_CITYSCAPES` (or a mapping the user
  passes); an unmapped category becomes unknown (static).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .panoptic import CITYSCAPES_CLASSES, UNKNOWN, Panoptic

#: COCO panoptic category names (things and merged stuff) -> Cityscapes ids; Cityscapes' own
#: names are accepted too (a Cityscapes-panoptic JSON names its categories that way)
COCO_TO_CITYSCAPES = {
    "person": 24, "bicycle": 33, "car": 26, "motorcycle": 32, "bus": 28, "train": 31,
    "truck": 27, "traffic light": 19, "stop sign": 20, "road": 7, "pavement-merged": 8,
    "building-other-merged": 11, "house": 11, "wall-other-merged": 12, "wall-brick": 12,
    "wall-stone": 12, "wall-wood": 12, "fence-merged": 13, "bridge": 15, "tree-merged": 21,
    "grass-merged": 22, "dirt-merged": 22, "sky-other-merged": 23, "railroad": 10,
    **{name: cid for cid, name in CITYSCAPES_CLASSES.items() if cid != UNKNOWN},
}


def read_sim_panoptic(path: str | Path) -> Panoptic:
    """Labels of one simulator (Cityscapes ``instanceIds``) PNG.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        The file is not a single-channel PNG, or holds ids outside the vocabulary.
    """
    from PIL import Image

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: panoptic PNG not found")
    try:
        with Image.open(path) as image:
            ids = np.array(image)
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the panoptic PNG: {exc}") from exc
    if ids.ndim != 2:
        raise ValueError(f"{path}: expected a single-channel 16-bit panoptic id image, "
                         f"got shape {ids.shape}")
    return Panoptic.from_cityscapes_ids(ids, source=str(path))


def load_coco_json(json_path: str | Path) -> tuple[dict[str, dict], dict[int, str]]:
    """A COCO panoptic JSON as (PNG file name -> annotation, category id -> name)."""
    json_path = Path(json_path)
    if not json_path.is_file():
        raise FileNotFoundError(f"{json_path}: COCO panoptic JSON not found")
    try:
        data = json.loads(json_path.read_text())
        names = {int(c["id"]): str(c["name"]) for c in data["categories"]}
        annotations = {Path(str(a["file_name"])).name: a for a in data["annotations"]}
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"{json_path}: not a COCO panoptic JSON (needs 'annotations' with "
                         f"'file_name' and 'segments_info', and 'categories'): {exc!r}") from exc
    return annotations, names


def read_coco_panoptic(png_path: str | Path, json_path: str | Path,
                       category_map: dict[str, int] | None = None, *,
                       loaded: tuple[dict, dict] | None = None) -> Panoptic:
    """Labels of one COCO panoptic PNG, described by its annotation in ``json_path``.

    Parameters
    ----------
    png_path : RGB PNG of segment ids (``R + 256 G + 256^2 B``, 0 = void -> unknown).
    json_path : COCO panoptic JSON whose annotation has this PNG's file name.
    category_map : category *name* -> Cityscapes id; default :data:`COCO_TO_CITYSCAPES`.
    loaded : ``load_coco_json(json_path)``, to parse a sequence's JSON once.

    Returns
    -------
    Panoptic
        Thing segments (category ``isthing`` or a dynamic Cityscapes class) get instance ids
        ``1..n`` in the JSON's order; stuff segments get instance 0.

    Raises
    ------
    FileNotFoundError
        The PNG or the JSON is missing.
    ValueError
        The PNG is not RGB, a segment id of the PNG is not in ``segments_info``, or a
        segment's category is not in ``categories`` -- each message names the file.
    """
    from PIL import Image

    png_path, json_path = Path(png_path), Path(json_path)
    if not png_path.is_file():
        raise FileNotFoundError(f"{png_path}: COCO panoptic PNG not found")
    annotations, names = loaded if loaded is not None else load_coco_json(json_path)
    ann = annotations.get(png_path.name)
    if ann is None or "segments_info" not in ann:
        raise ValueError(f"{json_path}: no annotation with file_name {png_path.name!r} "
                         "and a 'segments_info' list")
    with Image.open(png_path) as image:
        rgb = np.array(image)
    if rgb.ndim != 3 or rgb.shape[2] < 3 or rgb.dtype != np.uint8:
        raise ValueError(f"{png_path}: expected an 8-bit RGB PNG of segment ids, got "
                         f"shape {rgb.shape} {rgb.dtype}")
    rgb = rgb[..., :3].astype(np.int64)
    segment = rgb[..., 0] + 256 * rgb[..., 1] + 65536 * rgb[..., 2]
    mapping = COCO_TO_CITYSCAPES if category_map is None else category_map
    lut_ids, lut_class, lut_instance, things = [0], [UNKNOWN], [0], 0
    for info in ann["segments_info"]:
        category = int(info["category_id"])
        if category not in names:
            raise ValueError(f"{json_path}: segment {info['id']} of {png_path.name} has "
                             f"category_id {category}, not listed in 'categories'")
        class_id = int(mapping.get(names[category], UNKNOWN))
        is_thing = bool(info.get("isthing", class_id >= 24))
        things += is_thing
        lut_ids.append(int(info["id"]))
        lut_class.append(class_id)
        lut_instance.append(things if is_thing else 0)
    lut_ids = np.asarray(lut_ids)
    order = np.argsort(lut_ids)
    pos = np.searchsorted(lut_ids[order], segment)
    pos = np.clip(pos, 0, len(order) - 1)
    found = lut_ids[order][pos] == segment
    if not found.all():
        missing = np.unique(segment[~found])[:5].tolist()
        raise ValueError(f"{png_path}: segment ids {missing} are in the PNG but not in the "
                         f"segments_info of {json_path}")
    index = order[pos]
    return Panoptic(np.asarray(lut_class)[index], np.asarray(lut_instance)[index],
                    source=str(png_path))


class SimPanopticFiles:
    """Panoptic source ``frame -> Panoptic`` reading ``<folder>/NNNNNN.png`` (simulator)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise FileNotFoundError(f"{self.folder}: panoptic folder not found")

    @classmethod
    def of_sequence(cls, sequence, labels_dir: str = "panoptic") -> "SimPanopticFiles":
        """The files of a sequence on disk (``<base>/<labels_dir>/<seq>/``)."""
        return cls(Path(sequence.base) / labels_dir / str(sequence.seq))

    def __call__(self, frame) -> Panoptic:
        return read_sim_panoptic(self.folder / f"{frame.index:06d}.png")


class CocoPanopticFiles:
    """Panoptic source ``frame -> Panoptic`` reading ``<folder>/NNNNNN.png`` described by one
    COCO panoptic JSON (parsed once)."""

    def __init__(self, folder: str | Path, json_path: str | Path,
                 category_map: dict[str, int] | None = None) -> None:
        self.folder, self.json_path = Path(folder), Path(json_path)
        self.category_map = category_map
        self._loaded = load_coco_json(self.json_path)

    def __call__(self, frame) -> Panoptic:
        return read_coco_panoptic(self.folder / f"{frame.index:06d}.png", self.json_path,
                                  self.category_map, loaded=self._loaded)
