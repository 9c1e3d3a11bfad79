"""Optical-flow stage: file formats, DIS accuracy on known shifts and on the simulator's
exact flow, the source factory and its errors."""

import struct
import warnings

import numpy as np
import pytest

from twistslam import _core
from twistslam.datasets import Frame, KittiTracking
from twistslam.perception import (DisFlow, FileFlow, TimedStage, flow_source, read_flo, read_kitti_flow, write_flo,
                                  write_kitti_flow)
from twistslam.perception.flow import object_region
from twistslam.perception.run_stages import Perception
from twistslam.sim.generate import generate
from twistslam.datasets.png16 import write_png16


def frame(index, image):
    return Frame(index=index, timestamp=0.1 * index, image_left=image, image_right=None, points_c=None,
                 points_velo=None, calib=None)


def textured(h, w, seed=0, blur_px=2.0):
    """Random texture blurred with a Gaussian (via FFT) so gradients exist at every DIS scale."""
    noise = np.random.default_rng(seed).random((h, w))
    fy, fx = np.fft.fftfreq(h)[:, None], np.fft.fftfreq(w)[None, :]
    smooth = np.fft.ifft2(np.fft.fft2(noise) * np.exp(-2 * (np.pi * blur_px) ** 2 * (fx**2 + fy**2))).real
    return smooth


def shift(image, du, dv):
    """current(x, y) = image(x - du, y - dv) by a Fourier phase shift (exact for a periodic image)."""
    h, w = image.shape
    fy, fx = np.fft.fftfreq(h)[:, None], np.fft.fftfreq(w)[None, :]
    return np.fft.ifft2(np.fft.fft2(image) * np.exp(-2j * np.pi * (fx * du + fy * dv))).real


def to_u8(image, lo, hi):
    return np.clip(np.rint((image - lo) / (hi - lo) * 255), 0, 255).astype(np.uint8)


def test_kitti_flow_png_known_values_and_round_trip(tmp_path):
    raw = np.zeros((2, 3, 3), np.uint16)
    raw[0, 0] = (2**15 + 64, 2**15 - 32, 1)  # u = 1 px, v = -0.5 px, valid
    raw[0, 1] = (0, 65535, 1)  # extremes: -512 px and +511.98 px
    raw[1, 2] = (2**15 + 640, 2**15, 0)  # invalid: no value whatever is stored
    write_png16(tmp_path / "k.png", raw)
    flow = read_kitti_flow(tmp_path / "k.png")
    assert flow.shape == (2, 3, 2) and flow.dtype == np.float32
    np.testing.assert_array_equal(flow[0, 0], [1.0, -0.5])
    np.testing.assert_allclose(flow[0, 1], [-512.0, 32767 / 64], atol=1e-6)
    assert np.isnan(flow[1, 2]).all() and np.isnan(flow[1, 0]).all()
    rng = np.random.default_rng(1)
    fl = rng.uniform(-300, 300, (5, 7, 2)).astype(np.float32)
    fl[2, 3] = np.nan
    write_kitti_flow(tmp_path / "r.png", fl)
    back = read_kitti_flow(tmp_path / "r.png")
    np.testing.assert_array_equal(np.isnan(back), np.isnan(fl))
    assert np.nanmax(np.abs(back - fl)) <= 0.5 / 64 + 1e-6  # stored in 1/64 px steps


def test_flo_round_trip_and_known_layout(tmp_path):
    fl = np.arange(24, dtype=np.float32).reshape(3, 4, 2) - 10.25
    fl[1, 1] = np.nan
    write_flo(tmp_path / "a.flo", fl)
    data = (tmp_path / "a.flo").read_bytes()
    assert data[:4] == b"PIEH" and struct.unpack("<ii", data[4:12]) == (4, 3) and len(data) == 12 + 3 * 4 * 8
    assert struct.unpack("<ff", data[12:20]) == (-10.25, -9.25)  # (u, v) of pixel (0, 0) first
    back = read_flo(tmp_path / "a.flo")
    np.testing.assert_array_equal(back, fl)  # NaN in the same places, values exact


