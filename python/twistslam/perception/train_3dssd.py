"""Training 3DSSD on KITTI-layout tracking sequences (real KITTI or the simulator's).

    train(["/data/sim-urban"], ["0000"], "3dssd.pt", epochs=40, preset="small")

Each labelled frame gives one sample: the LiDAR points the left camera sees, in frame l, and
its ``label_02`` boxes (the config's classes are targets, other object types are ignored
regions, DontCare is dropped). Augmentation as in 3DSSD's KITTI recipe, minus the pasting of
ground-truth objects from other scenes: a random flip across the x axis, a global rotation
about z and a global scaling. Adam with a cosine-decayed learning rate. The checkpoint is
rewritten at the end of every epoch, so a stopped run leaves usable weights.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from twistslam.datasets import KittiTracking

log = logging.getLogger(__name__)

#: global rotation range of the augmentation, radians (3DSSD/OpenPCDet KITTI: +-pi/4)
ROTATION_RANGE = math.pi / 4
#: global scaling range of the augmentation (3DSSD/OpenPCDet KITTI: 0.95-1.05)
SCALE_RANGE = (0.95, 1.05)
#: 3DSSD's Adam learning rate
LEARNING_RATE = 2e-3
#: the cosine schedule ends at this fraction of the initial rate
FINAL_LR_FRACTION = 0.05
#: training steps between two progress lines in the log
LOG_EVERY_STEPS = 50
#: object types that are neither targets nor background: points inside carry no loss
DONT_CARE = "DontCare"


@dataclass
class Sample:
    """One training frame: points (K, 4) frame l; boxes (G, 7) frame l with class indices;
    boxes of other object types (I, 7) frame l."""

    points: np.ndarray
    boxes: np.ndarray
    labels: np.ndarray
    ignore: np.ndarray
    name: str


def load_samples(roots, seqs, config, max_frames: int | None = None) -> list[Sample]:
    """Every labelled frame of sequences ``seqs`` under each root (KITTI tracking layout)."""
    from .torch_models.ssd3d_boxes import camera_to_lidar_boxes
    from .torch_models.ssd3d_input import frame_points, image_shape_of

    samples = []
    for root in roots:
        for seq in seqs:
            sequence = KittiTracking(root, seq)
            objects = sequence.gt_objects
            if objects is None:
                raise ValueError(f"{sequence}: no labels (label_02/{sequence.seq}.txt) to train on")
            labelled = sorted(set(objects.frame.tolist()))[:max_frames]
            for index in labelled:
                frame = sequence.frame(index)
                if frame.points_c is None:
                    continue
                points = frame_points(frame.points_c, frame.calib.P2, image_shape_of(frame), config.point_range)
                table = frame.objects_gt
                known = np.isin(table.cls, config.classes)
                other = ~known & (table.cls != DONT_CARE)
                labels = np.array([config.classes.index(c) for c in table.cls[known]], dtype=np.int64)
                samples.append(Sample(points, camera_to_lidar_boxes(table.box_3d[known]).astype(np.float32),
                                      labels, camera_to_lidar_boxes(table.box_3d[other]).astype(np.float32),
                                      f"{root}:{seq}:{index:06d}"))
    return samples


def augment(sample: Sample, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flipped (half the time), rotated and scaled copies of the points, boxes and ignored boxes."""
    points, boxes, ignore = sample.points.copy(), sample.boxes.copy(), sample.ignore.copy()
    if rng.random() < 0.5:  # mirror across the x (forward) axis
        for b in (boxes, ignore):
            b[:, 1] *= -1
            b[:, 6] *= -1
        points[:, 1] *= -1
    angle = rng.uniform(-ROTATION_RANGE, ROTATION_RANGE)
    scale = rng.uniform(*SCALE_RANGE)
    rotation = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]], np.float32)
    points[:, :2] = points[:, :2] @ rotation.T
    points[:, :3] *= scale
    for b in (boxes, ignore):
        b[:, :2] = b[:, :2] @ rotation.T
        b[:, :6] *= scale
        b[:, 6] += angle
    return points, boxes, ignore


def _batch(samples: list[Sample], config, rng, augmentation: bool):
    import torch

    from .torch_models.ssd3d_input import resample
    from .torch_models.ssd3d_targets import FrameTargets

    inputs, targets = [], []
    for sample in samples:
        points, boxes, ignore = (augment(sample, rng) if augmentation
                                 else (sample.points, sample.boxes, sample.ignore))
        inputs.append(resample(points, config.num_points, rng))
        targets.append(FrameTargets(torch.from_numpy(boxes), torch.from_numpy(sample.labels),
                                    torch.from_numpy(ignore)))
    return torch.from_numpy(np.stack(inputs)), targets


