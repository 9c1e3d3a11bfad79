"""Visual object tracks against ground truth: offset / alignment gauge, coverage, ghosts."""


import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twistslam.eval.object_tracks import (
    MAX_OCCLUSION, MAX_RANGE_M, MAX_TRUNCATION, MIN_BOX_HEIGHT_PX, MIN_VISIBLE_FRAMES, GtTrack, SequenceGroundTruth,
    estimate_offset, evaluate_object_tracks, evaluated_cars, load_ground_truth, selected_frames,
)
from twistslam.objects.result import TrackedObject

FRAMES = 40
NOISE_M, NOISE_DEG = 0.01, 0.1
TALL_PX = 80.0  # labelled box height of the synthetic cars: well above the minimum


def pose(yaw_deg=0.0, t=(0, 0, 0), rotvec_deg=None):
    T = np.eye(4)
    rv = np.deg2rad(rotvec_deg) if rotvec_deg is not None else [0, np.deg2rad(yaw_deg), 0]
    T[:3, :3] = Rotation.from_rotvec(rv).as_matrix()
    T[:3, 3] = t
    return T


def turning_track(x0, z0, speed, yaw_rate_deg, n=FRAMES):
    """Poses of a car driving along its x axis (camera frame: y down) while turning about y."""
    poses, T = [], pose(-90.0, (x0, 0.8, z0))  # x along the camera's forward z
    for _ in range(n):
        poses.append(T.copy())
        T = T @ pose(yaw_rate_deg, (speed, 0, 0))
    return np.stack(poses)


def gt_track(tid, moving, T_w_o, labelled):
    """A car of fixed size whose labelled boxes are ``TALL_PX`` high (NaN where unlabelled)."""
    heights = np.where(labelled, TALL_PX, np.nan)
    return GtTrack(tid, "Car", moving, np.arange(FRAMES), T_w_o, np.array([4.0, 1.7, 1.5]),
                   labelled, heights)


def synthetic_gt():
    T_w_c = np.stack([pose(0.3 * f, (0, 0, 1.0 * f)) for f in range(FRAMES)])
    frames = np.arange(FRAMES)
    everywhere = np.ones(FRAMES, bool)
    tracks = {
        1: gt_track(1, True, turning_track(2.0, 10.0, 1.3, 1.5), everywhere),
        2: gt_track(2, True, turning_track(-3.0, 20.0, 1.1, -1.0), everywhere),
        # parked: not evaluated, but an estimate on it is no ghost
        3: gt_track(3, False, np.repeat(pose(-90.0, (-6, 0.8, 15))[None], FRAMES, 0), everywhere),
        # seen in too few frames to be evaluated
        4: gt_track(4, True, turning_track(6.0, 12.0, 1.0, 0.0), frames < 10),
    }
    return SequenceGroundTruth(T_w_c=T_w_c, tracks=tracks)


def tracked(track_id, frames, T_w_o):
    n = len(frames)
    return TrackedObject(track_id=track_id, cls="Car", state="confirmed", link="planar",
                         frames=np.asarray(frames), T_w_o=T_w_o, size=np.ones(3),
                         velocity_kmh=np.zeros(n), detected=np.ones(n, bool),
                         reported=np.ones(n, bool), score=np.ones(n), mean_score=1.0)


def noisy(T, rng, noise_m=NOISE_M, noise_deg=NOISE_DEG):
    out = T.copy()
    for k in range(len(T)):
        out[k] = out[k] @ pose(rotvec_deg=rng.normal(0, noise_deg, 3), t=rng.normal(0, noise_m, 3))
    return out


@pytest.fixture
def world():
    """GT, a global transform A (drifting SLAM world) and the estimated camera A T_w_c."""
    gt = synthetic_gt()
    A = pose(rotvec_deg=(2.0, 25.0, -3.0), t=(5.0, -1.0, 3.0))
    return gt, A, A @ gt.T_w_c


def estimate_of(gt, A, tid, offset, rng, frames=None):
    track = gt.tracks[tid]
    keep = np.isin(track.frames, frames) if frames is not None else np.ones(len(track.frames), bool)
    return tracked(tid * 10, track.frames[keep], noisy(A @ track.T_w_o[keep] @ offset, rng))


OFFSET = pose(rotvec_deg=(0, 40.0, 0), t=(0.4, 0.2, -0.3))  # identity-at-centroid look-alike


