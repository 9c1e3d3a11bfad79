"""Ray casting with Open3D's CPU ``RaycastingScene`` (Embree).

The static scene (ground, road, facades, furniture, parked cars) is built once per
sequence; the moving objects are cast into separately, each in its own frame (see
:mod:`twistslam.sim.objects`), and the nearer hit wins.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .mesh import Mesh

if TYPE_CHECKING:
    import open3d as o3d

    from .objects import MovingObjects


def _open3d():
    """open3d, imported when a scene is first cast: 0.7 s and ~100 MB, which every
    ``import twistslam.sim`` (the ``twistslam`` command's ``sim`` registration included) paid."""
    import open3d

    return open3d

#: static material groups, in geometry-id order of the static scene
STATIC_GROUPS = ("terrain", "road", "sidewalk", "wall", "roof", "trunk", "canopy", "pole", "sign", "rail")
GROUP = {name: k for k, name in enumerate(STATIC_GROUPS)}
OBJECT = 100  # group code of a hit on an object (car or pedestrian)
MISS = -1


def tensor_rays(origins: np.ndarray, dirs: np.ndarray) -> o3d.core.Tensor:
    """Open3D's (N, 6) float32 rays, converted while copying (no float64 intermediate)."""
    rays = np.empty((len(dirs), 6), np.float32)
    rays[:, :3] = origins
    rays[:, 3:] = dirs
    return _open3d().core.Tensor(rays)


class StaticScene:
    """Ray-casting scene of the named static meshes (map frame) and of the objects that never
    move (parked cars): one scene fewer to cast every ray into."""

    def __init__(self, groups: dict[str, Mesh], objects: list[tuple[int, Mesh]] = ()) -> None:
        self.scene = _open3d().t.geometry.RaycastingScene()
        self.mesh_of_group: dict[int, Mesh] = {}
        self.face_attrs: dict[int, np.ndarray] = {}
        group_of_geometry: list[int] = []
        agent_of_geometry: list[int] = []
        for name in STATIC_GROUPS:
            mesh = groups.get(name)
            if mesh is None or len(mesh.faces) == 0:
                continue
            self.scene.add_triangles(mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32))
            self.mesh_of_group[GROUP[name]] = mesh
            if mesh.attrs.shape[1]:
                self.face_attrs[GROUP[name]] = mesh.attrs[mesh.faces]  # see interpolate
            group_of_geometry.append(GROUP[name])
            agent_of_geometry.append(-1)
        for agent, mesh in objects:
            self.scene.add_triangles(mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32))
            group_of_geometry.append(OBJECT)
            agent_of_geometry.append(agent)
        self.group_of_geometry = np.array(group_of_geometry, dtype=np.int16)
        self.agent_of_geometry = np.array(agent_of_geometry, dtype=np.int32)
        # the same with a trailing entry for misses (see cast)
        self.group_table = np.append(self.group_of_geometry, np.int16(MISS))
        self.agent_table = np.append(self.agent_of_geometry, np.int32(-1))
        # build the BVH now, in one thread (Open3D builds it on the first query otherwise)
        self.scene.test_occlusions(_open3d().core.Tensor(np.zeros((1, 6), np.float32)))


def mesh_scene(vertices: np.ndarray, faces: np.ndarray) -> o3d.t.geometry.RaycastingScene:
    """A ray-casting scene of one triangle mesh, committed (its BVH built) at once: Open3D
    builds it on the first query, and two threads must not do that at the same time."""
    scene = _open3d().t.geometry.RaycastingScene()
    scene.add_triangles(vertices.astype(np.float32), faces.astype(np.uint32))
    scene.test_occlusions(_open3d().core.Tensor(np.zeros((1, 6), np.float32)))
    return scene


