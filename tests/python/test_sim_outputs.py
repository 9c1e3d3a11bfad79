"""Ground truth of a small simulated urban sequence against the files' own evidence:
reader round trips, LiDAR inside boxes, stereo and flow photo-consistency, labels vs masks."""

import filecmp
from pathlib import Path

import numpy as np
import pytest
from scipy.ndimage import maximum_filter

from twistslam.datasets import KittiTracking, read_detections, read_labels, read_oxts_poses, read_poses
from twistslam.geometry import box_iou_2d, project_boxes
from twistslam.sim.generate import generate
from twistslam.datasets.png16 import read_png16

W, H, FRAMES, SEQ = 414, 125, 4, "0003"


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sim") / "urban"
    generate(out, "urban", frames=FRAMES, seed=3, seq=SEQ, width=W, height=H, progress=False)
    return out


@pytest.fixture(scope="module")
def seq(root) -> KittiTracking:
    return KittiTracking(root, SEQ)


def _grey(img: np.ndarray) -> np.ndarray:
    return img.astype(np.float64) @ [0.299, 0.587, 0.114]


def test_layout_and_reader(root, seq):
    base = root / "training"
    for folder in ("image_02", "image_03", "velodyne", "velodyne_labels", "panoptic", "flow_occ", "flow_noc",
                   "disparity"):
        assert len(list((base / folder / SEQ).iterdir())) == FRAMES, folder
    for folder in ("calib", "oxts", "poses", "label_02", "object_poses"):
        assert (base / folder / f"{SEQ}.txt").is_file(), folder
    assert (root / "detections" / "oracle" / f"{SEQ}.txt").is_file()
    assert len(seq) == FRAMES
    frame = seq[1]
    assert frame.image_left.shape == (H, W, 3) and frame.image_right.shape == (H, W, 3)
    assert frame.points_c.shape[1] == 4 and len(frame.points_c) > 20000
    assert np.allclose(seq.gt_poses[0], np.eye(4))
    assert len(seq.gt_objects) > 0 and set(seq.gt_objects.cls) <= {"Car", "Pedestrian"}
    dets = read_detections(root / "detections" / "oracle" / f"{SEQ}.txt")
    assert len(dets) > 0 and set(dets.frame) <= set(range(FRAMES))


def test_oxts_recovers_poses(root, seq):
    poses = read_poses(root / "training" / "poses" / f"{SEQ}.txt")
    from_oxts = read_oxts_poses(root / "training" / "oxts" / f"{SEQ}.txt", seq.calib)
    assert np.abs(from_oxts[:, :3, 3] - poses[:, :3, 3]).max() < 1e-6
    assert np.abs(from_oxts[:, :3, :3] - poses[:, :3, :3]).max() < 1e-9
    travelled = np.linalg.norm(poses[-1, :3, 3])
    assert 0.5 * (FRAMES - 1) * 0.1 * 5 < travelled < (FRAMES - 1) * 0.1 * 16  # 5-15 m/s


def test_lidar_points_inside_boxes(root, seq):
    checked = 0
    for i in range(FRAMES):
        frame = seq[i]
        inst = np.fromfile(root / "training" / "velodyne_labels" / SEQ / f"{i:06d}.label", np.uint32) >> 16
        assert len(inst) == len(frame.points_c)
        objs = frame.objects_gt.of_class("Car")
        for b, track in zip(objs.box_3d, objs.track_id):
            pts = frame.points_c[inst == track + 1, :3].astype(np.float64)
            if len(pts) < 20:
                continue
            c, s = np.cos(b[6]), np.sin(b[6])
            R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
            local = (pts - b[:3]) @ R
            inside = np.all(np.abs(local) <= np.array([b[3], b[5], b[4]]) / 2 + 0.05, axis=1)
            assert inside.mean() >= 0.99, (i, track, inside.mean())
            checked += 1
    assert checked >= 3


def test_label_boxes_match_panoptic_masks(root, seq):
    for i in range(FRAMES):
        pan = read_png16(root / "training" / "panoptic" / SEQ / f"{i:06d}.png")
        objs = seq.gt_objects.in_frame(i)
        for cls, track, box in zip(objs.cls, objs.track_id, objs.box_2d):
            code = (26 if cls == "Car" else 24) * 1000 + track + 1
            v, u = np.nonzero(pan == code)
            assert len(u) > 0
            assert np.array_equal(box, [u.min(), v.min(), u.max(), v.max()])


def test_projected_3d_boxes_match_2d_boxes_of_unoccluded_cars(seq):
    objs = seq.gt_objects.of_class("Car")
    keep = (objs.occlusion == 0) & (objs.truncation == 0) & (objs.box_2d[:, 3] - objs.box_2d[:, 1] > 12)
    objs = objs.select(keep)
    assert len(objs) >= 2
    proj = project_boxes(objs.box_3d, seq.calib.P2, W, H)
    iou = np.diag(box_iou_2d(proj, objs.box_2d))
    assert iou.min() > 0.6 and np.median(iou) > 0.75, iou


def _textured(grey: np.ndarray, valid: np.ndarray, r: int, horizontal: bool = False) -> np.ndarray:
    """Pixels with image structure (along x only for stereo: the aperture problem)."""
    gy, gx = np.gradient(grey)
    mag = np.abs(gx) if horizontal else np.hypot(gx, gy)
    ok = valid & (mag > 6.0)
    ok[:r + 1], ok[-r - 1:], ok[:, :r + 12], ok[:, -r - 12:] = False, False, False, False
    return ok