def test_selection_keeps_moving_cars_seen_often_enough():
    gt = synthetic_gt()
    assert sorted(evaluated_cars(gt)) == [1, 2]
    assert sorted(evaluated_cars(gt, max_range_m=15.0)) == []  # car 2 too far, car 1 leaves


def test_offset_and_global_transform_leave_noise_level_errors(world):
    gt, A, cams = world
    rng = np.random.default_rng(0)
    est = [estimate_of(gt, A, tid, OFFSET, rng) for tid in (1, 2)]
    ev = evaluate_object_tracks(est, cams, gt)
    assert [c.gt_id for c in ev.cars] == [1, 2]
    for car in ev.cars:
        assert car.coverage == 1.0 and car.n_compared == FRAMES and car.est_ids == [car.gt_id * 10]
        assert car.rpe_t < 0.05 and car.rpe_r < 0.3 and car.ate_aligned < 0.03
        np.testing.assert_allclose(car.offset, OFFSET, atol=0.02)
    assert ev.n_tracked == 2 and ev.n_ghosts == 0
    assert "mean" in ev.format_table()


def test_wrong_offset_changes_only_canonical_metrics(world):
    gt, _, _ = world
    A = np.eye(4)  # canonical metrics need the SLAM world to be the ground-truth world
    right = evaluate_object_tracks([estimate_of(gt, A, 1, np.eye(4), np.random.default_rng(1))],
                                   gt.T_w_c, gt)
    wrong = evaluate_object_tracks([estimate_of(gt, A, 1, OFFSET, np.random.default_rng(1))],
                                   gt.T_w_c, gt)
    r, w = right.cars[0], wrong.cars[0]
    assert r.rpe_t == pytest.approx(w.rpe_t, rel=0.1) and r.ate_aligned == pytest.approx(w.ate_aligned, rel=0.1)
    assert r.rpe_r == pytest.approx(w.rpe_r, rel=0.1)
    assert r.ate_canonical < 0.03 < 0.3 < w.ate_canonical
    assert w.rpe_t_canonical > 3 * r.rpe_t_canonical


def test_dropped_frames_lower_coverage_and_split_tracks_share_it(world):
    gt, A, cams = world
    rng = np.random.default_rng(2)
    sparse = estimate_of(gt, A, 1, OFFSET, rng, frames=np.arange(0, FRAMES, 2))
    first = estimate_of(gt, A, 2, OFFSET, rng, frames=np.arange(0, 15))
    second = estimate_of(gt, A, 2, OFFSET, rng, frames=np.arange(15, FRAMES))
    second.track_id = 99
    ev = evaluate_object_tracks([sparse, first, second], cams, gt)
    car1, car2 = ev.cars
    assert car1.coverage == pytest.approx(0.5) and car1.n_compared == FRAMES // 2
    assert car1.ate_aligned < 0.03  # a gap is a longer RPE step, not an error
    assert car2.coverage == 1.0 and car2.est_ids == [99, 20]  # main (most hits) first
    assert car2.n_compared == FRAMES - 15
    assert ev.n_tracked == 1


def test_random_tracks_are_ghosts_unless_short_or_on_a_parked_car(world):
    gt, A, cams = world
    rng = np.random.default_rng(3)
    far = np.stack([A @ pose(t=(rng.uniform(20, 30), 0, f + 10.0)) for f in range(10)])
    short = far[:GHOST_SHORT]
    parked = estimate_of(gt, A, 3, OFFSET, rng, frames=np.arange(5, 25))
    est = [tracked(7, np.arange(10), far), tracked(8, np.arange(GHOST_SHORT), short), parked]
    ev = evaluate_object_tracks(est, cams, gt)
    assert ev.ghost_ids == [7]
    assert all(c.coverage == 0 and np.isnan(c.rpe_t) for c in ev.cars)


GHOST_SHORT = 4  # one frame short of a ghost


def test_lost_camera_frames_are_skipped(world):
    gt, A, cams = world
    cams = cams.copy()
    cams[10:12] = np.nan
    ev = evaluate_object_tracks([estimate_of(gt, A, 1, OFFSET, np.random.default_rng(4))], cams, gt)
    assert ev.cars[0].n_compared == FRAMES - 2 and ev.cars[0].coverage == pytest.approx(38 / 40)


