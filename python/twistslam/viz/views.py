"""What the view shows of one object, and the shape checks of everything that is logged.

Every check raises a :class:`ValueError` that names the offending field, so a caller sees
``log_frame: T_w_c must be a (4, 4) array, got (3, 4)`` rather than a rerun traceback.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(eq=False)
class ObjectView:
    """One tracked object as the view shows it in one frame.

    Attributes
    ----------
    track_id : int
        Track id; it picks the object's colour, stable over the run.
    cls : str
        Class name, e.g. ``"car"``.
    T_w_o : (4, 4) array
        Object pose in the world (first camera) frame.
    size : (3,) array
        Box length, width, height in metres. The box is centred at the object origin; in the
        object frame x is along the length, y points down (height) and z along the width,
        as in KITTI's box frame.
    velocity_kmh : float
        Speed shown in the label.
    points_w : (M, 3) array or None
        The object's map points in the world frame.
    box2d : (4,) array or None
        Image box ``x1, y1, x2, y2`` in pixels.
    """

    track_id: int
    cls: str
    T_w_o: np.ndarray
    size: np.ndarray
    velocity_kmh: float = 0.0
    points_w: np.ndarray | None = None
    box2d: np.ndarray | None = None

    def label(self) -> str:
        """The text of its boxes, e.g. ``"id 12 car 34 km/h"``."""
        return f"id {self.track_id} {self.cls} {self.velocity_kmh:.0f} km/h"


def check_array(value: object, shape: tuple[int | None, ...], field: str) -> np.ndarray:
    """A finite float64 array of the given shape (``None`` = any length on that axis).

    Parameters
    ----------
    value : array_like
        What the caller passed.
    shape : tuple
        Expected shape; ``None`` entries match any size.
    field : str
        Name used in the error message.

    Returns
    -------
    np.ndarray
        ``value`` as float64.

    Raises
    ------
    ValueError
        Wrong number of dimensions, wrong size on a fixed axis, or non-finite values.
    """
    array = np.asarray(value)
    if array.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, array.shape)):
        expected = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{field} must be a {expected} array, got shape {array.shape}")
    if not np.issubdtype(array.dtype, np.number) or np.issubdtype(array.dtype, np.complexfloating):
        raise ValueError(f"{field} must hold real numbers, got {array.dtype}")
    array = array.astype(np.float64, copy=False)
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{field} holds NaN or infinite values")
    return array


def check_image(image: object, field: str = "image_left") -> np.ndarray:
    """An ``(H, W, 3)`` uint8 RGB image."""
    array = np.asarray(image)
    if array.ndim != 3 or array.shape[2] != 3 or array.shape[0] == 0 or array.shape[1] == 0:
        raise ValueError(f"{field} must be an (H, W, 3) RGB image, got shape {array.shape}")
    if array.dtype != np.uint8:
        raise ValueError(f"{field} must be uint8, got {array.dtype}")
    return array


def check_label_image(labels: object, image_shape: tuple[int, int], field: str) -> np.ndarray:
    """An ``(H, W)`` integer label image of the left image's size, as uint16 for rerun."""
    array = np.asarray(labels)
    if array.shape != image_shape:
        raise ValueError(f"{field} must be an (H, W) = {image_shape} array like image_left, "
                         f"got shape {array.shape}")
    if not np.issubdtype(array.dtype, np.integer):
        raise ValueError(f"{field} must hold integers, got {array.dtype}")
    if array.size and (array.min() < 0 or array.max() > np.iinfo(np.uint16).max):
        raise ValueError(f"{field} values must be in [0, 65535]")
    return array.astype(np.uint16, copy=False)


def check_pose(pose: object, field: str) -> np.ndarray:
    """A ``(4, 4)`` rigid transform with a rotation block of determinant ~ +1."""
    matrix = check_array(pose, (4, 4), field)
    rotation = matrix[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-3) or np.linalg.det(rotation) < 0:
        raise ValueError(f"{field} must be a rigid transform: its 3x3 block is not a rotation")
    return matrix


def check_object(view: ObjectView, position: int) -> ObjectView:
    """An :class:`ObjectView` with checked, float64 arrays (fields named ``objects[i].x``)."""
    if not isinstance(view, ObjectView):
        raise ValueError(f"objects[{position}] must be an ObjectView, got {type(view).__name__}")
    prefix = f"objects[{position}]"
    size = check_array(view.size, (3,), f"{prefix}.size")
    if np.any(size < 0):
        raise ValueError(f"{prefix}.size must be non-negative (length, width, height)")
    points = None if view.points_w is None else check_array(view.points_w, (None, 3),
                                                             f"{prefix}.points_w")
    box2d = None if view.box2d is None else check_array(view.box2d, (4,), f"{prefix}.box2d")
    velocity = float(view.velocity_kmh)
    if not np.isfinite(velocity):
        raise ValueError(f"{prefix}.velocity_kmh must be finite, got {view.velocity_kmh}")
    return ObjectView(track_id=int(view.track_id), cls=str(view.cls),
                      T_w_o=check_pose(view.T_w_o, f"{prefix}.T_w_o"), size=size,
                      velocity_kmh=velocity, points_w=points, box2d=box2d)


def check_scalars(scalars: dict[str, float] | None) -> dict[str, float]:
    """Named finite-or-NaN floats (NaN = no value this frame)."""
    if scalars is None:
        return {}
    checked = {}
    for name, value in scalars.items():
        if not isinstance(name, str) or not name.strip("/"):
            raise ValueError(f"scalars: names must be non-empty strings, got {name!r}")
        try:
            checked[name] = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"scalars[{name!r}] must be a number, got {value!r}") from None
    return checked
