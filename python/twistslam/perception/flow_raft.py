"""RAFT optical flow (torchvision's ``raft_small`` / ``raft_large`` architectures, implemented
in plain torch in :mod:`twistslam.perception.raft_model`) from a weight file the user names.
Nothing is downloaded: without a weight file there is no RAFT source.

torch is an optional extra (``pip install twistslam[models]``), imported only when a RAFT source
is built; torchvision is not needed, and its checkpoints (e.g. ``raft_small_C_T_V2``) load as they
are. Any torch module with RAFT's interface (``network(image1, image2, num_flow_updates=K)`` ->
list of (N, 2, H, W) flow predictions, the last the finest) can be passed instead, e.g. a
fine-tuned model.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from twistslam.datasets import Frame

RAFT_MODELS = ("raft_small", "raft_large")
RAFT_SIZE_MULTIPLE = 8  # RAFT's feature maps are 1/8 of the image: sizes must divide by 8


def _import_torch():
    try:
        import torch
    except ImportError as e:  # pragma: no cover - torch is installed where tests run
        raise ImportError("RAFT flow needs torch: pip install 'twistslam[models]'") from e
    return torch


def load_raft(weights: str | Path, model: str = "raft_small"):
    """The RAFT network ``model`` with the state dict of the file ``weights``, in eval mode.

    Raises
    ------
    ValueError for an unknown model or a file that is not that model's state dict;
    FileNotFoundError for a missing file; ImportError when torch is not installed.
    """
    if model not in RAFT_MODELS:
        raise ValueError(f"RAFT model '{model}': expected one of {', '.join(RAFT_MODELS)}")
    path = Path(weights)
    if not path.is_file():
        raise FileNotFoundError(f"RAFT weights: {path} not found (nothing is downloaded; name a .pth file)")
    torch = _import_torch()
    from . import raft_model

    network = getattr(raft_model, model)()
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
        if not isinstance(state, dict):
            raise TypeError(f"the file holds a {type(state).__name__}, not a dict of tensors")
        network.load_state_dict(state, strict=True)
    except Exception as e:  # unpickling errors and key / shape mismatches alike
        raise ValueError(f"{path}: not a {model} state dict ({type(e).__name__}: {str(e)[:200]})") from e
    return network.eval()


class RaftFlow:
    """Flow from a RAFT network between the left images of two frames.

    Parameters
    ----------
    weights : state-dict file of ``model`` (ignored when ``network`` is given).
    model : "raft_small" or "raft_large".
    network : a ready torch module with RAFT's interface, instead of ``weights``.
    flow_updates : recurrent refinement steps (torchvision's default is 12).
    device : torch device the network runs on.
    """

    def __init__(self, weights: str | Path | None = None, model: str = "raft_small", *, network=None,
                 flow_updates: int = 12, device: str = "cpu") -> None:
        if flow_updates < 1:
            raise ValueError(f"RAFT flow_updates: expected >= 1, got {flow_updates}")
        if network is None:
            if weights is None:
                raise ValueError("RAFT flow: name a weight file (weights=...) or pass a network")
            network = load_raft(weights, model)
        self.torch = _import_torch()
        self.network = network.to(device).eval()
        self.flow_updates = flow_updates
        self.device = device

    def _tensor(self, image: np.ndarray | None, name: str, index: int):
        if image is None:
            raise ValueError(f"RAFT flow: frame {index} ({name}) has no left image")
        if image.dtype != np.uint8 or image.ndim not in (2, 3):
            raise ValueError(f"RAFT flow: frame {index} ({name}) image must be uint8 (H, W[, 3]), got "
                             f"{image.dtype} {image.shape}")
        rgb = np.repeat(image[..., None], 3, axis=2) if image.ndim == 2 else image
        # RAFT was trained on images scaled to [-1, 1]
        x = self.torch.from_numpy(np.ascontiguousarray(rgb)).permute(2, 0, 1)[None].float()
        return (x / 127.5 - 1.0).to(self.device)

    def __call__(self, previous: Frame, current: Frame) -> np.ndarray:
        a = self._tensor(previous.image_left, "previous", previous.index)
        b = self._tensor(current.image_left, "current", current.index)
        if a.shape != b.shape:
            raise ValueError(f"RAFT flow: frames {previous.index} and {current.index} differ in image size")
        h, w = a.shape[-2:]
        pad_h, pad_w = -h % RAFT_SIZE_MULTIPLE, -w % RAFT_SIZE_MULTIPLE
        # replicate the last row / column: zero padding would add a strong artificial edge
        pad = self.torch.nn.functional.pad
        a, b = (pad(x, (0, pad_w, 0, pad_h), mode="replicate") for x in (a, b))
        with self.torch.inference_mode():
            flow = self.network(a, b, num_flow_updates=self.flow_updates)[-1]
        return flow[0, :, :h, :w].permute(1, 2, 0).cpu().numpy().astype(np.float32)