def test_offset_mean_ignores_an_outlier():
    T_gt = turning_track(0, 10, 1.0, 2.0, n=20)
    T_est = T_gt @ OFFSET
    T_est[5] = T_est[5] @ pose(rotvec_deg=(0, 60, 0), t=(3, 0, 0))
    np.testing.assert_allclose(estimate_offset(T_gt, T_est), OFFSET, atol=1e-9)


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    from twistslam.sim import generate

    root = tmp_path_factory.mktemp("object_tracks_sim")
    generate(root, "urban", frames=12, seed=0, width=414, height=125, progress=False,
             lidar__enabled=False, overwrite=True)
    return root


def test_noisy_ground_truth_of_a_simulated_sequence(sim):
    gt = load_ground_truth(sim, "0000")
    rng = np.random.default_rng(5)
    est = []
    for tid, track in gt.tracks.items():
        seen = track.labelled
        est.append(tracked(tid, track.frames[seen], noisy(track.T_w_o[seen] @ OFFSET, rng)))
    ev = evaluate_object_tracks(est, gt.T_w_c, gt, min_frames=10)
    assert len(ev.cars) >= 1 and ev.n_ghosts == 0
    assert ev.n_tracked == len(ev.cars) and ev.ate_aligned < 0.03


def test_a_waiting_moving_car_has_ate_but_no_rpe_per_metre(world):
    gt, A, cams = world
    car = gt.tracks[1]
    car.T_w_o = np.repeat(car.T_w_o[:1], FRAMES, 0)  # "moving" in the scene, waiting here
    ev = evaluate_object_tracks([estimate_of(gt, A, 1, OFFSET, np.random.default_rng(6))], cams, gt)
    row = ev.cars[0]
    assert row.path_m < 1e-9 and np.isnan(row.rpe_t) and np.isnan(row.rpe_r)
    assert row.coverage == 1.0 and row.ate_aligned < 0.03


def test_frames_with_boxes_under_the_minimum_height_are_not_evaluated(world):
    gt, A, cams = world
    car = gt.tracks[1]
    car.labelled[[3, 17]] = False  # two frames out of the image as well
    rng = np.random.default_rng(7)
    car.box_height_px = np.where(car.labelled, rng.uniform(5.0, 60.0, FRAMES), np.nan)
    # the old rule, computed from the labels and the box centre's distance to the camera
    near = np.linalg.norm(car.T_w_o[:, :3, 3] - gt.T_w_c[car.frames, :3, 3], axis=1) <= MAX_RANGE_M
    old = car.frames[car.labelled & near]
    small = car.frames[car.labelled & (car.box_height_px < MIN_BOX_HEIGHT_PX)]
    assert len(small) and len(old) - len(np.intersect1d(old, small)) >= MIN_VISIBLE_FRAMES

    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c, min_box_height_px=0), old)
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c), np.setdiff1d(old, small))
    np.testing.assert_array_equal(evaluated_cars(gt)[1], np.setdiff1d(old, small))
    np.testing.assert_array_equal(evaluated_cars(gt, min_box_height_px=0)[1], old)

    # an estimate only where the box is tall enough: fully covered under the rule, not without
    tall = np.setdiff1d(old, small)
    est = [estimate_of(gt, A, 1, OFFSET, rng, frames=tall)]
    row = evaluate_object_tracks(est, cams, gt).cars[0]
    assert row.frames == len(tall) and row.coverage == 1.0
    row_old = evaluate_object_tracks(est, cams, gt, min_box_height_px=0).cars[0]
    assert row_old.frames == len(old) and row_old.coverage == pytest.approx(len(tall) / len(old))


def test_a_car_hidden_all_along_is_not_evaluated_and_a_track_on_it_is_no_ghost(world):
    gt, A, cams = world
    hidden = gt.tracks[2]
    hidden.box_height_px = np.full(FRAMES, 0.5 * MIN_BOX_HEIGHT_PX)
    assert sorted(evaluated_cars(gt)) == [1]
    assert sorted(evaluated_cars(gt, min_box_height_px=0)) == [1, 2]
    ev = evaluate_object_tracks([estimate_of(gt, A, 2, OFFSET, np.random.default_rng(8))], cams, gt)
    assert [c.gt_id for c in ev.cars] == [1] and ev.ghost_ids == []


