"""Ray casting with Open3D's CPU ``RaycastingScene`` (Embree).

The static scene (ground, road, facades, furniture) is built once per sequence; objects go
into a second, small scene rebuilt per frame (a RaycastingScene cannot move geometry).
Each ray is cast into both and the nearer hit wins.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d

from .mesh import Mesh

#: static material groups, in geometry-id order of the static scene
STATIC_GROUPS = ("terrain", "road", "sidewalk", "wall", "roof", "trunk", "canopy", "pole", "sign", "rail")
GROUP = {name: k for k, name in enumerate(STATIC_GROUPS)}
OBJECT = 100  # group code of a hit on an object (car or pedestrian)
MISS = -1


def _tensor_rays(origins: np.ndarray, dirs: np.ndarray) -> o3d.core.Tensor:
    return o3d.core.Tensor(np.concatenate([origins, dirs], axis=1).astype(np.float32))


class StaticScene:
    """Ray-casting scene of the named static meshes (map frame) and of the objects that never
    move (parked cars): one scene fewer to cast every ray into."""

    def __init__(self, groups: dict[str, Mesh], objects: list[tuple[int, Mesh]] = ()) -> None:
        self.scene = o3d.t.geometry.RaycastingScene()
        self.mesh_of_group: dict[int, Mesh] = {}
        group_of_geometry: list[int] = []
        agent_of_geometry: list[int] = []
        for name in STATIC_GROUPS:
            mesh = groups.get(name)
            if mesh is None or len(mesh.faces) == 0:
                continue
            self.scene.add_triangles(mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32))
            self.mesh_of_group[GROUP[name]] = mesh
            group_of_geometry.append(GROUP[name])
            agent_of_geometry.append(-1)
        for agent, mesh in objects:
            self.scene.add_triangles(mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32))
            group_of_geometry.append(OBJECT)
            agent_of_geometry.append(agent)
        self.group_of_geometry = np.array(group_of_geometry, dtype=np.int16)
        self.agent_of_geometry = np.array(agent_of_geometry, dtype=np.int32)
        # the same objects alone, for amodal masks (listing every wall a ray crosses is slow)
        self.objects = ObjectScene([a for a, _ in objects], [m for _, m in objects])


class ObjectScene:
    """Objects of one frame: one geometry per agent, meshes already in the map frame."""

    def __init__(self, agents: list[int], meshes: list[Mesh]) -> None:
        self.agents = np.array(agents, dtype=np.int32)
        self.scene = o3d.t.geometry.RaycastingScene() if agents else None
        for mesh in meshes:
            self.scene.add_triangles(mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32))


@dataclass
class Hits:
    """First hits of N rays (map frame)."""

    t: np.ndarray  # (N,) float64 distance along the unit direction; inf where nothing is hit
    group: np.ndarray  # (N,) int16: STATIC_GROUPS index, OBJECT, or MISS
    agent: np.ndarray  # (N,) int32 agent index for OBJECT hits, else -1
    prim: np.ndarray  # (N,) int64 triangle index within its geometry
    uv: np.ndarray  # (N, 2) float32 barycentric coordinates of vertices 1 and 2
    normal: np.ndarray  # (N, 3) float64 unit normal facing the ray origin
    point: np.ndarray  # (N, 3) float64 hit point

    def select(self, mask: np.ndarray) -> "Hits":
        idx = np.flatnonzero(mask)
        return Hits(*(getattr(self, k)[idx] for k in self.__dataclass_fields__))


def cast(static: StaticScene, objects: "ObjectScene | list[ObjectScene]", origins: np.ndarray,
         dirs: np.ndarray) -> Hits:
    """First hits of rays with unit directions ``dirs`` (N, 3) from ``origins`` (N, 3) in the
    static scene and the object scene(s)."""
    rays = _tensor_rays(origins, dirs)
    a = static.scene.cast_rays(rays)
    t = a["t_hit"].numpy().astype(np.float64)
    geom = a["geometry_ids"].numpy()
    prim = a["primitive_ids"].numpy().astype(np.int64)
    uv = a["primitive_uvs"].numpy()
    normal = a["primitive_normals"].numpy().astype(np.float64)
    hit = np.isfinite(t)
    group = np.full(len(t), MISS, dtype=np.int16)
    group[hit] = static.group_of_geometry[geom[hit]]
    agent = np.full(len(t), -1, dtype=np.int32)
    agent[hit] = static.agent_of_geometry[geom[hit]]
    for obj in objects if isinstance(objects, list) else [objects]:
        if obj.scene is None:
            continue
        b = obj.scene.cast_rays(rays)
        tb = b["t_hit"].numpy().astype(np.float64)
        closer = tb < t
        t[closer] = tb[closer]
        group[closer] = OBJECT
        agent[closer] = obj.agents[b["geometry_ids"].numpy()[closer]]
        prim[closer] = b["primitive_ids"].numpy()[closer]
        uv[closer] = b["primitive_uvs"].numpy()[closer]
        normal[closer] = b["primitive_normals"].numpy()[closer]
    flip = np.einsum("ij,ij->i", normal, dirs) > 0
    normal[flip] *= -1
    point = origins + np.where(np.isfinite(t), t, 0.0)[:, None] * dirs
    return Hits(t, group, agent, prim, uv, normal, point)


def occluded(static: StaticScene, objects: ObjectScene, origins: np.ndarray, dirs: np.ndarray,
             tfar: float | np.ndarray = np.inf) -> np.ndarray:
    """Whether anything lies on each ray between 0 and ``tfar`` (per ray or common)."""
    if np.ndim(tfar) == 0:
        rays = _tensor_rays(origins, dirs)
        out = static.scene.test_occlusions(rays, tfar=float(tfar)).numpy()
        for obj in objects if isinstance(objects, list) else [objects]:
            if obj.scene is not None:
                out |= obj.scene.test_occlusions(rays, tfar=float(tfar)).numpy()
        return out
    # per-ray limits: scale the directions so that t = 1 is the limit
    scaled = dirs * np.asarray(tfar)[:, None]
    return occluded(static, objects, origins, scaled, 1.0)


def interpolate(mesh: Mesh, prim: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Per-vertex attributes of ``mesh`` at hits (triangle ``prim``, barycentric ``uv``)."""
    f = mesh.faces[prim]
    w1, w2 = uv[:, 0:1], uv[:, 1:2]
    a = mesh.attrs
    return a[f[:, 0]] * (1 - w1 - w2) + a[f[:, 1]] * w1 + a[f[:, 2]] * w2


def all_objects_on_rays(static: StaticScene, objects: list[ObjectScene], origins: np.ndarray, dirs: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Every (ray index, agent) pair whose ray passes through the agent's mesh (amodal masks)."""
    keys = [np.zeros(0, dtype=np.int64)]
    if len(origins) == 0:
        return keys[0], np.zeros(0, dtype=np.int32)
    rays = _tensor_rays(origins, dirs)
    for obj in [static.objects, *objects]:
        if obj.scene is None:
            continue
        r = obj.scene.list_intersections(rays)
        ray_ids = r["ray_ids"].numpy().astype(np.int64)
        keys.append(ray_ids * 100000 + obj.agents[r["geometry_ids"].numpy()])
    key = np.unique(np.concatenate(keys))
    return key // 100000, (key % 100000).astype(np.int32)
