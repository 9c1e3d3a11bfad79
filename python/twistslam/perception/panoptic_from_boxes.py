"""Panoptic labels without network weights: instance masks from 3D boxes, road from LiDAR.

What runs on real KITTI here; the work is done in the C++ core (``cpp/perception/box_masks``,
a few milliseconds per KITTI frame where numpy took 35-55 ms). For each box of the frame (from a detection file, or from the
run's detector on this frame) the LiDAR points inside the box, minus the ground under it, are projected into
the left image (``P2``) and their 2D convex hull is filled; boxes are drawn far to near so a
nearer object covers a farther one. Road: a RANSAC plane through the low points; the points
within a band of it mark cells of a bird's-eye grid, and a pixel is road when its ray meets
the plane in a marked cell (a LiDAR ring is many pixels apart near the car, so dilating the
projected points alone leaves gaps). Everything else is unknown, hence static.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from twistslam import _core
from twistslam.datasets import DONT_CARE, ObjectTable

from .panoptic import CAR, PERSON, ROAD, UNKNOWN, Panoptic

#: KITTI object classes -> Cityscapes ids (Cityscapes has no van: a van is a car);
#: a class not listed (Misc) is unknown, hence static
KITTI_TO_CITYSCAPES = {"Car": CAR, "Van": CAR, "Truck": 27, "Pedestrian": PERSON,
                       "Person_sitting": PERSON, "Cyclist": 25, "Tram": 31}


@dataclass(frozen=True)
class BoxMaskConfig:
    """Options of :class:`PanopticFromBoxes` (measured on real KITTI 0001 and the simulator,
    tests/python/test_perception_panoptic.py)."""

    #: m below the camera for a point to be a ground candidate: KITTI's camera is 1.65 m
    #: high, and 1.0 m keeps car roofs and walls out while leaving hundreds of road points
    low_point_below_camera_m: float = 1.0
    #: m, RANSAC inlier distance of the plane fit (a few times the LiDAR's ~2 cm range noise)
    plane_fit_threshold_m: float = 0.1
    #: m from the plane for a point to mark a road cell. Simulator road IoU 0.80 / 0.78 /
    #: 0.75 at 0.05 / 0.1 / 0.2 (its kerbs are 0.15 m high): 0.1 keeps real KITTI's uneven
    #: road (28 % of the image is road on 0001; 25 % at 0.05, 30 % at 0.2) without the sidewalk
    ground_band_m: float = 0.1
    #: m above the plane for a point inside a box to join the object's hull (lower ones are
    #: the ground under it). Simulator car IoU 0.886 / 0.877 / 0.834 at 0.05 / 0.1 / 0.2;
    #: KITTI 0001 unoccluded cars' mask-box IoU 0.84 / 0.81 / 0.78. 0.1 rather than 0.05:
    #: twice the LiDAR's range noise, for roads less flat than these
    hull_ground_clearance_m: float = 0.1
    #: m, side of a bird's-eye road cell: simulator road IoU 0.748 / 0.750 / 0.737 at
    #: 0.25 / 0.5 / 1 m (finer cells leave gaps between rings, coarser ones spill over kerbs)
    road_cell_m: float = 0.5
    #: cells of dilation of the road grid: road IoU 0.741 / 0.750 / 0.740 at 0 / 1 / 2
    road_dilation_cells: int = 1
    #: m, farthest road: beyond, rings are too sparse to mark cells reliably
    road_max_range_m: float = 40.0
    #: inside points a box needs for a mask (a hull needs 3 non-collinear points)
    min_box_points: int = 3
    #: boxes scored below are ignored; ``None`` keeps all (labels score 1). For the real
    #: PointRCNN detections of 0001, 2.0 puts all car pixels inside labelled objects'
    #: 2D boxes (98.7 % with every box) at a coverage of 94.3 % (94.7 %) of their points
    min_score: float | None = None


#: ``BoxMaskConfig.min_score`` of the masks made from a run's detector, by detector name
#: (scores are not comparable across detectors; a detector not listed keeps all its boxes:
#: files, whose scale depends on who wrote them, 3DSSD and callables). The classical
#: detector's scores lie in (0, 1]. 0.05 since its road is held behind occluders: its car boxes
#: on real KITTI 0001 within 2 m of a labelled object / elsewhere are 132 / 13 at 0.05, 101 / 5
#: at 0.1; 0.1 -> 0.05 took the whole system's 3D MOTA there from 75.0 to 79.2 % (TP 95.8 ->
#: 100 %, FP 5 both) and, on 28 simulated sequences, the cars tracked from 126 to 129 of 132
#: (ghosts 50 -> 51): far lead cars scored 0.05-0.1 get masks from their first frame
#: (docs/visual_objects.md, "Masks from the configured detector")
DETECTOR_MASK_MIN_SCORE: dict[str, float | None] = {"classical": 0.05}


def ground_plane(points: np.ndarray, config: BoxMaskConfig) -> np.ndarray | None:
    """Plane ``[n, d]`` (``n . X + d = 0``, ``n`` pointing up, i.e. towards -y) through the
    low points of ``points`` (N, >=3, camera frame), or ``None`` when there are too few."""
    return _core.perception.ground_plane(
        np.asarray(points, dtype=np.float64)[:, :3],
        low_point_below_camera_m=config.low_point_below_camera_m,
        plane_fit_threshold_m=config.plane_fit_threshold_m)


def panoptic_from_boxes(points_c: np.ndarray, boxes: ObjectTable, P: np.ndarray,
                        shape: tuple[int, int], config: BoxMaskConfig = BoxMaskConfig()
                        ) -> Panoptic:
    """Labels of one image from its LiDAR points and 3D boxes.

    Parameters
    ----------
    points_c : (N, >=3) LiDAR points in the rectified camera frame (rows with NaN ignored).
    boxes : this frame's boxes; instance id of row ``k`` is ``k + 1`` (DontCare rows, and rows
        scored below ``config.min_score``, skipped).
    P : (3, 4) projection of the left image (``calib.P2``).
    shape : (H, W) of the left image.
    """
    use = boxes.cls != DONT_CARE
    if config.min_score is not None:
        use &= boxes.score >= config.min_score
    rows = np.flatnonzero(use)
    class_ids = np.array([KITTI_TO_CITYSCAPES.get(str(c), UNKNOWN) for c in boxes.cls[rows]],
                         dtype=np.int32)
    options = {k: v for k, v in asdict(config).items() if k != "min_score"}
    class_id, instance_id, _ = _core.perception.masks_from_boxes(
        np.asarray(points_c, dtype=np.float64)[:, :3], boxes.box_3d[rows].reshape(-1, 7),
        class_ids, (rows + 1).astype(np.int32), P, int(shape[0]), int(shape[1]),
        unknown_id=UNKNOWN, road_id=ROAD, **options)
    return Panoptic(class_id, instance_id, source="boxes")


def _check_frame(frame) -> None:
    if frame.points_c is None:
        raise ValueError(f"frame {frame.index}: masks from boxes need the LiDAR scan "
                         "(points_c is None; open the sequence with lidar=True)")
    if frame.image_left is None:
        raise ValueError(f"frame {frame.index}: masks from boxes need the left image size "
                         "(image_left is None)")


class PanopticFromBoxes:
    """Panoptic source ``frame -> Panoptic`` from a table of 3D boxes (all frames) and each
    frame's LiDAR scan and left image size."""

    def __init__(self, boxes: ObjectTable, config: BoxMaskConfig = BoxMaskConfig()) -> None:
        self.boxes, self.config = boxes, config

    def __call__(self, frame) -> Panoptic:
        _check_frame(frame)
        return panoptic_from_boxes(frame.points_c, self.boxes.in_frame(frame.index),
                                   frame.calib.P2, frame.image_left.shape[:2], self.config)


class PanopticFromDetections:
    """Panoptic source ``(frame, detections) -> Panoptic``: masks from the boxes a detection
    stage gave this very frame (:class:`~.detection.Detections3D`), so the masks follow
    whichever detector the run uses and the detector runs once per frame for both the masks
    and the LiDAR fusion (:func:`twistslam.run`)."""

    def __init__(self, config: BoxMaskConfig = BoxMaskConfig()) -> None:
        self.config = config

    def __call__(self, frame, detections) -> Panoptic:
        _check_frame(frame)
        return panoptic_from_boxes(frame.points_c, detections.to_table(frame.index),
                                   frame.calib.P2, frame.image_left.shape[:2], self.config)
