"""A run's frames into a :class:`RerunLogger`: what :func:`twistslam.run` calls with
``viz=True`` / ``viz_save=...`` after each tracked frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..objects.camera_boxes import CameraBoxRules
from ..objects.visual import KITTI_TYPES, cluster_box
from ..perception.panoptic import ROAD
from .lidar_view import lidar_view
from .logger import RerunLogger
from .views import ObjectView

#: the static map is re-sent every this many frames (it grows slowly; sending it each frame
#: would write the whole map 10 times a second)
STATIC_POINTS_EVERY = 10


class RunViewer:
    """Logs each frame of a run: image, segmentation, camera, object clusters, the frame's
    LiDAR returns (road returns apart, by ``road_class_id``), stage times."""

    def __init__(self, sequence, *, spawn: bool = False, save: str | Path | None = None,
                 box_rules: CameraBoxRules = CameraBoxRules(), road_class_id: int = ROAD) -> None:
        self.logger = RerunLogger(spawn=spawn, save=save)
        self.sequence = sequence
        self.box_rules = box_rules
        self.road_class_id = road_class_id
        self._camera_logged = False
        self._camera_poses: dict[int, np.ndarray] = {}  # frame -> T_w_c, the rows so far

    def log(self, item, tracked, slam) -> None:
        frame = item.frame
        image = np.asarray(frame.image_left)
        if image.ndim == 2:
            image = np.repeat(image[:, :, None], 3, axis=2)
        if not self._camera_logged and slam.camera is not None:
            cam = slam.camera
            self.logger.log_camera(np.asarray(cam.K), image.shape[1], image.shape[0])
            self._camera_logged = True
        views = []
        T_c_w = np.linalg.inv(tracked.T_w_c)
        self._camera_poses[int(tracked.index)] = np.asarray(tracked.T_w_c)
        for c in slam.objects():
            frames = np.asarray(c["frames"])
            if not len(frames) or frames[-1] != tracked.index or not c["detected"][-1]:
                continue
            points = np.asarray(c["points_o"]).reshape(-1, 3)
            T_w_o_rows = np.asarray(c["T_w_o"]).reshape(-1, 4, 4)
            # the run's output box (objects/visual.py): a canonical track's own, else fitted
            T_o_box, size, _ = cluster_box(c, self._camera_poses, self.box_rules)
            T_w_o = T_w_o_rows[-1]
            speed = 0.0
            if len(frames) > 1:
                speed = float(np.linalg.norm(np.asarray(c["twist"])[-2][:3]) * 36.0)
            views.append(ObjectView(
                track_id=int(c["id"]), cls=KITTI_TYPES.get(int(c["class_id"]), "Misc").lower(),
                T_w_o=T_w_o @ T_o_box, size=size, velocity_kmh=speed,
                points_w=points @ T_w_o[:3, :3].T + T_w_o[:3, 3],
                box2d=_box2d(points, T_c_w @ T_w_o, slam.camera)))
        static = None
        if tracked.index % STATIC_POINTS_EVERY == 0:
            static = slam.map_points()["X_w"]
        lidar = None
        if frame.points_c is not None and slam.camera is not None:
            lidar = lidar_view(frame.points_c, tracked.T_w_c, np.asarray(slam.camera.K),
                               item.class_ids, self.road_class_id)
        scalars = {"inliers": float(tracked.num_inliers),
                   "objects_tracked": float(tracked.num_objects_tracked),
                   **{f"ms/{k}": float(v) for k, v in {**item.stage_ms, **tracked.timings_ms}.items()}}
        self.logger.log_frame(tracked.index, image_left=image, T_w_c=tracked.T_w_c,
                              class_ids=item.class_ids, instance_ids=item.instance_ids,
                              objects=views, static_points_w=static,
                              lidar_points_w=None if lidar is None else lidar.scan_w,
                              road_lidar_points_w=None if lidar is None else lidar.road_w,
                              scalars=scalars)

    def close(self) -> None:
        self.logger.close()


def _box2d(points_o: np.ndarray, T_c_o: np.ndarray, camera) -> np.ndarray | None:
    """Bounding box (x1, y1, x2, y2) of the cluster's points projected into the image."""
    X = points_o @ T_c_o[:3, :3].T + T_c_o[:3, 3]
    X = X[X[:, 2] > 0.1]
    if len(X) < 3 or camera is None:
        return None
    K = np.asarray(camera.K)
    uv = (X @ K.T)[:, :2] / X[:, 2:3]
    return np.array([*uv.min(axis=0), *uv.max(axis=0)])
