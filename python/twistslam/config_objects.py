"""The ``objects`` section of :class:`twistslam.Config`: the 3D object tracker (cpp/objects).

Every field but the Python-side ones (``frame``, ``classes``, ``planar_classes``,
``min_track_score``) is an option of the C++ tracker (``twistslam._core.objects.Tracker``);
:meth:`ObjectsConfig.tracker_options` gives them in the layout it takes. Detection scores are
PointRCNN's raw confidences (not probabilities; they range about -5 to 15 on KITTI).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from ._settings import param

#: fields read in Python, not passed to the C++ tracker
PYTHON_ONLY = ("frame", "classes", "planar_classes", "min_track_score")


@dataclass
class ObjectsConfig:
    """3D multi-object tracking from detections (docs/objects.md)."""

    frame: str = param("auto", "tracking frame: 'world' needs camera poses (oxts / poses, or a "
                       "SLAM run), 'camera' tracks in each frame's camera frame as AB3DMOT; "
                       "'auto' = world when the sequence has poses")
    classes: list[str] = param(["Car"], "detection classes that are tracked (KITTI names)")
    planar_classes: list[str] = param(
        ["Car", "Van", "Truck", "Bus", "Tram"],
        "classes on the planar link (3 DoF: ground-plane translation + yaw); others are free")
    ground_normal: list[float] = param(
        [0.0, -1.0, 0.0], "planar link normal (up) in the tracking frame until a road plane is "
        "estimated: camera -y (KITTI's cameras are mounted level)")
    association: str = param("giou_3d", "association cost: giou_3d (1 - GIoU), iou_bev "
                             "(1 - IoU) or centre_distance (m, the paper's 2 m rule)")
    max_cost: float = param(1.2, "first-pass gate: GIoU > -0.2, AB3DMOT's KITTI setting "
                            "(boxes may not overlap after a missed frame)", lo=0.0)
    second_pass: bool = param(True, "associate low-score detections with unmatched tracks")
    second_pass_max_cost: float = param(1.0, "second-pass gate: GIoU > 0 (a weak detection "
                                        "must overlap its track)", lo=0.0)
    high_score: float = param(1.0, "detections at least this confident take part in the first "
                              "pass and births", "score")
    low_score: float = param(-1.0, "below this a detection is dropped; between low_score and "
                             "high_score it only keeps known tracks alive", "score")
    birth_score: float = param(1.0, "an unmatched detection at least this confident starts a "
                               "track", "score")
    birth_hits: int = param(2, "detections before a track is confirmed; 2 vs AB3DMOT's 3: "
                            "sAMOTA 91.8 -> 93.9 on the 5 public validation sequences (the "
                            "score threshold removes the extra short false tracks)", "frames", lo=1)
    max_misses: int = param(2, "consecutive missed frames a confirmed track survives",
                            "frames", lo=0)
    tentative_max_misses: int = param(0, "consecutive missed frames a tentative track survives",
                                      "frames", lo=0)
    optimize: bool = param(True, "sliding-window optimisation of each track's poses after each "
                           "association (e_const, e_det, detection prior)")
    window: int = param(6, "frames in each track's optimisation window: 6 vs 10 gives the same "
                        "MOTA/MOTP on the validation sequences at twice the speed (~1600 "
                        "frames/s median)", "frames", lo=2)
    report_tentative_frames: bool = param(
        True, "once a track is confirmed, its frames before confirmation are reported too "
        "(the results are written after the run)")
    max_reported_gap: int = param(3, "missed frames between two detections of a track that "
                                  "are reported with the smoothed prediction", "frames", lo=0)
    min_track_score: float = param(
        4.0, "tracks whose mean detection score is lower are left out of tracking/SEQ.txt "
        "(tracking_all/ keeps every box for sAMOTA); chosen on the public validation "
        "sequences, then fixed: MOTA 84.1 / 85.5 / 85.3 at 3 / 4 / 5 (PointRCNN scores)", "score")
    const_sigma_translation: float = param(
        0.1, "e_const: change of the translational twist between frames (1 m/s^2 per 0.1 s "
        "frame); 0.3 let one noisy detection give a car 1 m/frame of sideways speed (an id "
        "switch on the simulator) and is no better on real KITTI (MOTA 84.0 vs 84.1 at score 3)",
        "m/frame", lo=1e-6)
    const_sigma_rotation: float = param(0.03, "e_const: change of the rotational twist between "
                                        "frames", "rad/frame", lo=1e-6)
    det_sigma_translation: float = param(0.3, "e_det: noise of a detection twist (two boxes)",
                                         "m", lo=1e-6)
    det_sigma_rotation: float = param(0.1, "e_det: rotation noise of a detection twist", "rad",
                                      lo=1e-6)
    prior_sigma_translation: float = param(0.3, "detection prior: noise of a box centre", "m",
                                           lo=1e-6)
    prior_sigma_rotation: float = param(0.1, "detection prior: noise of a box orientation",
                                        "rad", lo=1e-6)
    link_sigma_translation: float = param(
        0.1, "out-of-link translation allowed per frame: the camera's -y is not the road's "
        "normal (pitch, slopes: 1 deg is 0.7 m of height over 40 m); 0.01 cost 5 points of 3D "
        "MOTP on real KITTI (74.6 vs 80.5)", "m/frame", lo=1e-6)
    link_sigma_rotation: float = param(0.002, "out-of-link rotation allowed per frame",
                                       "rad/frame", lo=1e-6)
    huber_const: float = param(3.0, "Huber threshold of e_const", "sigma", lo=0.0)
    huber_det: float = param(2.0, "Huber threshold of e_det", "sigma", lo=0.0)
    huber_prior: float = param(2.0, "Huber threshold of the detection prior", "sigma", lo=0.0)
    use_const: bool = param(True, "e_const in the window (ablation switch)")
    use_det_twist: bool = param(True, "e_det in the window (ablation switch)")
    use_prior: bool = param(True, "detection prior in the window (ablation switch)")
    use_link: bool = param(True, "mechanical-link residual in the window (ablation switch)")
    max_iterations: int = param(5, "Levenberg-Marquardt iterations per window (the start is "
                                "the previous solution: a few steps converge)", lo=1)

    def tracker_options(self) -> dict[str, Any]:
        """The options dictionary of ``twistslam._core.objects.Tracker``."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name not in PYTHON_ONLY}
