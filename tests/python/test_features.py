"""ORB extraction and stereo matching (twistslam.features, the facade of twistslam._core.features).

Stereo accuracy is checked on a pair rendered by twistslam.sim.planes: fronto-parallel
textured planes ray-cast for KITTI sequence 0000's cameras 2 and 3, so every keypoint has a
known disparity.
"""

import threading

import numpy as np
import pytest

from twistslam import geometry as g
from twistslam import features as f
from twistslam.sim.planes import KITTI_P2, KITTI_P3, KITTI_SIZE, PlaneScene, texture

P2, P3, (W, H) = KITTI_P2, KITTI_P3, KITTI_SIZE
SCENE = None


def scene() -> PlaneScene:
    global SCENE
    if SCENE is None:
        SCENE = PlaneScene.default()
    return SCENE


def cast(cam, offset, u, v):
    return scene().cast(cam, offset, u, v)


def render(cam, right, seed):
    return scene().render(cam, right, seed)


@pytest.fixture(scope="module")
def camera():
    return g.StereoCamera.from_kitti(P2, P3, W, H)


@pytest.fixture(scope="module")
def pair(camera):
    left, ids_left = render(camera, False, 100)
    right, ids_right = render(camera, True, 101)
    return left, right, ids_left, ids_right


@pytest.fixture(scope="module")
def textured():
    return np.clip(np.rint(texture((H, W), 5)), 0, 255).astype(np.uint8)


def test_extract_orb_outputs(textured):
    r = f.extract_orb(textured)
    n = len(r["keypoints"])
    assert 1900 <= n <= 2000
    assert r["keypoints"].shape == (n, 2) and r["keypoints"].dtype == np.float64
    assert r["descriptors"].shape == (n, 32) and r["descriptors"].dtype == np.uint8
    levels = f.default_options()["num_levels"]
    assert r["octave"].dtype == np.int32 and set(np.unique(r["octave"])) == set(range(levels))
    assert np.all((r["angle"] >= 0) & (r["angle"] < 360))
    assert np.all(r["response"] > 0)
    np.testing.assert_allclose(r["size"], 31 * 1.2 ** r["octave"], rtol=1e-5)
    u, v = r["keypoints"].T
    assert u.min() >= 15 and u.max() <= W - 16 and v.min() >= 15 and v.max() <= H - 16
    # Deterministic.
    again = f.extract_orb(textured)
    np.testing.assert_array_equal(again["keypoints"], r["keypoints"])
    np.testing.assert_array_equal(again["descriptors"], r["descriptors"])


def test_options_dict_and_kwargs(textured):
    assert len(f.extract_orb(textured, {"num_features": 500})["keypoints"]) == 500
    assert len(f.extract_orb(textured, num_features=300)["keypoints"]) == 300
    # kwargs override the dict
    assert len(f.extract_orb(textured, {"num_features": 500}, num_features=200)["keypoints"]) == 200
    r = f.extract_orb(textured, num_levels=1, num_features=400)
    assert np.all(r["octave"] == 0)
    defaults = f.default_options()
    assert defaults["num_features"] == 2000 and defaults["max_depth"] == 80.0
    # one conversion path with the SLAM options (options_table): Python's error types, the
    # option's name and range in every message
    with pytest.raises(TypeError, match="unexpected keyword argument 'num_feature'"):
        f.extract_orb(textured, num_feature=10)
    with pytest.raises(ValueError, match="unknown key 'num_feature'"):
        f.extract_orb(textured, {"num_feature": 10})
    with pytest.raises(TypeError, match="max_depth"):  # a stereo option is not an ORB option
        f.extract_orb(textured, max_depth=10)
    with pytest.raises(ValueError, match=r"scale_factor = 1.0 is out of range \[1.001, 4\]"):
        f.extract_orb(textured, scale_factor=1.0)
    with pytest.raises(TypeError, match="num_features: expected an integer, got str"):
        f.extract_orb(textured, num_features="many")
    with pytest.raises(TypeError, match="num_levels: expected an integer, got float"):
        f.extract_orb(textured, num_levels=2.5)
    with pytest.raises(ValueError, match=r"num_features = 3000000000 is out of range \[0, 100000\]"):
        f.extract_orb(textured, num_features=3_000_000_000)
    with pytest.raises(ValueError, match="min_fast_threshold .* must not exceed fast_threshold"):
        f.extract_orb(textured, fast_threshold=10, min_fast_threshold=12)
    ranges = f.option_ranges()
    assert ranges["num_features"] == (0, 100000) and ranges["row_radius"] == (0.0, 64.0)
    assert set(ranges) == set(defaults)  # every option has a range


