"""Live rerun view of a SLAM run: :class:`RerunLogger`.

Entity layout (world = first camera frame, x right, y down, z forward):

==================================  ===============================================
``world``                           view coordinates RDF (static)
``world/camera``                    camera pose ``T_w_c`` and its pinhole frustum
``world/camera/image``              the left image
``world/camera/image/segmentation`` class ids, Cityscapes colours
``world/camera/image/instances``    instance masks, one colour per instance
``world/camera/image/boxes``        2D boxes labelled ``id 12 car 34 km/h``
``world/static_points``             static map points (grey)
``world/lidar/scan``                the frame's LiDAR returns (light grey)
``world/lidar/road``                those on road pixels (green)
``world/objects/points``            object points, one colour per track
``world/objects/boxes``             3D boxes
``world/objects/trajectories``      object trajectories so far
``world/camera_trajectory``         camera trajectory so far
``scalars/<name>``                  per-frame time series (inliers, stage times, ...)
==================================  ===============================================
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from types import ModuleType, TracebackType
from typing import Any

import numpy as np

from ._rerun import import_rerun
from .colors import (CAMERA_TRAJECTORY_COLOR, CITYSCAPES_COLORS, LIDAR_COLOR, ROAD_LIDAR_COLOR,
                     STATIC_POINT_COLOR, rotation_to_quaternion_xyzw, track_color)
from .views import (ObjectView, check_array, check_image, check_label_image, check_object,
                    check_pose, check_scalars)

TIMELINE = "frame"
WORLD = "world"
CAMERA = "world/camera"
IMAGE = "world/camera/image"
SEGMENTATION = "world/camera/image/segmentation"
INSTANCES = "world/camera/image/instances"
BOXES_2D = "world/camera/image/boxes"
STATIC_POINTS = "world/static_points"
LIDAR_SCAN = "world/lidar/scan"
LIDAR_ROAD = "world/lidar/road"
OBJECT_POINTS = "world/objects/points"
OBJECT_BOXES = "world/objects/boxes"
OBJECT_TRAJECTORIES = "world/objects/trajectories"
CAMERA_TRAJECTORY = "world/camera_trajectory"
SCALARS = "scalars"
#: the map view's eye: this high above the first camera (m), looking down at the road this far
#: ahead of it (m): KITTI's cars are tracked within ~50 m, the view spans ~60 m of road
MAP_EYE_HEIGHT_M = 70.0
MAP_LOOK_AHEAD_M = 20.0


class RerunLogger:
    """Logs each frame of a run to rerun: images, segmentation, objects, map, trajectories.

    Parameters
    ----------
    app_id : str
        Rerun application id (the viewer groups recordings by it).
    spawn : bool
        Start a viewer and stream to it.
    save : str or Path, optional
        Write the recording to this ``.rrd`` file (no viewer needed: headless machines,
        tests). With ``spawn`` too, both happen. With neither, the logger streams to a viewer
        already running on the default port (``rerun`` in a terminal).

    Raises
    ------
    ImportError
        When ``rerun-sdk`` is not installed (``pip install 'twistslam[viz]'``).

    Examples
    --------
    >>> with RerunLogger(save="run.rrd") as viz:                      # doctest: +SKIP
    ...     viz.log_camera(K, width, height)
    ...     viz.log_frame(0, image_left=image, T_w_c=np.eye(4))
    """

    def __init__(self, app_id: str = "twistslam", *, spawn: bool = False,
                 save: str | Path | None = None) -> None:
        self._rr: ModuleType = import_rerun()
        self._stream: Any = self._rr.RecordingStream(app_id)
        self._camera_positions: list[np.ndarray] = []
        self._object_positions: dict[int, list[np.ndarray]] = {}
        self._closed = False
        self._open_sinks(spawn, None if save is None else Path(save))
        self._stream.send_blueprint(self._default_layout())
        self._log_static_context()

    # ------------------------------------------------------------------ public API

    def log_camera(self, K: np.ndarray, width: int, height: int) -> None:
        """Log the left camera's intrinsics (static: once per run).

        Parameters
        ----------
        K : (3, 3) array
            Intrinsic matrix of the left camera.
        width, height : int
            Image size in pixels.
        """
        intrinsics = check_array(K, (3, 3), "K")
        if int(width) <= 0 or int(height) <= 0:
            raise ValueError(f"width and height must be positive, got {width} x {height}")
        self._stream.log(CAMERA, self._rr.Pinhole(
            image_from_camera=intrinsics, width=int(width), height=int(height),
            camera_xyz=self._rr.ViewCoordinates.RDF, image_plane_distance=1.0), static=True)

    def log_frame(self, index: int, *, image_left: np.ndarray, T_w_c: np.ndarray,
                  class_ids: np.ndarray | None = None, instance_ids: np.ndarray | None = None,
                  objects: Sequence[ObjectView] = (), static_points_w: np.ndarray | None = None,
                  lidar_points_w: np.ndarray | None = None,
                  road_lidar_points_w: np.ndarray | None = None,
                  scalars: dict[str, float] | None = None) -> None:
        """Log one frame on the ``frame`` timeline.

        Parameters
        ----------
        index : int
            Frame index (the time of everything logged here).
        image_left : (H, W, 3) uint8
            Left RGB image.
        T_w_c : (4, 4) array
            Camera pose in the world (first camera) frame.
        class_ids : (H, W) int array, optional
            Cityscapes class id per pixel.
        instance_ids : (H, W) int array, optional
            Instance id per pixel, 0 = none.
        objects : sequence of ObjectView
            Tracked objects in this frame.
        static_points_w : (N, 3) array, optional
            Static map points in the world frame.
        lidar_points_w : (N, 3) array, optional
            The frame's LiDAR returns in the world frame (those off the road:
            :func:`twistslam.viz.lidar_view.lidar_view`).
        road_lidar_points_w : (M, 3) array, optional
            Its returns on the road, shown green (the paper's figure 1 (d)).
        scalars : dict, optional
            Per-frame numbers (inliers, stage times in ms, ...), one time series each.

        Raises
        ------
        ValueError
            A field of the wrong shape or type; the message names the field.
        """
        image = check_image(image_left)
        pose = check_pose(T_w_c, "T_w_c")
        classes = None if class_ids is None else check_label_image(class_ids, image.shape[:2],
                                                                   "class_ids")
        instances = None if instance_ids is None else check_label_image(
            instance_ids, image.shape[:2], "instance_ids")
        views = [check_object(view, i) for i, view in enumerate(objects)]
        static_points = None if static_points_w is None else check_array(
            static_points_w, (None, 3), "static_points_w")
        lidar_points = None if lidar_points_w is None else check_array(
            lidar_points_w, (None, 3), "lidar_points_w")
        road_points = None if road_lidar_points_w is None else check_array(
            road_lidar_points_w, (None, 3), "road_lidar_points_w")
        numbers = check_scalars(scalars)

        self._stream.set_time(TIMELINE, sequence=int(index))
        self._log_camera_pose(pose)
        self._log_image(image, classes, instances)
        self._log_objects_2d(views)
        self._log_objects_3d(views)
        self._log_points(STATIC_POINTS, static_points, STATIC_POINT_COLOR)
        self._log_points(LIDAR_SCAN, lidar_points, LIDAR_COLOR, radius_ui=1.0)
        self._log_points(LIDAR_ROAD, road_points, ROAD_LIDAR_COLOR, radius_ui=1.0)
        self._log_trajectories(pose, views)
        self._log_scalars(numbers)

    def close(self) -> None:
        """Flush the recording and close its sinks (the ``.rrd`` is complete after this)."""
        if self._closed:
            return
        self._closed = True
        self._stream.flush()
        self._stream.disconnect()

    def __enter__(self) -> RerunLogger:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close()

    # ------------------------------------------------------------------ setup

    def _open_sinks(self, spawn: bool, save: Path | None) -> None:
        rr = self._rr
        if save is not None:
            save.parent.mkdir(parents=True, exist_ok=True)
        if spawn and save is not None:
            self._stream.spawn(connect=False)
            self._stream.set_sinks(rr.GrpcSink(), rr.FileSink(str(save)))
        elif spawn:
            self._stream.spawn()
        elif save is not None:
            self._stream.save(str(save))
        else:
            self._stream.connect_grpc()

    def _default_layout(self) -> Any:
        """The 3D scene and the map from above (the paper's figure 1 (d): LiDAR returns, the
        road's in green, the tracked cars' boxes, the camera frustum) beside the image with
        masks and boxes labelled with id and speed (figure 1 (a)) above the time series."""
        rrb = self._rr.blueprint
        # world = first camera frame, y down: "above" is -y; the eye follows the camera, the
        # road ahead (+z) up in the view
        from_above = rrb.EyeControls3D(position=[0.0, -MAP_EYE_HEIGHT_M, MAP_LOOK_AHEAD_M],
                                       look_target=[0.0, 0.0, MAP_LOOK_AHEAD_M],
                                       eye_up=[0.0, 0.0, 1.0], tracking_entity=CAMERA)
        return rrb.Blueprint(rrb.Horizontal(
            rrb.Vertical(rrb.Spatial3DView(origin=WORLD, name="3D"),
                         rrb.Spatial3DView(origin=WORLD, name="map from above",
                                           eye_controls=from_above)),
            rrb.Vertical(rrb.Spatial2DView(origin=IMAGE, name="left image"),
                         rrb.TimeSeriesView(origin=SCALARS, name="per frame"))))

    def _log_static_context(self) -> None:
        rr = self._rr
        self._stream.log(WORLD, rr.ViewCoordinates.RDF, static=True)
        from ..perception.panoptic import CITYSCAPES_CLASSES  # numpy only

        self._stream.log(SEGMENTATION, rr.AnnotationContext([
            rr.AnnotationInfo(id=class_id, label=name, color=CITYSCAPES_COLORS.get(class_id))
            for class_id, name in CITYSCAPES_CLASSES.items()]), static=True)

    # ------------------------------------------------------------------ per frame

    def _log_camera_pose(self, T_w_c: np.ndarray) -> None:
        self._stream.log(CAMERA, self._rr.Transform3D(translation=T_w_c[:3, 3],
                                                      mat3x3=T_w_c[:3, :3]))

    def _log_image(self, image: np.ndarray, classes: np.ndarray | None,
                   instances: np.ndarray | None) -> None:
        rr = self._rr
        self._stream.log(IMAGE, rr.Image(image))
        if classes is None:
            self._stream.log(SEGMENTATION, rr.Clear(recursive=False))
        else:
            self._stream.log(SEGMENTATION, rr.SegmentationImage(classes, opacity=0.4,
                                                                draw_order=1.0))
        if instances is None:
            self._stream.log(INSTANCES, rr.Clear(recursive=False))
            return
        present = [int(i) for i in np.unique(instances) if i != 0]
        self._stream.log(INSTANCES, rr.AnnotationContext(
            [rr.AnnotationInfo(id=0, label="none", color=(0, 0, 0, 0))]
            + [rr.AnnotationInfo(id=i, label=f"instance {i}", color=track_color(i))
               for i in present]))
        self._stream.log(INSTANCES, rr.SegmentationImage(instances, opacity=0.5, draw_order=2.0))

    def _log_objects_2d(self, views: list[ObjectView]) -> None:
        boxed = [view for view in views if view.box2d is not None]
        corners = np.array([view.box2d for view in boxed]).reshape(-1, 4)
        self._stream.log(BOXES_2D, self._rr.Boxes2D(
            array=corners, array_format=self._rr.Box2DFormat.XYXY,
            labels=[view.label() for view in boxed],
            colors=[track_color(view.track_id) for view in boxed], draw_order=3.0))

    def _log_objects_3d(self, views: list[ObjectView]) -> None:
        rr = self._rr
        self._stream.log(OBJECT_BOXES, rr.Boxes3D(
            centers=np.array([view.T_w_o[:3, 3] for view in views]).reshape(-1, 3),
            # object frame: x = length, y = height (down), z = width
            sizes=np.array([(view.size[0], view.size[2], view.size[1])
                            for view in views]).reshape(-1, 3),
            quaternions=[rr.Quaternion(xyzw=rotation_to_quaternion_xyzw(view.T_w_o[:3, :3]))
                         for view in views],
            colors=[track_color(view.track_id) for view in views],
            labels=[view.label() for view in views]))
        with_points = [view for view in views if view.points_w is not None]
        points = [view.points_w for view in with_points]
        colors = [np.tile(track_color(view.track_id), (len(view.points_w), 1))
                  for view in with_points]
        self._stream.log(OBJECT_POINTS, rr.Points3D(
            np.concatenate(points) if points else np.zeros((0, 3)),
            colors=np.concatenate(colors).astype(np.uint8) if colors else np.zeros((0, 3), np.uint8),
            radii=rr.Radius.ui_points(3.0)))

    def _log_points(self, entity: str, points: np.ndarray | None,
                    color: tuple[int, int, int], radius_ui: float = 2.0) -> None:
        if points is None:
            self._stream.log(entity, self._rr.Clear(recursive=False))
            return
        self._stream.log(entity, self._rr.Points3D(points, colors=color,
                                                   radii=self._rr.Radius.ui_points(radius_ui)))

    def _log_trajectories(self, T_w_c: np.ndarray, views: list[ObjectView]) -> None:
        rr = self._rr
        self._camera_positions.append(T_w_c[:3, 3].copy())
        self._stream.log(CAMERA_TRAJECTORY, rr.LineStrips3D(
            [np.array(self._camera_positions)], colors=CAMERA_TRAJECTORY_COLOR))
        for view in views:
            self._object_positions.setdefault(view.track_id, []).append(view.T_w_o[:3, 3].copy())
        track_ids = sorted(self._object_positions)
        self._stream.log(OBJECT_TRAJECTORIES, rr.LineStrips3D(
            [np.array(self._object_positions[t]) for t in track_ids],
            colors=[track_color(t) for t in track_ids],
            labels=[f"id {t}" for t in track_ids]))

    def _log_scalars(self, numbers: dict[str, float]) -> None:
        for name, value in numbers.items():
            parts = [part for part in name.split("/") if part]
            self._stream.log([SCALARS, *parts], self._rr.Scalars(value))
