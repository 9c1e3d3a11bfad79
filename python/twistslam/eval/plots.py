"""Bird-view trajectory plots (x right, z forward of the first camera) as PNG files."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .metrics import SequenceMetrics


def _figure(size: float):
    """A figure drawn by the Agg canvas directly: no pyplot, so no window and no change of
    the user's global backend (e.g. inline plots in a notebook)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(size, size))
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def _xz(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    ok = np.isfinite(positions).all(axis=1)
    return positions[ok, 0], positions[ok, 2]


def plot_trajectories(metrics: SequenceMetrics, out_dir: str | Path) -> list[Path]:
    """Write ``<seq>_camera_bev.png`` and ``<seq>_objects_bev.png`` (those with data).

    Ground truth is drawn solid, the estimate dashed in the same colour; object tracks are
    labelled with their ground-truth id. Returns the written paths.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    traj, written = metrics.trajectories, []

    if traj.camera_gt is not None:
        fig, ax = _figure(6)
        ax.plot(*_xz(traj.camera_gt[:, :3, 3]), "k-", label="ground truth")
        if traj.camera_est is not None:
            ax.plot(*_xz(traj.camera_est[:, :3, 3]), "C3--", label="estimate")
        _finish(ax, f"sequence {metrics.seq}: camera (bird view)")
        written.append(_save(fig, out_dir / f"{metrics.seq}_camera_bev.png"))

    if traj.objects:
        fig, ax = _figure(7)
        if traj.camera_gt is not None:
            ax.plot(*_xz(traj.camera_gt[:, :3, 3]), color="0.6", lw=1, label="camera")
        for k, (tid, (gt_xyz, est_xyz)) in enumerate(sorted(traj.objects.items())):
            colour = f"C{k % 10}"
            x, z = _xz(gt_xyz)
            ax.plot(x, z, "-", color=colour, lw=1.5)
            if len(x):
                ax.annotate(str(tid), (x[0], z[0]), fontsize=7, color=colour)
            if est_xyz is not None:
                ax.plot(*_xz(est_xyz), "--", color=colour, lw=1)
        ax.plot([], [], "k-", label="object ground truth")
        ax.plot([], [], "k--", label="object estimate")
        frame = f" [{metrics.world_frame}]" if metrics.world_frame else ""
        _finish(ax, f"sequence {metrics.seq}: objects (bird view){frame}")
        written.append(_save(fig, out_dir / f"{metrics.seq}_objects_bev.png"))
    return written


def _finish(ax, title: str) -> None:
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, lw=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title, fontsize=10)


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path