def test_bad_flow_files_give_clear_errors(tmp_path):
    write_flo(tmp_path / "ok.flo", np.zeros((3, 4, 2), np.float32))
    data = (tmp_path / "ok.flo").read_bytes()
    (tmp_path / "magic.flo").write_bytes(b"XXXX" + data[4:])
    with pytest.raises(ValueError, match=r"magic.flo: not a .flo file"):
        read_flo(tmp_path / "magic.flo")
    (tmp_path / "short.flo").write_bytes(data[:-5])
    with pytest.raises(ValueError, match=r"short.flo: truncated .flo file: 103 bytes, 4x3 needs 108"):
        read_flo(tmp_path / "short.flo")
    (tmp_path / "head.flo").write_bytes(data[:7])
    with pytest.raises(ValueError, match=r"head.flo: truncated .flo file \(7 bytes"):
        read_flo(tmp_path / "head.flo")
    (tmp_path / "size.flo").write_bytes(data[:4] + struct.pack("<ii", -4, 3) + data[12:])
    with pytest.raises(ValueError, match=r"size.flo: implausible .flo size -4x3"):
        read_flo(tmp_path / "size.flo")
    write_png16(tmp_path / "grey.png", np.zeros((3, 4), np.uint16))
    with pytest.raises(ValueError, match=r"grey.png: a KITTI flow PNG is 16-bit RGB"):
        read_kitti_flow(tmp_path / "grey.png")
    (tmp_path / "text.png").write_text("not a png")
    with pytest.raises(ValueError, match=r"text.png: not a PNG file"):
        read_kitti_flow(tmp_path / "text.png")
    # a flow file of another image size than the frames it describes
    (tmp_path / "seq").mkdir()
    write_flo(tmp_path / "seq" / "000000.flo", np.zeros((3, 4, 2), np.float32))
    img = np.zeros((5, 6, 3), np.uint8)
    with pytest.raises(ValueError, match=r"000000.flo: flow must be \(5, 6, 2\)"):
        FileFlow(tmp_path / "seq")(frame(0, img), frame(1, img))
    with pytest.raises(FileNotFoundError, match=r"neither 000001.png nor 000001.flo"):
        FileFlow(tmp_path / "seq")(frame(1, img), frame(2, img))


@pytest.mark.parametrize("du, dv", [(3.4, -1.7), (-0.6, 2.25)])
def test_dis_recovers_a_synthetic_shift(du, dv):
    base = textured(120, 256, seed=3)
    lo, hi = base.min(), base.max()
    prev, cur = to_u8(base, lo, hi), to_u8(shift(base, du, dv), lo, hi)
    rgb = np.repeat(prev[..., None], 3, axis=2), np.repeat(cur[..., None], 3, axis=2)
    flow = DisFlow()(frame(0, rgb[0]), frame(1, rgb[1]))
    assert flow.shape == (120, 256, 2) and flow.dtype == np.float32
    inner = flow[16:-16, 16:-16]  # borders: the shifted content wraps around
    assert abs(np.median(inner[..., 0]) - du) < 0.2 and abs(np.median(inner[..., 1]) - dv) < 0.2


def test_object_region_boxes_every_instance_with_a_margin():
    a, b = np.zeros((100, 200), np.int32), np.zeros((100, 200), np.int32)
    a[40:50, 60:70] = 26001
    b[45:60, 150:160] = 26002
    assert object_region((a, b), margin_px=5) == (55, 35, 165, 65)
    assert object_region((None, b), margin_px=0) == (150, 45, 160, 60)
    assert object_region((a, b), margin_px=80) == (0, 0, 200, 100)  # clipped to the image
    assert object_region((np.zeros_like(a), None)) is None  # no instance: no box
    assert object_region((None, None)) is None


def test_dis_on_a_region_is_nan_outside_and_dis_of_the_crop_inside():
    base = textured(120, 256, seed=5)
    lo, hi = base.min(), base.max()
    prev, cur = to_u8(base, lo, hi), to_u8(shift(base, 2.5, -1.0), lo, hi)
    rgb = np.repeat(prev[..., None], 3, axis=2), np.repeat(cur[..., None], 3, axis=2)
    region = (40, 20, 200, 100)
    flow = DisFlow()(frame(0, rgb[0]), frame(1, rgb[1]), region=region)
    assert flow.shape == (120, 256, 2) and flow.dtype == np.float32
    inside = np.zeros((120, 256), bool)
    inside[20:100, 40:200] = True
    assert np.isnan(flow[~inside]).all() and np.isfinite(flow[inside]).all()
    crop = _core.perception.dis_flow(np.ascontiguousarray(rgb[0][20:100, 40:200]),
                                     np.ascontiguousarray(rgb[1][20:100, 40:200]))
    np.testing.assert_array_equal(flow[20:100, 40:200], crop)
    inner = flow[36:84, 56:184]
    assert abs(np.median(inner[..., 0]) - 2.5) < 0.2 and abs(np.median(inner[..., 1]) + 1.0) < 0.2
    for bad in ((0, 0, 0, 10), (10, 10, 300, 20), (-1, 0, 5, 5)):
        with pytest.raises(ValueError, match="is not a non-empty box inside the 256x120 image"):
            DisFlow()(frame(0, rgb[0]), frame(1, rgb[1]), region=bad)


