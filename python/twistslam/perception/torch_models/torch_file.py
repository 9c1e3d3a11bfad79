"""Reading a weight file from a path the user names, shared by every plain-torch model."""

from __future__ import annotations

from pathlib import Path

import torch


def load_torch_file(path: str | Path, what: str, missing_hint: str) -> object:
    """The object torch saved at ``path``, loaded on the CPU with ``weights_only=True``.

    Raises
    ------
    FileNotFoundError
        No file at ``path`` (nothing is ever downloaded); ``missing_hint`` says what to name.
    ValueError
        ``torch.load`` failed: the file is not a torch file (``what`` names what was expected).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{what}: {path} not found (nothing is downloaded; "
                                f"{missing_hint})")
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # unpickling errors of every kind: not a torch file
        raise ValueError(f"{path}: not a {what} (torch.load failed: "
                         f"{type(exc).__name__}: {str(exc)[:160]})") from exc
