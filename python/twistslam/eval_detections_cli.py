"""``twistslam eval-detections GT DETS``: KITTI object detection AP of a detector's output.

``GT`` is either a KITTI object root (``GT/training/label_2/NNNNNN.txt``; also ``GT/label_2``
or the label folder itself) or a KITTI tracking root (``GT/training/label_02/SEQ.txt``, with
``--seq``; also a label file itself). ``DETS`` is one of

* a folder of KITTI object result files ``NNNNNN.txt`` (16 columns, the score last): the
  frames evaluated are the files present, as the devkit does; each needs its label;
* a tracking result file (``frame track_id type ...`` with a score, 18 columns), or a folder
  holding ``SEQ.txt`` in that format when ``--seq`` is given;
* a PointRCNN / AB3DMOT comma-separated detection file (``frame, type, x1, ...``).

With a single detection file, every frame present in the labels or the detections is
evaluated (a frame without detections has all its objects missed). Malformed lines are
reported by the readers as ``file:line: what``.

The command is registered in :mod:`twistslam.cli` through :func:`add_eval_detections`.
"""

from __future__ import annotations

import argparse
import errno
import json
from pathlib import Path

from .datasets import ObjectTable, read_detection_file, read_labels, read_object_labels
from .eval.detection_ap import CLASSES, METRICS, SAMPLINGS, evaluate_detections

Tables = ObjectTable | dict[int, ObjectTable]


def _missing(path: Path, what: str) -> FileNotFoundError:
    return FileNotFoundError(errno.ENOENT, f"{what} not found: {path}", str(path))


#: digits of a KITTI object frame file name (``000123.txt``); tracking files have 4 (``0001``)
FRAME_NAME_DIGITS = 6


def _numbered_files(folder: Path) -> dict[int, Path]:
    """``{frame: path}`` of the ``NNNNNN.txt`` files of a folder."""
    return {int(p.stem): p for p in sorted(folder.glob("*.txt"))
            if p.stem.isdigit() and len(p.stem) == FRAME_NAME_DIGITS}


def _label_folder(gt: Path, split: str) -> Path | None:
    """The object-layout label folder under ``gt``, if it has one."""
    for folder in (gt / split / "label_2", gt / "label_2"):
        if folder.is_dir():
            return folder
    return gt if _numbered_files(gt) else None


def _tracking_label_file(gt: Path, seq: str | None, split: str) -> Path | None:
    folder = next((f for f in (gt / split / "label_02", gt / "label_02") if f.is_dir()), None)
    if folder is None:
        return None
    if seq is None:
        raise ValueError(f"{gt} is a KITTI tracking root ({folder}): name the sequence "
                         "with --seq, e.g. --seq 0001")
    path = folder / f"{seq}.txt"
    if not path.is_file():
        raise _missing(path, f"labels of sequence {seq}")
    return path


def load_ground_truth(gt: str | Path, seq: str | None = None,
                      split: str = "training") -> tuple[Tables, str]:
    """Labels under ``gt`` and the layout they came from (``"object"`` or ``"tracking"``).

    Object labels come back as ``{frame: ObjectTable}`` with every label file's frame (even
    one without objects); tracking labels as one :class:`ObjectTable`.
    """
    gt = Path(gt)
    if gt.is_file():
        return read_labels(gt), "tracking"
    if not gt.is_dir():
        raise _missing(gt, "ground truth")
    tracking = _tracking_label_file(gt, seq, split)
    if tracking is not None:
        return read_labels(tracking), "tracking"
    folder = _label_folder(gt, split)
    if folder is None:
        raise ValueError(f"{gt}: no KITTI labels found (expected {split}/label_2/NNNNNN.txt "
                         f"or {split}/label_02/SEQ.txt)")
    return {f: read_object_labels(p, frame=f) for f, p in _numbered_files(folder).items()}, \
        "object"


def load_detections(dets: str | Path, seq: str | None = None) -> tuple[Tables, bool]:
    """Detections under ``dets`` and whether they came from per-frame files (whose names
    then fix the evaluated frames)."""
    dets = Path(dets)
    if dets.is_file():
        return read_detection_file(dets), False
    if not dets.is_dir():
        raise _missing(dets, "detections")
    if seq is not None and (dets / f"{seq}.txt").is_file():
        return read_detection_file(dets / f"{seq}.txt"), False
    files = _numbered_files(dets)
    if not files:
        raise ValueError(f"{dets}: no detection files NNNNNN.txt"
                         + (f" nor {seq}.txt" if seq is not None else ""))
    return {f: read_object_labels(p, frame=f) for f, p in files.items()}, True