def test_frames_hidden_beyond_the_moderate_occlusion_level_are_not_evaluated(world):
    gt, A, cams = world
    assert MAX_OCCLUSION == 1  # KITTI moderate: "partly occluded" at most
    car = gt.tracks[1]
    rng = np.random.default_rng(11)
    car.occlusion = rng.integers(0, 3, FRAMES)
    hidden = car.frames[car.occlusion == 2]
    seen = car.frames[car.occlusion <= 1]
    assert len(hidden) and len(seen) >= MIN_VISIBLE_FRAMES
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c), seen)
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c, max_occlusion=2), car.frames)
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c, max_occlusion=0),
                                  car.frames[car.occlusion == 0])
    # an estimate only where the car is seen: fully covered under the rule, not without it
    est = [estimate_of(gt, A, 1, OFFSET, rng, frames=seen)]
    row = evaluate_object_tracks(est, cams, gt).cars[0]
    assert row.frames == len(seen) and row.coverage == 1.0
    row_all = evaluate_object_tracks(est, cams, gt, max_occlusion=2).cars[0]
    assert row_all.frames == FRAMES and row_all.coverage == pytest.approx(len(seen) / FRAMES)
    # hidden in all but a few frames: not evaluated at all
    car.occlusion = np.where(car.frames < MIN_VISIBLE_FRAMES - 1, 1, 2)
    assert 1 not in evaluated_cars(gt) and 1 in evaluated_cars(gt, max_occlusion=2)


def test_frames_mostly_outside_the_image_are_not_evaluated(world):
    gt, A, cams = world
    assert MAX_TRUNCATION == 1  # at least half of the projected box inside the image
    car = gt.tracks[1]
    rng = np.random.default_rng(12)
    car.truncation = rng.integers(0, 3, FRAMES)
    inside = car.frames[car.truncation <= 1]
    assert len(inside) < FRAMES and len(inside) >= MIN_VISIBLE_FRAMES
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c), inside)
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c, max_truncation=2), car.frames)
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c, max_truncation=0),
                                  car.frames[car.truncation == 0])
    # the two rules combine: a frame must pass both
    car.occlusion = rng.integers(0, 3, FRAMES)
    both = car.frames[(car.truncation <= 1) & (car.occlusion <= 1)]
    np.testing.assert_array_equal(selected_frames(car, gt.T_w_c), both)
    est = [estimate_of(gt, A, 1, OFFSET, rng, frames=both)]
    row = evaluate_object_tracks(est, cams, gt, max_occlusion=2, max_truncation=2).cars[0]
    assert row.frames == FRAMES and row.coverage == pytest.approx(len(both) / FRAMES)
    # beside the camera in all but a few frames: not evaluated
    car.occlusion = None
    car.truncation = np.where(car.frames < MIN_VISIBLE_FRAMES - 1, 1, 2)
    assert 1 not in evaluated_cars(gt) and 1 in evaluated_cars(gt, max_truncation=2)


def parse_label_heights(path):
    """``{(track id, frame): bottom - top}`` of a KITTI tracking label file, read directly."""
    heights = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        tok = line.split()
        if tok:  # frame track_id type truncated occluded alpha left top right bottom ...
            heights[(int(tok[1]), int(tok[0]))] = float(tok[9]) - float(tok[7])
    return heights


def parse_label_levels(path, column):
    """``{(track id, frame): level}`` of a KITTI tracking label file's column (3: truncation,
    4: occlusion), read directly."""
    return {(int(tok[1]), int(tok[0])): int(tok[column])
            for tok in (line.split() for line in path.read_text(encoding="utf-8").splitlines()) if tok}