def test_rgb_equals_its_grey_and_views_are_handled(textured):
    grey = f.extract_orb(textured)
    rgb = f.extract_orb(np.repeat(textured[:, :, None], 3, axis=2))
    np.testing.assert_array_equal(rgb["keypoints"], grey["keypoints"])
    # A row-padded view (wrapped without a copy) and a non-contiguous one (copied) both work.
    crop = textured[:, 100:900]
    a = f.extract_orb(crop)
    b = f.extract_orb(np.ascontiguousarray(crop))
    np.testing.assert_array_equal(a["keypoints"], b["keypoints"])
    strided = textured[:, ::2]
    c = f.extract_orb(strided)
    d = f.extract_orb(np.ascontiguousarray(strided))
    np.testing.assert_array_equal(c["keypoints"], d["keypoints"])
    np.testing.assert_array_equal(c["descriptors"], d["descriptors"])


def test_mask_keeps_keypoints_out(textured):
    mask = np.ones((H, W), bool)
    mask[60:300, 300:750] = False
    mask[:, ::97] = False
    r = f.extract_orb(textured, mask=mask)
    px = np.rint(r["keypoints"]).astype(int)
    assert len(px) > 1800
    assert mask[px[:, 1], px[:, 0]].all()
    r8 = f.extract_orb(textured, mask=mask.astype(np.uint8) * 255)
    np.testing.assert_array_equal(r8["keypoints"], r["keypoints"])
    with pytest.raises(ValueError, match="mask"):
        f.extract_orb(textured, mask=mask[:100])
    with pytest.raises(ValueError, match="mask"):
        f.extract_orb(textured, mask=mask.astype(np.float32))


@pytest.mark.parametrize(
    "image, message",
    [
        (np.zeros((375, 1242), np.float32), r"image: expected uint8 \(H, W\) or \(H, W, 3\), got float32 \(375, 1242\)"),
        (np.zeros((375, 1242, 4), np.uint8), r"got uint8 \(375, 1242, 4\)"),
        (np.zeros((375, 1242), np.uint16), "uint16"),
        (np.zeros((375,), np.uint8), r"\(375,\)"),
        (np.zeros((0, 0), np.uint8), "empty"),
        (None, "None"),
    ],
)
def test_bad_images_raise_value_error(image, message):
    with pytest.raises(ValueError, match=message):
        f.extract_orb(image)


def test_blank_image_gives_no_keypoints(camera):
    blank = np.full((H, W), 128, np.uint8)
    r = f.extract_orb(blank)
    assert r["keypoints"].shape == (0, 2) and r["descriptors"].shape == (0, 32)
    s = f.match_stereo(blank, blank, camera)
    assert s["keypoints"].shape == (0, 2)
    assert s["u_right"].shape == (0,) and s["depth"].shape == (0,) and s["points_c"].shape == (0, 3)
    tiny = f.extract_orb(np.zeros((10, 10), np.uint8))
    assert tiny["keypoints"].shape == (0, 2)


def test_match_stereo_bad_input(camera, pair):
    left, right = pair[0], pair[1]
    with pytest.raises(ValueError, match="image_left: expected uint8"):
        f.match_stereo(left.astype(np.float32), right, camera)
    with pytest.raises(ValueError, match="image_right"):
        f.match_stereo(left, np.zeros((H, W, 4), np.uint8), camera)
    with pytest.raises(ValueError, match="differ in size"):
        f.match_stereo(left, right[:, :1000], camera)
    with pytest.raises(ValueError, match="camera is for 1242x375"):
        f.match_stereo(left[:, :1000], right[:, :1000], camera)
    with pytest.raises(ValueError, match="empty"):
        f.match_stereo(np.zeros((0, 0), np.uint8), np.zeros((0, 0), np.uint8), camera)
    with pytest.raises(ValueError, match="min_depth"):
        f.match_stereo(left, right, camera, min_depth=10, max_depth=5)
    with pytest.raises(ValueError, match=r"row_radius = 1e\+30 is out of range \[0, 64\]"):
        f.match_stereo(left, right, camera, row_radius=1e30)
    with pytest.raises(ValueError, match="max_depth = inf is out of range"):
        f.match_stereo(left, right, camera, {"max_depth": float("inf")})
    with pytest.raises(TypeError):
        f.match_stereo(left, right, "not a camera")


