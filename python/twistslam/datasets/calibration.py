"""KITTI calibration files: projection matrices and the LiDAR / IMU extrinsics.

KITTI ships the same matrices under two spellings. The object benchmark (and the files in
``kitti_tracking/training/calib``) write ``P2: ...``, ``R0_rect: ...``, ``Tr_velo_to_cam: ...``,
``Tr_imu_to_velo: ...``; the tracking devkit writes ``R_rect``, ``Tr_velo_cam``,
``Tr_imu_velo`` without a colon. :func:`read_calibration` takes both (and mixtures of them);
:func:`write_calibration` writes the devkit spelling.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._parsing import PathLike, ensure_parent, format_float, iter_lines, parse_error, to_floats

#: accepted spellings -> (field name, shape)
_KEYS: dict[str, tuple[str, tuple[int, int]]] = {
    "P0": ("P0", (3, 4)),
    "P1": ("P1", (3, 4)),
    "P2": ("P2", (3, 4)),
    "P3": ("P3", (3, 4)),
    "R_rect": ("R_rect", (3, 3)),
    "R0_rect": ("R_rect", (3, 3)),
    "Tr_velo_cam": ("Tr_velo_cam", (3, 4)),
    "Tr_velo_to_cam": ("Tr_velo_cam", (3, 4)),
    "Tr_imu_velo": ("Tr_imu_velo", (3, 4)),
    "Tr_imu_to_velo": ("Tr_imu_velo", (3, 4)),
}
_FIELDS = ("P0", "P1", "P2", "P3", "R_rect", "Tr_velo_cam", "Tr_imu_velo")
#: |R R^T - I| a rotation may show: KITTI's 7-digit matrices are orthonormal to 1e-7; 1e-3
#: still passes a hand-rounded file and catches a mistyped digit or a matrix that is no rotation
ROTATION_TOLERANCE = 1e-3


def value_problem(name: str, M: np.ndarray) -> str | None:
    """Why matrix ``name`` cannot be a KITTI calibration entry, or None when it can.

    Non-finite values anywhere (an inf in ``Tr_velo_cam`` turns every LiDAR point and every
    oxts pose NaN); a zero or negative focal length in the colour cameras P2 / P3 the system
    projects with (singular intrinsics); rotation parts that are not rotations.
    """
    if not np.isfinite(M).all():
        return "holds NaN or inf values"
    if name in ("P2", "P3") and not (M[0, 0] > 0 and M[1, 1] > 0):
        return f"focal lengths fx = {M[0, 0]:g}, fy = {M[1, 1]:g} must be positive"
    if name in ("R_rect", "Tr_velo_cam", "Tr_imu_velo"):
        R = M[:, :3]
        error = np.abs(R @ R.T - np.eye(3)).max()
        if error > ROTATION_TOLERANCE or np.linalg.det(R) < 0:
            return (f"rotation part is not a rotation (|R R^T - I| = {error:.2g}, "
                    f"det {np.linalg.det(R):.3g})")
    return None


def _homogeneous(M: np.ndarray) -> np.ndarray:
    """3x3 or 3x4 -> 4x4 with ``[0 0 0 1]`` as last row (a 3x3 gets zero translation)."""
    T = np.eye(4)
    T[: M.shape[0], : M.shape[1]] = M
    return T


@dataclass(eq=False)
class Calibration:
    """Calibration of one KITTI sequence; all matrices float64.

    ``P0..P3`` project points of the rectified reference camera frame ``c`` into images 0..3
    (so ``P2`` keeps its fourth column: camera 2 is about 6 cm from the reference).
    ``R_rect`` rectifies the reference camera; ``Tr_velo_cam`` maps LiDAR points into the
    unrectified reference camera, ``Tr_imu_velo`` maps IMU points into the LiDAR frame.
    """

    P0: np.ndarray
    P1: np.ndarray
    P2: np.ndarray
    P3: np.ndarray
    R_rect: np.ndarray
    Tr_velo_cam: np.ndarray
    Tr_imu_velo: np.ndarray
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        for name in _FIELDS:
            shape = (3, 3) if name == "R_rect" else (3, 4)
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != shape:
                raise ValueError(f"Calibration.{name}: expected shape {shape}, got {value.shape}")
            problem = value_problem(name, value)
            if problem is not None:
                where = f"{self.source}: " if self.source else "Calibration."
                raise ValueError(f"{where}{name}: {problem}")
            setattr(self, name, value)

    def __eq__(self, other: object) -> bool:
        # element-wise array comparison (the generated __eq__ would compare arrays ambiguously)
        if not isinstance(other, Calibration):
            return NotImplemented
        return all(np.array_equal(getattr(self, n), getattr(other, n)) for n in _FIELDS)

    @property
    def T_c_velo(self) -> np.ndarray:
        """4x4 LiDAR -> rectified camera frame ``c``: ``R_rect @ Tr_velo_cam``."""
        return _homogeneous(self.R_rect) @ _homogeneous(self.Tr_velo_cam)

    @property
    def T_c_imu(self) -> np.ndarray:
        """4x4 IMU -> rectified camera frame ``c``: ``T_c_velo @ Tr_imu_velo``."""
        return self.T_c_velo @ _homogeneous(self.Tr_imu_velo)

    @property
    def K(self) -> np.ndarray:
        """3x3 intrinsics of the left colour camera (camera 2)."""
        return self.P2[:, :3].copy()

    @property
    def baseline(self) -> float:
        """Stereo baseline between cameras 2 and 3 in metres (about 0.53 m on KITTI).

        The x distance between the two camera centres, ``t = K^-1 P[:, 3]`` for each camera;
        the same definition as ``StereoCamera.baseline``. It differs from the devkit's
        shortcut ``(P2[0,3] - P3[0,3]) / fx`` by ``cx * (tz2 - tz3) / fx`` (about 1e-5 m).
        """
        K_inv = np.linalg.inv(self.P2[:, :3])
        return float((K_inv @ self.P2[:, 3])[0] - (K_inv @ self.P3[:, 3])[0])

    def stereo_camera(self, width: int, height: int):
        """The C++ ``twistslam.geometry.StereoCamera`` of cameras 2 and 3."""
        # imported here so that reading calibration never needs the compiled extension
        from twistslam.geometry import StereoCamera

        return StereoCamera.from_kitti(self.P2, self.P3, int(width), int(height))


def read_calibration(path: PathLike) -> Calibration:
    """Read a KITTI calibration file in either key spelling.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        ``"<file>:<line>: <key>: ..."`` for a bad value count, an unparsable or non-finite
        number, a non-positive focal length of P2 / P3, a rotation that is none, or a
        repeated key; ``"<file>: missing key <key>"`` for a matrix that never appears.
        Unknown keys are ignored (some KITTI variants add their own).
    """
    values: dict[str, np.ndarray] = {}
    for line_no, tokens in iter_lines(path):
        key, rest = tokens[0], tokens[1:]
        if ":" in key and not key.endswith(":"):  # "P2:1.0 ..." without a space
            key, first = key.split(":", 1)
            rest = [first, *rest]
        key = key.rstrip(":")
        if key not in _KEYS:
            continue
        name, shape = _KEYS[key]
        if name in values:
            raise parse_error(path, line_no, f"{key}: {name} given twice")
        expected = shape[0] * shape[1]
        if len(rest) != expected:
            raise parse_error(path, line_no, f"{key}: expected {expected} values, got {len(rest)}")
        values[name] = to_floats(rest, path, line_no, key).reshape(shape)
        problem = value_problem(name, values[name])
        if problem is not None:
            raise parse_error(path, line_no, f"{key}: {problem}")
    for name in _FIELDS:
        if name not in values:
            raise parse_error(path, None, f"missing key {name}")
    return Calibration(**values, source=str(path))


def write_calibration(path: PathLike, calib: Calibration) -> None:
    """Write ``calib`` in the tracking devkit spelling (``P2 ...``, ``R_rect ...``, no colons)."""
    path = ensure_parent(path)
    with open(path, "w", encoding="utf-8") as f:
        for name in _FIELDS:
            row = " ".join(format_float(v) for v in getattr(calib, name).reshape(-1))
            f.write(f"{name} {row}\n")