@dataclass
class Hits:
    """First hits of N rays (map frame)."""

    t: np.ndarray  # (N,) float64 distance along the unit direction; inf where nothing is hit
    group: np.ndarray  # (N,) int16: STATIC_GROUPS index, OBJECT, or MISS
    agent: np.ndarray  # (N,) int32 agent index for OBJECT hits, else -1
    prim: np.ndarray  # (N,) uint32 triangle index within its geometry
    uv: np.ndarray  # (N, 2) float32 barycentric coordinates of vertices 1 and 2
    normal: np.ndarray  # (N, 3) float32 unit normal facing the ray origin
    point: np.ndarray  # (N, 3) float64 hit point

    def select(self, mask: np.ndarray) -> "Hits":
        """The hits of a boolean ``mask`` or of an index array."""
        idx = np.flatnonzero(mask) if mask.dtype == bool else mask
        return Hits(*(getattr(self, k)[idx] for k in self.__dataclass_fields__))


def cast(static: StaticScene, objects: "MovingObjects | None", origins: np.ndarray, dirs: np.ndarray,
         candidates: list[np.ndarray] | None = None) -> Hits:
    """First hits of rays with unit directions ``dirs`` (N, 3) from ``origins`` (N, 3) in the
    static scene and among the moving ``objects``, ``candidates[k]`` being the rays that may
    hit object k (default: all rays)."""
    rays = tensor_rays(origins, dirs)
    a = static.scene.cast_rays(rays)
    t = a["t_hit"].numpy().astype(np.float64)
    # misses carry Open3D's INVALID_ID: clamp it onto the tables' trailing MISS entry, so the
    # lookups are single gathers instead of masked assignments over every ray
    geom = np.minimum(a["geometry_ids"].numpy(), len(static.group_of_geometry))
    group = static.group_table[geom]
    agent = static.agent_table[geom]
    prim = a["primitive_ids"].numpy()
    uv = a["primitive_uvs"].numpy()
    normal = a["primitive_normals"].numpy()  # float32: shading does not need more
    if objects is not None and len(objects):
        if candidates is None:
            candidates = [np.arange(len(dirs))] * len(objects)
        objects.first_hits(origins, dirs, candidates, t, group, agent, prim, uv, normal, OBJECT)
    # face the normals towards the ray origin (a multiply by +-1: masked writes cost twice as much)
    normal *= np.where(np.einsum("ij,ij->i", normal, dirs) > 0, np.float32(-1), np.float32(1))[:, None]
    # hit points in float64 (ground truth is projected from them); misses at the origin
    point = np.multiply(dirs, np.where(np.isfinite(t), t, 0.0)[:, None], dtype=np.float64)
    point += origins
    return Hits(t, group, agent, prim, uv, normal, point)


def occluded(static: StaticScene, objects: "MovingObjects | None", origins: np.ndarray, dirs: np.ndarray,
             tfar: float | np.ndarray = np.inf, candidates: list[np.ndarray] | None = None) -> np.ndarray:
    """Whether anything lies on each ray between 0 and ``tfar`` (per ray or common);
    ``candidates`` as for :func:`cast`."""
    if np.ndim(tfar) == 0:
        out = static.scene.test_occlusions(tensor_rays(origins, dirs), tfar=float(tfar)).numpy()
    else:  # per-ray limits: scale the directions so that t = 1 is the limit
        out = static.scene.test_occlusions(tensor_rays(origins, dirs * np.asarray(tfar)[:, None]), tfar=1.0).numpy()
    if objects is not None and len(objects):
        if candidates is None:
            candidates = [np.arange(len(dirs))] * len(objects)
        out |= objects.occluded(origins, dirs, tfar, candidates)
    return out


def interpolate(face_attrs: np.ndarray, prim: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Per-vertex attributes at hits (triangle ``prim``, barycentric ``uv``), from the
    attributes of each face's three vertices ``face_attrs`` (F, 3, K): one gather per hit
    instead of a gather of the face and then of each vertex."""
    w = np.empty((len(uv), 3), np.float32)  # barycentric weights of the three vertices
    w[:, 1:] = uv
    w[:, 0] = 1 - uv[:, 0] - uv[:, 1]
    return np.einsum("nkj,nk->nj", face_attrs[prim], w)