def test_match_stereo_recovers_rendered_disparities(camera, pair):
    left, right, ids_left, ids_right = pair
    r = f.match_stereo(left, right, camera)
    kp, matched = r["keypoints"], r["matched"]
    n = len(kp)
    assert n == 2000 and r["num_right_keypoints"] == 4000
    assert np.array_equal(matched, np.isfinite(r["depth"]))
    assert np.all(np.isnan(r["u_right"][~matched])) and np.all(np.isnan(r["points_c"][~matched]))

    # Ground truth: the plane point seen by each left keypoint, projected into the right image.
    ids, X = cast(camera, camera.t_left, kp[:, 0], kp[:, 1])
    u_right_true = camera.project(X, right=True)[:, 0]
    disparity_true = kp[:, 0] - u_right_true
    # Valid: the whole descriptor patch lies on one plane in both images.
    radius = np.ceil(16 * 1.2 ** r["octave"]).astype(int)
    valid = np.zeros(n, bool)
    for i in range(n):
        if ids[i] < 0:
            continue
        rad = radius[i]
        boxes = []
        for img_ids, (cu, cv) in ((ids_left, kp[i]), (ids_right, (u_right_true[i], kp[i, 1]))):
            u0, v0 = int(np.floor(cu - rad)), int(np.floor(cv - rad))
            u1, v1 = int(np.ceil(cu + rad)), int(np.ceil(cv + rad))
            if u0 < 0 or v0 < 0 or u1 >= W or v1 >= H:
                boxes.append(False)
            else:
                boxes.append(bool(np.all(img_ids[v0:v1 + 1, u0:u1 + 1] == ids[i])))
        valid[i] = all(boxes)
    assert valid.sum() > 1000
    rate = matched[valid].mean()
    err = np.abs(kp[:, 0] - r["u_right"] - disparity_true)[valid & matched]
    assert rate > 0.7, rate
    assert np.median(err) < 0.1, np.median(err)
    assert np.mean(err < 0.5) >= 0.95
    # No gross outlier anywhere (boundary keypoints included).
    all_err = np.abs(kp[:, 0] - r["u_right"] - disparity_true)[matched & (ids >= 0)]
    assert np.mean(all_err > 1.0) < 0.01

    # depth = fx b / disparity along the left axis; points_c = triangulation in frame c.
    m = matched
    np.testing.assert_allclose(r["depth"][m], camera.fx * camera.baseline / (kp[m, 0] - r["u_right"][m]),
                               rtol=1e-5)
    np.testing.assert_allclose(r["points_c"][m, 2] + camera.t_left[2], r["depth"][m], rtol=1e-5)
    np.testing.assert_allclose(camera.project(r["points_c"][m]), kp[m], atol=1e-4)
    depth_true = X[:, 2] + camera.t_left[2]
    assert np.median(np.abs(r["depth"] - depth_true)[valid & m] / depth_true[valid & m]) < 0.01


def test_match_stereo_mask_and_rgb(camera, pair):
    left, right = pair[0], pair[1]
    mask = np.ones((H, W), bool)
    mask[:, :600] = False
    r = f.match_stereo(np.repeat(left[:, :, None], 3, 2), np.repeat(right[:, :, None], 3, 2),
                       camera, mask=mask, num_features=800)
    assert len(r["keypoints"]) == 800
    assert np.all(r["keypoints"][:, 0] >= 599.5)
    assert r["matched"].mean() > 0.5


def test_hamming_distance_matches_bit_count():
    rng = np.random.default_rng(3)
    a = rng.integers(0, 256, (20, 32), dtype=np.uint8)
    b = rng.integers(0, 256, (7, 32), dtype=np.uint8)
    ref = np.unpackbits(a[:, None, :] ^ b[None, :, :], axis=2).sum(axis=2)
    np.testing.assert_array_equal(f.hamming_distance(a, b), ref)
    with pytest.raises(ValueError, match="a: expected uint8"):
        f.hamming_distance(a[:, :16], b)


def test_parallel_calls_agree(textured):
    """The GIL is released: concurrent calls from threads run and agree with a serial one."""
    serial = f.extract_orb(textured)
    results = [None] * 4

    def work(i):
        results[i] = f.extract_orb(textured)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        np.testing.assert_array_equal(r["keypoints"], serial["keypoints"])
