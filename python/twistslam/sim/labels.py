"""KITTI tracking labels of one frame from the rendered left image's object masks.

- 2D box: bounding box of the object's *visible* pixels (pixel centres, image 2).
- occlusion: from the visible fraction of the object's silhouette inside the image
  (visible pixels / pixels whose ray passes through the object at all): 0 if >= 0.9,
  1 if >= 0.5, else 2.
- truncation (tracking-style integer level): 0 when the silhouette does not touch the
  image border; else 1, or 2 when over half of the projected 3D box lies outside the image.
- 3D box: exact size, geometric centre and yaw (about the camera y axis) of the object box
  in the camera frame, written as KITTI's bottom centre by the label writer.
"""

from __future__ import annotations

import numpy as np

from twistslam.datasets import ObjectTable
from twistslam.geometry import project_boxes

from .camera_render import Camera
from .mesh import rotate
from .raycast import OBJECT, Hits, tensor_rays
from .world import World


def boxes_in_camera(world: World, agents: np.ndarray, n: int) -> np.ndarray:
    """(K, 7) boxes ``[cx, cy, cz, l, w, h, ry]`` of ``agents`` in the camera frame at ``n``."""
    T_c_o = np.linalg.inv(world.T_m_c[n]) @ world.traj.T_m_o[agents, n]
    x_axis = T_c_o[:, :3, 0]
    ry = np.arctan2(-x_axis[:, 2], x_axis[:, 0])
    size = np.array([world.agents[a].size for a in agents]).reshape(-1, 3)
    return np.column_stack([T_c_o[:, :3, 3], size, ry])


def frame_labels(world: World, camera: Camera, hits: Hits, n: int) -> ObjectTable:
    """Labels of every object with enough visible pixels in the left image at frame ``n``."""
    H, W = camera.height, camera.width
    agent_img = np.where(hits.group == OBJECT, hits.agent, -1)
    visible = agent_img >= 0
    counts = np.bincount(agent_img[visible], minlength=len(world.agents))
    agents = np.flatnonzero(counts >= world.cfg.output.min_visible_pixels)
    agents = agents[world.track_id[agents] >= 0]
    if len(agents) == 0:
        return ObjectTable.empty()
    pix = np.flatnonzero(visible)
    order = np.argsort(agent_img[pix], kind="stable")
    pix, owner = pix[order], agent_img[pix[order]]
    start = np.searchsorted(owner, agents)
    end = np.searchsorted(owner, agents, side="right")
    boxes = boxes_in_camera(world, agents, n)
    proj = project_boxes(boxes, camera.P)  # unclipped image boxes of the 3D boxes
    clipped = np.clip(proj, [0, 0, 0, 0], [W - 1, H - 1, W - 1, H - 1])
    amodal, border = _amodal(world, camera, agents, clipped, n)
    rows = []
    for k, a in enumerate(agents):
        p = pix[start[k] : end[k]]
        y, x = p // W, p % W
        box2d = [x.min(), y.min(), x.max(), y.max()]
        frac = counts[a] / max(amodal[k], counts[a])
        occlusion = 0 if frac >= 0.9 else 1 if frac >= 0.5 else 2
        area = max((proj[k, 2] - proj[k, 0]) * (proj[k, 3] - proj[k, 1]), 1e-9)
        inside = (clipped[k, 2] - clipped[k, 0]) * (clipped[k, 3] - clipped[k, 1]) / area
        truncation = 0 if not border[k] else (1 if inside >= 0.5 else 2)
        cx, _, cz = boxes[k, :3]
        alpha = np.arctan2(np.sin(boxes[k, 6] - np.arctan2(cx, cz)), np.cos(boxes[k, 6] - np.arctan2(cx, cz)))
        cls = "Car" if world.is_car[a] else "Pedestrian"
        rows.append((world.track_id[a], cls, truncation, occlusion, alpha, box2d))
    n_rows = len(rows)
    return ObjectTable(
        frame=np.full(n_rows, n), track_id=[r[0] for r in rows], cls=[r[1] for r in rows],
        truncation=[r[2] for r in rows], occlusion=[r[3] for r in rows], alpha=[r[4] for r in rows],
        box_2d=np.array([r[5] for r in rows], dtype=np.float64), box_3d=boxes, score=np.ones(n_rows),
    )


def _amodal(world: World, camera: Camera, agents: np.ndarray, clipped: np.ndarray, n: int
            ) -> tuple[np.ndarray, np.ndarray]:
    """Amodal silhouette size (pixels whose ray passes through the object at all) and whether
    it touches the image border, for each of ``agents`` with clipped image boxes ``clipped``.

    The silhouette lies inside the projected 3D box, so only the box's pixels are tested, each
    against the object alone: its rays are moved into the object frame and cast into the
    object's own scene, built once per sequence. (Listing every intersection of every object
    on the rays of all boxes, and deduplicating them, cost several times more.)"""
    H, W = camera.height, camera.width
    amodal = np.zeros(len(agents), dtype=np.int64)
    border = np.zeros(len(agents), dtype=bool)
    dirs_c = camera.directions().reshape(H, W, 3)
    for k, a in enumerate(agents):
        x1, y1, x2, y2 = clipped[k]
        r0, r1, c0, c1 = int(np.floor(y1)), int(np.ceil(y2)), int(np.floor(x1)), int(np.ceil(x2))
        T_o_c = np.linalg.inv(world.object_pose(a, n)) @ world.T_m_c[n]
        d = dirs_c[r0 : r1 + 1, c0 : c1 + 1].reshape(-1, 3)
        origin = T_o_c[:3, :3] @ camera.centre + T_o_c[:3, 3]
        rays = tensor_rays(np.broadcast_to(origin, d.shape), rotate(d, T_o_c[:3, :3]))
        hit = world.object_scenes[a].test_occlusions(rays).numpy().reshape(r1 - r0 + 1, c1 - c0 + 1)
        amodal[k] = hit.sum()
        border[k] = ((r0 == 0 and hit[0].any()) or (r1 == H - 1 and hit[-1].any()) or (c0 == 0 and hit[:, 0].any())
                     or (c1 == W - 1 and hit[:, -1].any()))
    return amodal, border