def train_model(model, samples: list[Sample], epochs: int, batch_size: int = 2, lr: float = LEARNING_RATE,
                seed: int = 0, augmentation: bool = True, on_epoch=None) -> list[dict[str, float]]:
    """Train ``model`` in place on ``samples``; returns the mean loss terms of each epoch.
    ``on_epoch(epoch, losses)`` is called after every epoch (the checkpoint writer)."""
    import torch

    if not samples:
        raise ValueError("no training frames")
    rng = np.random.default_rng(seed)
    torch.manual_seed(seed)
    optimiser = torch.optim.Adam(model.parameters(), lr=lr)
    steps = epochs * math.ceil(len(samples) / batch_size)

    def cosine(step: int) -> float:
        return FINAL_LR_FRACTION + (1 - FINAL_LR_FRACTION) * 0.5 * (1 + math.cos(math.pi * step / steps))

    schedule = torch.optim.lr_scheduler.LambdaLR(optimiser, cosine)
    history = []
    for epoch in range(epochs):
        model.train()
        order = rng.permutation(len(samples))
        sums: dict[str, float] = {}
        started = time.monotonic()
        for begin in range(0, len(order), batch_size):
            points, targets = _batch([samples[i] for i in order[begin:begin + batch_size]], model.config,
                                     rng, augmentation)
            losses = model.losses(model(points), targets)
            optimiser.zero_grad()
            losses["total"].backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)  # 3DSSD's gradient clipping
            optimiser.step()
            schedule.step()
            for key, value in losses.items():
                sums[key] = sums.get(key, 0.0) + value.item() * len(targets)
            step = begin // batch_size + 1
            if step % LOG_EVERY_STEPS == 0:
                log.info("epoch %d step %d: total %.3f (%.1f s/step)", epoch + 1, step,
                         losses["total"].item(), (time.monotonic() - started) / step)
        means = {key: value / len(samples) for key, value in sums.items()}
        history.append(means)
        log.info("epoch %d/%d: %s (%.0f s)", epoch + 1, epochs,
                 " ".join(f"{k} {v:.3f}" for k, v in means.items()), time.monotonic() - started)
        if on_epoch is not None:
            on_epoch(epoch, means)
    return history


def train(roots, seqs, out, epochs: int = 40, preset: str = "small", batch_size: int = 2,
          lr: float = LEARNING_RATE, seed: int = 0, max_frames: int | None = None, threads: int | None = None) -> Path:
    """Train a 3DSSD of size ``preset`` (``tiny``, ``small``, ``full``) on the labelled frames
    of ``seqs`` under every root and write the checkpoint ``out`` (after every epoch).

    Returns the checkpoint path."""
    import torch

    from .torch_models.ssd3d_checkpoint import save_checkpoint
    from .torch_models.ssd3d_config import PRESETS
    from .torch_models.ssd3d_model import SSD3D

    if preset not in PRESETS:
        raise ValueError(f"unknown 3DSSD size {preset!r}; choose among {', '.join(PRESETS)}")
    if epochs <= 0:
        raise ValueError(f"epochs must be positive, got {epochs}")
    if threads:
        torch.set_num_threads(int(threads))
    config = PRESETS[preset]
    roots, seqs = [str(r) for r in roots], [str(s) for s in seqs]
    samples = load_samples(roots, seqs, config, max_frames)
    log.info("3DSSD %s: %d training frames from %s, sequences %s", preset, len(samples), roots, seqs)
    torch.manual_seed(seed)
    model = SSD3D(config)

    def write(epoch: int, losses: dict[str, float]) -> None:
        save_checkpoint(out, model.eval(), {
            "preset": preset, "roots": roots, "seqs": seqs, "frames": len(samples),
            "epochs_done": epoch + 1, "epochs": epochs, "batch_size": batch_size, "lr": lr, "seed": seed,
            "augmentation": "flip, rotation +-pi/4, scale 0.95-1.05", "losses": losses,
            "saved": datetime.now(timezone.utc).isoformat(timespec="seconds")})

    train_model(model, samples, epochs, batch_size, lr, seed, on_epoch=write)
    return Path(out)
