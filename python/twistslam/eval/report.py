"""Tables of a sequence evaluation, laid out like the paper's (``seq / obj. id / class`` rows).

Tables are built once as plain rows of strings (:class:`Table`) and rendered either as
fixed-width text (the terminal) or Markdown (``make demo``'s report). When a path to the
paper's ``tables.json`` is given, the paper's rows for the same sequence / object are printed
beneath ours, one per system, so a run on real KITTI can be read against the publication.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .metrics import OBJECT_KEYS, SequenceMetrics

POSE_COLUMNS = [("ate", "ATE (m)"), ("rpe_t", "RPE_t (m/m)"), ("rpe_r", "RPE_R (deg/m)"),
                ("yaw", "yaw (deg)")]
DETECTION_COLUMNS = [
    ("tp_2d", "2D TP"), ("motp_2d", "2D MOTP"), ("tp_bv", "BV TP"),
    ("motp_bv", "BV MOTP"), ("tp_3d", "3D TP"), ("motp_3d", "3D MOTP"),
]
CAMERA_COLUMNS = [
    ("rpe_t_mean", "RPE_t (m/f)"), ("rpe_r_mean", "RPE_R (deg/f)"),
    ("rpe_t_rmse", "RPE_t rmse"), ("rpe_r_rmse", "RPE_R rmse"), ("ate_rmse", "ATE (m)"),
]
MOT_COLUMNS = [
    ("mota", "MOTA"), ("motp", "MOTP"), ("tp_rate", "TP"), ("idsw", "IDSW"), ("frag", "FRAG"),
    ("fp", "FP"), ("fn", "FN"), ("mt", "MT"), ("ml", "ML"), ("samota", "sAMOTA"),
    ("amota", "AMOTA"), ("amotp", "AMOTP"), ("hota", "HOTA"), ("deta", "DetA"),
    ("assa", "AssA"),
]


@dataclass
class Table:
    title: str
    header: list[str]
    rows: list[list[str]]
    notes: list[str] = field(default_factory=list)  # printed under the table


def fmt(value, digits: int = 3) -> str:
    """A number for a table cell; ``-`` where there is none (NaN / None)."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, (int, np.integer)):
        return str(value)
    return f"{value:.{digits}f}"


def load_paper_tables(path: str | Path) -> dict:
    """The paper's numbers (``paper/tables.json``): ``{"camera": {system: {seq: {...}}},
    "objects": {system: [row, ...]}}``."""
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def _same_seq(a: str, b: str) -> bool:
    # the paper writes "03", our results "0003"
    return a.isdigit() and b.isdigit() and int(a) == int(b)


def object_label(seq: str, track_id: int, cls: str) -> str:
    return f"{int(seq):02d} / {track_id} / {cls}"


def _cells(values, columns, digits: int) -> list[str]:
    return [fmt(values.get(key), digits) for key, _ in columns]


def _paper_objects(paper: dict | None, seq: str, track_id: int) -> list[tuple[str, dict]]:
    """(system, row) of every system of the paper that reports this object."""
    return [
        (system, r)
        for system, rows in (paper or {}).get("objects", {}).items()
        for r in rows
        if _same_seq(str(r.get("seq")), seq) and r.get("track_id") == track_id
    ]


def _object_tables(runs: list[SequenceMetrics], paper: dict | None) -> list[Table]:
    first = ["seq / obj. id / class", "system"]
    pose = Table("Object pose (ATE m, RPE_t m/m, RPE_R deg/m, yaw error deg)",
                 first + [h for _, h in POSE_COLUMNS], [])
    det = Table("Object boxes (TP and MOTP in %)", first + [h for _, h in DETECTION_COLUMNS], [])
    all_rows = []
    for run in runs:
        aligned = run.settings.object_alignment == "se3"
        for obj in run.objects:
            label, values = object_label(run.seq, obj.track_id, obj.cls), obj.values(aligned)
            all_rows.append(values)
            pose.rows.append([label, "ours"] + _cells(values, POSE_COLUMNS, 3))
            det.rows.append([label, "ours"] + _cells(values, DETECTION_COLUMNS, 2))
            for system, r in _paper_objects(paper, run.seq, obj.track_id):
                pose.rows.append(["", system] + _cells(r, POSE_COLUMNS, 2))
                det.rows.append(["", system] + _cells(r, DETECTION_COLUMNS, 2))
        if run.objects:
            ate = "SE(3)-aligned" if aligned else "canonical"
            where = (f"objects placed in the world with the {run.world_frame}"
                     if run.world_frame != "camera frame" else
                     "no ground-truth camera poses: objects compared in each frame's camera frame")
            pose.notes.append(f"{run.seq}: {ate} ATE; {where}")
            det.notes.append(f"{run.seq}: {protocol_note(run.settings.protocol)}")
    if all_rows:
        # over all tracks of all sequences, as the paper's mean row
        mean = {k: _nanmean(r[k] for r in all_rows) for k in OBJECT_KEYS}
        pose.rows.append(["mean", "ours"] + _cells(mean, POSE_COLUMNS, 3))
        det.rows.append(["mean", "ours"] + _cells(mean, DETECTION_COLUMNS, 2))
    return [pose, det]


