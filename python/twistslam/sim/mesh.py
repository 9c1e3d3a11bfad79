"""Triangle meshes with per-vertex attributes, a few closed primitives, and a PLY writer.

Attributes (``attrs``, one row per vertex) carry texture coordinates: the renderer
interpolates them at a hit with the barycentric coordinates the ray caster returns.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np


def rotate(X: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``X @ R.T`` for (N, 3) points and a 3x3 matrix, without BLAS: for an inner dimension
    of 3, threaded BLAS is several times slower than einsum on a busy 2-core machine."""
    return np.einsum("ij,kj->ik", X, R)


@dataclass
class Mesh:
    """Vertices (V, 3) float64, triangles (F, 3) int64 (counter-clockwise seen from outside),
    attributes (V, K) float32 interpolated by the renderer (K may be 0)."""

    vertices: np.ndarray
    faces: np.ndarray
    attrs: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.asarray(self.faces, dtype=np.int64).reshape(-1, 3)
        if self.attrs is None:
            self.attrs = np.zeros((len(self.vertices), 0), dtype=np.float32)
        attrs = np.asarray(self.attrs, dtype=np.float32)
        self.attrs = attrs.reshape(len(self.vertices), attrs.shape[-1] if attrs.ndim == 2 else 0)

    @staticmethod
    def concat(meshes: list["Mesh"]) -> "Mesh":
        """One mesh holding all ``meshes`` (their attribute widths must agree)."""
        meshes = [m for m in meshes if len(m.faces)]
        if not meshes:
            return Mesh(np.zeros((0, 3)), np.zeros((0, 3)))
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
        return Mesh(
            np.concatenate([m.vertices for m in meshes]),
            np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]),
            np.concatenate([m.attrs for m in meshes]),
        )

    def transformed(self, T: np.ndarray) -> "Mesh":
        """The mesh with vertices mapped by the 4x4 ``T`` (attributes unchanged)."""
        return Mesh(rotate(self.vertices, T[:3, :3]) + T[:3, 3], self.faces, self.attrs)

    def signed_volume(self) -> float:
        """Volume enclosed by a closed mesh; positive when faces point outwards."""
        a, b, c = (self.vertices[self.faces[:, k]] for k in range(3))
        return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)

    def is_watertight(self) -> bool:
        """True when every edge is shared by exactly two faces with opposite directions."""
        f = self.faces
        edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        forward = {tuple(e) for e in edges.tolist()}
        if len(forward) != len(edges):
            return False  # an edge used twice in the same direction
        return all((b, a) in forward for a, b in forward)


def ring_loft(rings: np.ndarray) -> Mesh:
    """Closed surface through ``rings`` (S, M, 3): quads between consecutive rings, a fan
    from each end ring's centroid. Orientation is fixed so that the volume is positive."""
    S, M, _ = rings.shape
    vertices = np.concatenate([rings.reshape(-1, 3), rings[0].mean(0)[None], rings[-1].mean(0)[None]])
    i = np.arange(S - 1)[:, None] * M
    j = np.arange(M)[None, :]
    a, b = i + j, i + (j + 1) % M
    c, d = a + M, b + M
    quads = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    start, end = S * M, S * M + 1
    fan0 = np.stack([np.full(M, start), (j[0] + 1) % M, j[0]], -1)
    fan1 = np.stack([np.full(M, end), (S - 1) * M + j[0], (S - 1) * M + (j[0] + 1) % M], -1)
    mesh = Mesh(vertices, np.concatenate([quads, fan0, fan1]))
    if mesh.signed_volume() < 0:
        mesh.faces = mesh.faces[:, ::-1].copy()
    return mesh


def cylinder(radius: float, length: float, segments: int = 16) -> Mesh:
    """Closed cylinder along z from 0 to ``length``."""
    ang = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    ring = np.stack([radius * np.cos(ang), radius * np.sin(ang), np.zeros(segments)], -1)
    rings = np.stack([ring, ring + [0, 0, length]])
    return ring_loft(rings)


def box(size: tuple[float, float, float], bottom: bool = True) -> Mesh:
    """Axis-aligned box ``[0, sx] x [0, sy] x [0, sz]`` with outward faces (4 vertices per face,
    so that faces get their own texture coordinates)."""
    sx, sy, sz = size
    c = np.array([[x, y, z] for z in (0, sz) for y in (0, sy) for x in (0, sx)], dtype=float)
    quads = [(0, 1, 5, 4), (1, 3, 7, 5), (3, 2, 6, 7), (2, 0, 4, 6), (4, 5, 7, 6)]
    if bottom:
        quads.append((0, 2, 3, 1))
    vertices = np.concatenate([c[list(q)] for q in quads])
    k = 4 * np.arange(len(quads))[:, None]
    faces = np.concatenate([k + [0, 1, 2], k + [0, 2, 3]])
    return Mesh(vertices, faces)


def write_ply(path: str | Path, mesh: Mesh) -> None:
    """Binary little-endian PLY: float32 vertices, int32 triangle indices."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(mesh.vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(mesh.faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    faces = np.zeros(len(mesh.faces), dtype=[("n", "u1"), ("idx", "<i4", (3,))])
    faces["n"] = 3
    faces["idx"] = mesh.faces
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(mesh.vertices.astype("<f4").tobytes())
        f.write(faces.tobytes())


def read_ply(path: str | Path) -> Mesh:
    """Read a PLY written by :func:`write_ply` (binary, float vertices, triangles)."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    nv = int(next(h for h in header if h.startswith("element vertex")).split()[-1])
    nf = int(next(h for h in header if h.startswith("element face")).split()[-1])
    vertices = np.frombuffer(data, "<f4", nv * 3, end).reshape(nv, 3)
    faces = np.frombuffer(data, [("n", "u1"), ("idx", "<i4", (3,))], nf, end + nv * 12)
    return Mesh(vertices.astype(np.float64), faces["idx"].astype(np.int64))