def test_ground_truth_reads_the_box_heights_of_label_02(sim):
    gt = load_ground_truth(sim, "0000")
    heights = parse_label_heights(sim / "training" / "label_02" / "0000.txt")
    occlusions = parse_label_levels(sim / "training" / "label_02" / "0000.txt", 4)
    truncations = parse_label_levels(sim / "training" / "label_02" / "0000.txt", 3)
    assert set(occlusions.values()) <= {0, 1, 2} and set(truncations.values()) <= {0, 1, 2}
    n_labelled = 0
    for tid, track in gt.tracks.items():
        expected = np.array([heights.get((tid, int(f)), np.nan) for f in track.frames])
        np.testing.assert_array_equal(track.box_height_px, expected)
        np.testing.assert_array_equal(track.labelled, np.isfinite(expected))
        occlusion = np.array([occlusions.get((tid, int(f)), -1) for f in track.frames])
        np.testing.assert_array_equal(track.occlusion, occlusion)
        truncation = np.array([truncations.get((tid, int(f)), -1) for f in track.frames])
        np.testing.assert_array_equal(track.truncation, truncation)
        n_labelled += track.labelled.sum()
    assert n_labelled > 0
    # the simulator labels cars seen through a gap: the rule must drop some labelled frames
    small = [(tid, f) for (tid, f), h in heights.items()
             if tid in gt.tracks and gt.tracks[tid].cls == "Car" and h < MIN_BOX_HEIGHT_PX]
    assert small
    for tid, track in gt.tracks.items():
        kept = set(selected_frames(track, gt.T_w_c).tolist())
        assert not kept & {f for t, f in small if t == tid}
        assert kept <= set(selected_frames(track, gt.T_w_c, min_box_height_px=0).tolist())


def queued_gt(gap_m=0.8):
    """Two moving cars in a queue along the camera's z, ``gap_m`` between bumper and bumper
    (4 m long: a point in the gap lies inside both boxes grown by ``HIT_MARGIN_M``)."""
    T_w_c = np.stack([pose(t=(0, 0, 0.5 * f)) for f in range(FRAMES)])
    everywhere = np.ones(FRAMES, bool)
    lead = np.stack([pose(-90.0, (0, 0.8, 12.0 + 0.5 * f)) for f in range(FRAMES)])
    behind = lead.copy()
    behind[:, 2, 3] -= 4.0 + gap_m
    return SequenceGroundTruth(T_w_c=T_w_c, tracks={1: gt_track(1, True, lead, everywhere),
                                                    2: gt_track(2, True, behind, everywhere)})


def test_one_track_between_two_queued_cars_covers_one_of_them():
    gt = queued_gt()
    lead = gt.tracks[1].T_w_o
    # the lead car's track sits on its rear bumper: inside the car behind's grown box too
    on_rear = lead @ pose(t=(-1.9, 0, 0))
    ev = evaluate_object_tracks([tracked(5, np.arange(FRAMES), on_rear)], gt.T_w_c, gt)
    rows = {c.gt_id: c for c in ev.cars}
    assert rows[1].coverage == 1.0 and rows[1].est_ids == [5]
    assert rows[2].coverage == 0.0 and rows[2].est_ids == [] and np.isnan(rows[2].ate_aligned)
    assert ev.n_tracked == 1 and ev.n_ghosts == 0


def test_two_tracks_on_queued_cars_each_stand_for_their_own():
    gt = queued_gt()
    rng = np.random.default_rng(7)
    # both tracks biased towards the gap (rear / front faces): inside both grown boxes
    lead = tracked(5, np.arange(FRAMES), noisy(gt.tracks[1].T_w_o @ pose(t=(-1.9, 0, 0)), rng))
    behind = tracked(6, np.arange(FRAMES), noisy(gt.tracks[2].T_w_o @ pose(t=(1.9, 0, 0)), rng))
    ev = evaluate_object_tracks([behind, lead], gt.T_w_c, gt)
    rows = {c.gt_id: c for c in ev.cars}
    assert rows[1].est_ids == [5] and rows[2].est_ids == [6]
    assert ev.n_tracked == 2


def test_a_matched_track_keeps_its_car_while_inside_the_gate():
    from twistslam.eval.track_assignment import assign_tracks

    half = np.array([2.0, 0.85, 0.75])
    box = {f: [(1, pose(), half)] for f in range(3)}
    # track 5 on the car from frame 0; track 6 appears nearer its centre in frame 1
    tracks = {0: [(5, np.array([1.8, 0, 0]))],
              1: [(5, np.array([1.8, 0, 0])), (6, np.array([0.1, 0, 0]))],
              2: [(5, np.array([4.0, 0, 0])), (6, np.array([0.1, 0, 0]))]}
    pairs = assign_tracks(box, tracks, margin_m=1.0)
    assert pairs[0] == {5: 1} and pairs[1] == {5: 1}  # no switch to the closer newcomer
    assert pairs[2] == {6: 1}  # track 5 left the gate (4.0 > 2.0 + 1.0): the car goes to 6