def _nanmean(values: Iterable[float]) -> float:
    vals = [v for v in values if v is not None and not math.isnan(v)]
    return sum(vals) / len(vals) if vals else float("nan")


def _camera_table(runs: list[SequenceMetrics], paper: dict | None) -> Table:
    cam = Table("Camera", ["seq", "system"] + [h for _, h in CAMERA_COLUMNS], [])
    for run in (r for r in runs if r.camera is not None):
        cam.rows.append([f"{int(run.seq):02d}", "ours"]
                        + _cells(run.camera.to_dict(), CAMERA_COLUMNS, 3))
        for system, seqs in (paper or {}).get("camera", {}).items():
            for key, r in seqs.items():
                if _same_seq(key, run.seq):  # the paper gives mean RPE only
                    cam.rows.append(["", system, fmt(r.get("rpe_t"), 2), fmt(r.get("rpe_r"), 2)]
                                    + ["-"] * 3)
        if run.camera.n_skipped:
            cam.notes.append(f"{run.seq}: {run.camera.n_skipped} of {run.camera.n_frames} "
                             "frames have no estimate (skipped)")
        if run.camera.n_beyond_gt:
            cam.notes.append(f"{run.seq}: evaluated on frames 0-{run.camera.n_frames - 1}, the "
                             f"ground truth's; {run.camera.n_beyond_gt} estimated frames after "
                             "them are not evaluated")
    cam.notes.append("ATE after SE(3) Umeyama alignment; RPE over consecutive frames")
    return cam


def protocol_note(protocol: str) -> str:
    """One line naming a protocol and its rules, printed under the tables it produced."""
    from .protocol import get_protocol

    return f"protocol {protocol}: {get_protocol(protocol).description}"


def _mot_table(runs: list[SequenceMetrics]) -> Table:
    s = runs[0].settings
    protocols = sorted({run.settings.protocol for run in runs if run.mot})
    title = (f"CLEAR MOT ({'/'.join(protocols)} protocol; {s.cls}, {s.difficulty.name}, "
             f"IoU >= {s.iou_threshold:g}; all but IDSW, FRAG, FP, FN in %)")
    mot = Table(title, ["seq", "overlap"] + [h for _, h in MOT_COLUMNS], [])
    for run in runs:
        for mode, m in run.mot.items():
            mot.rows.append([f"{int(run.seq):02d}", mode.upper()]
                            + _cells(vars(m), MOT_COLUMNS, 2))
    mot.notes += [protocol_note(p) for p in protocols]
    mot.notes.append("sAMOTA, AMOTA, AMOTP: AB3DMOT's averages over 40 recall-sampled score "
                     "thresholds; HOTA, DetA, AssA: means over alpha 0.05..0.95 (TrackEval)")
    return mot


def build_tables(
    runs: SequenceMetrics | list[SequenceMetrics], paper: dict | None = None
) -> list[Table]:
    """The report's tables for one or several evaluated sequences: camera, object pose,
    object boxes, CLEAR MOT (each only when some sequence has its inputs)."""
    runs = [runs] if isinstance(runs, SequenceMetrics) else list(runs)
    tables = []
    if any(run.camera for run in runs):
        tables.append(_camera_table(runs, paper))
    if any(run.mot for run in runs):
        tables += _object_tables(runs, paper) + [_mot_table(runs)]
    return tables


def _widths(table: Table) -> list[int]:
    return [max(len(r[i]) for r in [table.header] + table.rows) for i in range(len(table.header))]


def render_text(runs, paper: dict | None = None) -> str:
    """Fixed-width text: first column left-aligned, numbers right-aligned."""
    blocks = []
    for t in build_tables(runs, paper):
        w = _widths(t)
        line = lambda cells: "  ".join(  # noqa: E731
            c.ljust(w[i]) if i < 2 else c.rjust(w[i]) for i, c in enumerate(cells)
        ).rstrip()
        rule = "-" * len(line(t.header))
        blocks.append("\n".join([t.title, rule, line(t.header), rule]
                                + [line(r) for r in t.rows] + [rule] + t.notes))
    return "\n\n".join(blocks) + "\n"


def render_markdown(runs, paper: dict | None = None) -> str:
    """GitHub-flavoured Markdown tables, one ``###`` section per table."""
    blocks = []
    for t in build_tables(runs, paper):
        rows = [t.header, ["---", "---"] + ["---:"] * (len(t.header) - 2)] + t.rows
        notes = "".join(f"\n\n*{n}*" for n in t.notes)
        blocks.append(f"### {t.title}\n\n" + "\n".join("| " + " | ".join(r) + " |" for r in rows)
                      + notes)
    return "\n\n".join(blocks) + "\n"
