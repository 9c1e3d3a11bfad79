"""Loading a state-dict file into the matching plain-torch model, its size read from the file.

A checkpoint names its architecture through its keys and shapes: the ResNet depth is the
number of ``layerK.N`` blocks, its width the stem's output channels, the class count the
classifier's rows. Building the model from those (instead of assuming ResNet-50) lets a
torchvision checkpoint and a small test model load through the same path; the load itself is
``strict=True``, so any other file is refused with a message naming it.
"""

from __future__ import annotations

import re
from pathlib import Path

import torch

from .deeplab import SegmentationNet
from .maskrcnn import MaskRCNN, MaskRCNNShape
from .resnet import ResNetShape
from .torch_file import load_torch_file

#: key prefixes of the backbone of each model family
DETECTOR_BACKBONE = "backbone.body."
SEGMENTATION_BACKBONE = "backbone."


def read_state_dict(path: str | Path, what: str) -> dict[str, torch.Tensor]:
    """The tensors of a state-dict file (or of the ``"model"`` entry of a training checkpoint,
    the way torchvision's reference scripts save them).

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist (nothing is ever downloaded).
    ValueError
        The file is not a torch file holding a dict of tensors.
    """
    path = Path(path)
    state = load_torch_file(path, f"{what} state dict", "name a state-dict .pth file")
    if isinstance(state, dict) and isinstance(state.get("model"), dict):
        state = state["model"]
    if not isinstance(state, dict) or not state or not all(
            isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in state.items()):
        raise ValueError(f"{path}: not a {what} state dict (expected a dict of named tensors, "
                         f"got {type(state).__name__})")
    return state


def _backbone_shape(state: dict[str, torch.Tensor], prefix: str) -> ResNetShape:
    blocks = []
    for stage in range(1, 5):
        pattern = re.compile(rf"{re.escape(prefix)}layer{stage}\.(\d+)\.conv1\.weight$")
        found = [int(m.group(1)) for k in state if (m := pattern.match(k))]
        blocks.append(max(found) + 1 if found else 0)
    if min(blocks) == 0 or prefix + "conv1.weight" not in state:
        raise KeyError(f"{prefix}layer1..4 bottleneck blocks")
    return ResNetShape(tuple(blocks), int(state[prefix + "conv1.weight"].shape[0]))


def _strict_load(model: torch.nn.Module, state: dict, path: Path, what: str) -> None:
    try:
        model.load_state_dict(state, strict=True)
    except RuntimeError as exc:  # missing / unexpected keys, shape mismatches
        message = " ".join(str(exc).split())  # torch's report spans lines and tabs
        raise ValueError(f"{path}: not a {what} state dict ({message[:300]})") from exc


def load_maskrcnn(path: str | Path, **settings) -> MaskRCNN:
    """A :class:`MaskRCNN` sized by, and holding the weights of, the file ``path``, in eval
    mode. ``settings``: ``resize``, ``proposals``, ``detections`` of :class:`MaskRCNN`.

    Raises FileNotFoundError for a missing file and ValueError naming it for any file that is
    not a Mask R-CNN (torchvision ``maskrcnn_resnet50_fpn`` layout) state dict."""
    what = "Mask R-CNN"
    path = Path(path)
    state = read_state_dict(path, what)
    try:
        shape = MaskRCNNShape(
            num_classes=int(state["roi_heads.box_predictor.cls_score.weight"].shape[0]),
            backbone=_backbone_shape(state, DETECTOR_BACKBONE),
            fpn_channels=int(state["backbone.fpn.inner_blocks.0.0.weight"].shape[0]),
            box_head_width=int(state["roi_heads.box_head.fc6.weight"].shape[0]),
            mask_channels=int(state["roi_heads.mask_head.0.0.weight"].shape[0]))
    except KeyError as exc:
        raise ValueError(f"{path}: not a {what} state dict (no {exc.args[0]})") from None
    model = MaskRCNN(shape, **settings)
    _strict_load(model, state, path, what)
    return model.eval()


def load_segmentation(path: str | Path, num_classes: int | None = None) -> SegmentationNet:
    """A :class:`SegmentationNet` (DeepLabV3 or FCN head, told apart by the file's keys)
    sized by, and holding the weights of, the file ``path``, in eval mode.

    Raises FileNotFoundError for a missing file and ValueError naming it for a file that is
    not a torchvision ``deeplabv3_resnet50`` / ``fcn_resnet50`` layout state dict, or whose
    class count is not ``num_classes`` (when given)."""
    what = "semantic segmentation (DeepLabV3 / FCN)"
    path = Path(path)
    state = read_state_dict(path, what)
    try:
        backbone = _backbone_shape(state, SEGMENTATION_BACKBONE)
        classes = int(state["classifier.4.weight"].shape[0])
    except KeyError as exc:
        raise ValueError(f"{path}: not a {what} state dict (no {exc.args[0]})") from None
    if num_classes is not None and classes != num_classes:
        raise ValueError(f"{path}: the semantic network has {classes} classes, "
                         f"num_semantic_classes is {num_classes}")
    is_deeplab = "classifier.0.convs.0.0.weight" in state
    head_channels = int(state["classifier.0.convs.0.0.weight"].shape[0]) if is_deeplab else 0
    model = SegmentationNet("deeplabv3" if is_deeplab else "fcn", classes,
                            aux="aux_classifier.0.weight" in state, backbone=backbone,
                            **({"head_channels": head_channels} if is_deeplab else {}))
    _strict_load(model, state, path, what)
    return model.eval()