def _bilinear(img: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    x0, y0 = np.clip(x0, 0, img.shape[1] - 2), np.clip(y0, 0, img.shape[0] - 2)
    return (img[y0, x0] * (1 - fx) * (1 - fy) + img[y0, x0 + 1] * fx * (1 - fy)
            + img[y0 + 1, x0] * (1 - fx) * fy + img[y0 + 1, x0 + 1] * fx * fy)


@pytest.fixture(scope="module")
def full_res(tmp_path_factory) -> Path:
    """One frame at KITTI resolution: stereo texture is judged where it is meant to be used."""
    out = tmp_path_factory.mktemp("sim") / "full"
    generate(out, "urban", frames=1, seed=5, progress=False, output__flow=False)
    return out


def _hidden_in_right(disp: np.ndarray) -> np.ndarray:
    """Left pixels whose surface is hidden in the right image by a nearer surface to their
    right (it lands on the same right pixel with a larger disparity)."""
    H_, W_ = disp.shape
    u = np.arange(W_)[None].repeat(H_, 0)
    target = u - disp
    hidden = np.zeros(disp.shape, bool)
    for k in range(1, int(disp.max()) + 2):
        other_d = np.pad(disp[:, k:], ((0, 0), (0, k)))
        other_t = np.pad(target[:, k:], ((0, 0), (0, k)), constant_values=-1e9)
        hidden |= (other_d > disp + 0.5) & (np.abs(other_t - target) < 1.5)
    return hidden


def test_stereo_ncc_peaks_at_ground_truth_disparity(full_res):
    seq = KittiTracking(full_res, "0000")
    frame = seq[0]
    left, right = _grey(frame.image_left), _grey(frame.image_right)
    h, w = left.shape
    disp = read_png16(full_res / "training" / "disparity" / "0000" / "000000.png") / 256.0
    # the disparity is f * b / Z: check it against the LiDAR depths first
    fb = seq.calib.P2[0, 0] * seq.calib.baseline
    X = frame.points_c[:, :3].astype(np.float64)
    X = X[X[:, 2] > 3]
    uv = X @ seq.calib.P2[:, :3].T + seq.calib.P2[:, 3]
    u, v = np.rint(uv[:, 0] / uv[:, 2]).astype(int), np.rint(uv[:, 1] / uv[:, 2]).astype(int)
    inside = (u >= 0) & (u < w) & (v >= 0) & (v < h)
    d_lidar, d_gt = fb / X[inside, 2], disp[v[inside], u[inside]]
    good = d_gt > 0
    assert np.median(np.abs(d_lidar[good] - d_gt[good]) / d_gt[good]) < 0.01  # LiDAR noise, pixel rounding
    # NCC of 11x11 patches around textured pixels, searched +-2 px around the ground truth
    r = 5
    edge = np.abs(np.gradient(disp)[1]) + np.abs(np.gradient(disp)[0])
    smooth = maximum_filter(edge, size=2 * r + 3) < 0.1  # no depth edge in the window
    visible = ~maximum_filter(_hidden_in_right(disp), size=2 * r + 3)
    ok = _textured(left, (disp > 1.0) & smooth & visible, r, horizontal=True)
    rng = np.random.default_rng(0)
    vs, us = np.nonzero(ok)
    pick = rng.choice(len(us), size=min(300, len(us)), replace=False)
    offsets = np.arange(-2.0, 2.01, 0.125)
    dy, dx = np.mgrid[-r:r + 1, -r:r + 1]
    errors = []
    for k in pick:
        u0, v0 = us[k], vs[k]
        patch = left[v0 - r:v0 + r + 1, u0 - r:u0 + r + 1].ravel()
        patch = patch - patch.mean()
        scores = []
        for off in offsets:
            x = u0 + dx - disp[v0, u0] + off
            cand = _bilinear(right, x.astype(float), (v0 + dy).astype(float)).ravel()
            cand = cand - cand.mean()
            scores.append(patch @ cand / (np.linalg.norm(patch) * np.linalg.norm(cand) + 1e-9))
        errors.append(offsets[int(np.argmax(scores))])
    errors = np.abs(np.array(errors))
    assert len(errors) >= 200
    # the rest are NCC ambiguities (periodic facades) and edges aliased at one ray per pixel
    assert np.mean(errors <= 0.5) >= 0.85, np.mean(errors <= 0.5)
    assert np.median(errors) <= 0.25


def test_flow_warp_reproduces_previous_frame(root, seq):
    for i in range(FRAMES - 1):
        img0, img1 = _grey(seq[i].image_left), _grey(seq[i + 1].image_left)
        raw = read_png16(root / "training" / "flow_noc" / SEQ / f"{i:06d}.png").astype(np.float64)
        valid = raw[..., 2] > 0
        fu, fv = (raw[..., 0] - 2**15) / 64.0, (raw[..., 1] - 2**15) / 64.0
        ok = _textured(img0, valid, 2)
        v, u = np.nonzero(ok)
        warped = _bilinear(img1, u + fu[v, u], v + fv[v, u])
        err = np.abs(warped - img0[v, u])
        assert len(err) > 500
        assert np.median(err) < 6.0, np.median(err)
        occ = read_png16(root / "training" / "flow_occ" / SEQ / f"{i:06d}.png")[..., 2] > 0
        assert (occ | ~valid).all()  # non-occluded pixels are a subset of the valid ones


def test_same_seed_gives_identical_files(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    for out in (a, b):
        generate(out, "urban", frames=2, seed=7, width=138, height=42, progress=False)
    files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    assert len(files) > 20
    for f in files:
        assert filecmp.cmp(a / f, b / f, shallow=False), f
    labels = read_labels(a / "training" / "label_02" / "0000.txt")
    assert len(labels) > 0