def _frames_to_evaluate(gt: Tables, gt_layout: str, dets: Tables, per_frame_files: bool,
                        gt_path: Path) -> list[int] | None:
    """Evaluated frames (``None``: every frame of either side); refuses a detection frame
    whose object label file is missing."""
    det_frames = sorted(dets) if isinstance(dets, dict) else [int(f) for f in dets.frames]
    if gt_layout == "object":
        unlabelled = [f for f in det_frames if f not in gt]
        if unlabelled:
            raise ValueError(f"{gt_path}: no label file for detected frame "
                             f"{unlabelled[0]:06d} ({len(unlabelled)} frames without labels)")
    if per_frame_files:
        return det_frames
    return None


def run_eval_detections(args: argparse.Namespace) -> int:
    """Handler of ``twistslam eval-detections``: prints the AP table, writes ``--json``."""
    from .input_checks import check_output_file

    if args.json:
        check_output_file(args.json, "--json")  # before the evaluation, not after it
    gt, layout = load_ground_truth(args.gt, args.seq, args.split)
    dets, per_frame_files = load_detections(args.dets, args.seq)
    frames = _frames_to_evaluate(gt, layout, dets, per_frame_files, Path(args.gt))
    result = evaluate_detections(
        gt, dets, classes=args.classes, metrics=args.metrics,
        iou=args.iou if args.iou else None, frames=frames, sampling=args.sampling,
    )
    print(result.table(), end="")
    out = result.to_dict()
    if args.box_ends:
        from .eval.box_ends import evaluate_box_ends

        ends = [evaluate_box_ends(gt, dets, cls, frames=frames) for cls in args.classes]
        for e in ends:
            if e.n_matched:
                print(e.table(), end="")
        out["box_ends"] = [e.to_dict() for e in ends]
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {path}")
    return 0


def _iou(text: str) -> float:
    value = float(text)
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 1], got {text}")
    return value


def add_eval_detections(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``twistslam eval-detections`` on the ``twistslam`` sub-command parsers."""
    p = sub.add_parser(
        "eval-detections",
        help="KITTI object detection AP (2D, bird view, 3D) of detections against labels",
        description="AP_R40 of 3D detections per class and difficulty (easy, moderate, hard) "
        "at the KITTI object benchmark's IoU thresholds (Car 0.7 / 0.5, Pedestrian and "
        "Cyclist 0.5 / 0.25), in the image, the bird view and 3D, with the devkit's rules "
        "(neighbour classes, DontCare regions and small detections ignored).",
    )
    p.add_argument("gt", help="KITTI object root (training/label_2) or tracking root "
                              "(training/label_02/SEQ.txt, with --seq), or a label file")
    p.add_argument("dets", help="folder of NNNNNN.txt result files, a tracking result file "
                                "(or a folder holding SEQ.txt), or a PointRCNN comma file")
    p.add_argument("--seq", help="tracking sequence number, e.g. 0001")
    p.add_argument("--split", default="training", help="dataset split folder (default: training)")
    p.add_argument("--classes", nargs="+", default=list(CLASSES), metavar="CLASS",
                   help="evaluated classes (default: %(default)s)")
    p.add_argument("--metrics", nargs="+", default=list(METRICS), choices=METRICS,
                   help="overlap metrics (default: %(default)s)")
    p.add_argument("--iou", nargs="+", type=_iou, metavar="IOU",
                   help="IoU thresholds for every class (default: each class's strict and "
                        "loose thresholds)")
    p.add_argument("--sampling", default="exact", choices=SAMPLINGS,
                   help="recall sampling: exact (the AP_R40 definition, right on few boxes) "
                        "or devkit (the KITTI devkit's / OpenPCDet's shortcut)")
    p.add_argument("--json", metavar="FILE", help="write every curve and AP as JSON")
    p.add_argument("--box-ends", action="store_true",
                   help="also where the boxes end: median offsets of each matched box's near "
                        "and far end along its label's length, by view angle and range "
                        "(twistslam.eval.box_ends)")
    p.set_defaults(handler=run_eval_detections)
    return p