def test_the_instances_go_only_to_sources_that_take_them():
    img = np.zeros((100, 120, 3), np.uint8)
    previous_ids, current_ids = np.zeros((100, 120), np.int32), np.zeros((100, 120), np.int32)
    current_ids[94:96, 55:57] = 26001  # a 2 px instance near the bottom edge
    calls = []

    def user_flow(previous, current):  # a user's two-argument stage
        calls.append((previous.index, current.index))
        return np.ones((100, 120, 2), np.float32)

    out = Perception(flow=user_flow, flow_name="mine").optical_flow(
        frame(0, img), frame(1, img), instances=(previous_ids, current_ids))
    assert calls == [(0, 1)] and (out == 1).all()
    # DIS: the instance's box, 5 px around it, widened to 64 px (DIS refuses images under its
    # patch size) inside the image
    dis = Perception(flow=DisFlow(region_margin_px=5), flow_name="dis").optical_flow(
        frame(0, img), frame(1, img), instances=(previous_ids, current_ids))
    computed = np.isfinite(dis[..., 0])
    assert computed[36:100, 24:88].all() and computed.sum() == 64 * 64
    whole = DisFlow(object_region=False)(frame(0, img), frame(1, img),
                                         instances=(previous_ids, current_ids))
    no_instance = DisFlow()(frame(0, img), frame(1, img), instances=(previous_ids, None))
    assert np.isfinite(whole).all() and np.isfinite(no_instance).all()
    small = DisFlow()(frame(0, img[:20, :30]), frame(1, img[:20, :30]), region=(0, 0, 5, 5))
    assert np.isfinite(small).all()  # an image under 64 px: the whole of it
    with pytest.raises(ValueError, match="region_margin_px = -1"):
        DisFlow(region_margin_px=-1)


def test_dis_rejects_bad_images_and_options():
    img = np.zeros((20, 30), np.uint8)
    with pytest.raises(ValueError, match=r"previous: expected uint8 .* float64 \(20, 30\)"):
        _core.perception.dis_flow(img.astype(float), img)
    with pytest.raises(ValueError, match=r"current: image size \(21, 30\) differs from previous \(20, 30\)"):
        _core.perception.dis_flow(img, np.zeros((21, 30), np.uint8))
    with pytest.raises(ValueError, match="DIS preset 'slow'"):
        _core.perception.dis_flow(img, img, preset="slow")
    with pytest.raises(ValueError, match="patch_size_px"):
        _core.perception.dis_flow(img, img, patch_size_px=1)
    with pytest.raises(ValueError, match=r"frame 1 \(current\) has no left image"):
        DisFlow()(frame(0, img), frame(1, None))


@pytest.fixture(scope="module")
def sim_sequence(tmp_path_factory):
    root = tmp_path_factory.mktemp("flow_sim")
    generate(root, "urban", frames=3, seed=0, width=414, height=125, progress=False, lidar__enabled=False,
             overwrite=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no velodyne/ folder: not needed here
        return KittiTracking(root, "0000")


def test_dis_against_the_simulator_exact_flow(sim_sequence):
    """File N is the flow from frame N to N + 1; DIS (medium) agrees with it.

    Measured at 414x125 (urban, seeds 0-2; crowded seed 0): median EPE 0.19-0.66 px where
    the ground truth moves 0.7-8.9 px (median). The 1.0 px bound leaves room for other
    renders while staying 9x below the zero-flow error of this sequence; the reversed flow
    (the file read as N + 1 -> N) fails it."""
    files = flow_source("auto", sim_sequence)
    assert isinstance(files, FileFlow) and files.folder.parts[-2:] == ("flow_noc", "0000")
    dis = TimedStage(flow_source("dis", sim_sequence), "flow")
    for n in range(len(sim_sequence) - 1):
        a, b = sim_sequence[n], sim_sequence[n + 1]
        gt = files(a, b)
        valid = np.isfinite(gt).all(axis=2)
        assert valid.mean() > 0.5
        est = dis(a, b)
        epe = np.median(np.linalg.norm(est - gt, axis=2)[valid])
        zero_flow_epe = np.median(np.linalg.norm(gt, axis=2)[valid])
        assert epe < 1.0 and epe < zero_flow_epe / 5, (n, epe, zero_flow_epe)
        reversed_epe = np.median(np.linalg.norm(-est - gt, axis=2)[valid])
        assert reversed_epe > 3 * epe
    assert len(dis.ms) == len(sim_sequence) - 1 and dis.last_ms().keys() == {"flow"}


def test_flow_source_choices(sim_sequence, tmp_path):
    assert isinstance(flow_source("auto", None), DisFlow)
    assert isinstance(flow_source("files", sim_sequence, occlusions="occ"), FileFlow)
    with pytest.raises(ValueError, match="flow source 'flownet': expected one of auto, files, dis, raft"):
        flow_source("flownet", sim_sequence)
    with pytest.raises(ValueError, match="expected 'noc' or 'occ'"):
        flow_source("files", sim_sequence, occlusions="all")
    files = flow_source("files", sim_sequence)
    with pytest.raises(ValueError, match="not 0 -> 2"):
        files(sim_sequence[0], sim_sequence[2])
    generate(tmp_path / "nf", frames=1, width=138, height=42, progress=False, lidar__enabled=False,
                       output__flow=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        seq = KittiTracking(tmp_path / "nf", "0000")
    assert isinstance(flow_source("auto", seq), DisFlow)
    with pytest.raises(FileNotFoundError, match="has no flow_noc/ files"):
        flow_source("files", seq)
