"""The 3DSSD checkpoint file: one ``torch.save``-d dict, readable with
``torch.load(path, weights_only=True)`` (no pickled code)::

    {
      "format": {"name": "twistslam-3dssd", "version": 1},
      "config": SSD3DConfig.to_dict(),      # every size of the network and its box coding
      "state_dict": {name: tensor},         # SSD3D(config).state_dict()
      "classes": ["Car", ...],              # score columns (same as config["classes"])
      "training": {...},                    # free-form metadata: data, epochs, losses, date
    }

A file of another name or a newer version is refused with a message saying so.
"""

from __future__ import annotations

from pathlib import Path

import torch

from .ssd3d_config import SSD3DConfig
from .ssd3d_model import SSD3D
from .torch_file import load_torch_file

FORMAT_NAME = "twistslam-3dssd"
FORMAT_VERSION = 1
REQUIRED_KEYS = ("format", "config", "state_dict", "classes")


def save_checkpoint(path: str | Path, model: SSD3D, training: dict | None = None) -> Path:
    """Write ``model`` (its config and weights) and ``training`` metadata to ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    state = {k: v.detach().cpu().clone() for k, v in model.state_dict().items()}
    torch.save({"format": {"name": FORMAT_NAME, "version": FORMAT_VERSION},
                "config": model.config.to_dict(), "state_dict": state,
                "classes": list(model.config.classes), "training": dict(training or {})}, path)
    return path


def read_checkpoint(path: str | Path) -> dict:
    """The checked checkpoint dict of ``path``.

    Raises
    ------
    FileNotFoundError
        No file at ``path`` (nothing is ever downloaded).
    ValueError
        The file is not a torch file, not a dict with the keys above, or of another format or
        a newer version.
    """
    path = Path(path)
    checkpoint = load_torch_file(path, "3DSSD checkpoint", "train one with `twistslam "
                                 "train-detector` or name a checkpoint file")
    if not isinstance(checkpoint, dict) or any(key not in checkpoint for key in REQUIRED_KEYS):
        found = sorted(checkpoint)[:8] if isinstance(checkpoint, dict) else type(checkpoint).__name__
        raise ValueError(f"{path}: not a 3DSSD checkpoint (expected a dict with keys "
                         f"{', '.join(REQUIRED_KEYS)}; found {found})")
    fmt = checkpoint["format"]
    if not isinstance(fmt, dict) or fmt.get("name") != FORMAT_NAME:
        raise ValueError(f"{path}: checkpoint format is {fmt!r}, not {FORMAT_NAME!r}")
    if not isinstance(fmt.get("version"), int) or fmt["version"] > FORMAT_VERSION:
        raise ValueError(f"{path}: {FORMAT_NAME} version {fmt.get('version')!r} is not supported "
                         f"(this twistslam reads up to version {FORMAT_VERSION})")
    return checkpoint


def load_checkpoint(path: str | Path) -> tuple[SSD3D, dict]:
    """The :class:`SSD3D` stored in ``path`` (eval mode, CPU) and the file's training metadata."""
    checkpoint = read_checkpoint(path)
    try:
        config = SSD3DConfig.from_dict(checkpoint["config"])
    except (TypeError, ValueError, KeyError) as exc:
        raise ValueError(f"{path}: malformed 3DSSD config ({exc})") from exc
    if list(checkpoint["classes"]) != list(config.classes):
        raise ValueError(f"{path}: classes {checkpoint['classes']} differ from the config's {list(config.classes)}")
    model = SSD3D(config)
    try:
        model.load_state_dict(checkpoint["state_dict"], strict=True)
    except (RuntimeError, TypeError, AttributeError) as exc:  # missing / unexpected keys, shapes
        message = " ".join(str(exc).split())
        raise ValueError(f"{path}: 3DSSD weights do not match its config ({message[:300]})") from exc
    return model.eval(), dict(checkpoint.get("training") or {})
