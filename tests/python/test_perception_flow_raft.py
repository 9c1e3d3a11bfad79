"""RAFT flow source: image preparation (scaling to [-1, 1], padding to multiples of 8,
cropping back) with a stand-in network and weight-file errors; the plain-torch RAFT network
(tiny untrained models end to end, state-dict round trips, torchvision's key layout and
parameter counts, the correlation lookup and the upsampling)."""

import numpy as np
import pytest

from twistslam.datasets import Frame
from twistslam.perception import RaftFlow, flow_source, load_raft

import torch  # noqa: E402  the models extra, which make setup installs: a missing torch fails here


def frame(index, image):
    return Frame(index=index, timestamp=0.1 * index, image_left=image, image_right=None, points_c=None,
                 points_velo=None, calib=None)


class ProbeNetwork(torch.nn.Module):
    """Stands in for RAFT: u = image1 value of channel 0 + x, v = image2 value of channel 1 +
    the padded height, so the test sees what the network received."""

    def __init__(self):
        super().__init__()
        self.calls = []

    def forward(self, image1, image2, num_flow_updates=12):
        self.calls.append((tuple(image1.shape), num_flow_updates))
        n, _, h, w = image1.shape
        xs = torch.arange(w, dtype=torch.float32).expand(n, h, w)
        u = image1[:, 0] + xs
        v = image2[:, 1] + h
        return [torch.zeros(n, 2, h, w), torch.stack([u, v], dim=1)]


def test_raft_pads_to_multiples_of_8_scales_and_crops():
    probe = ProbeNetwork()
    raft = RaftFlow(network=probe, flow_updates=3)
    a = np.zeros((45, 70, 3), np.uint8)
    a[..., 0] = 255  # -> +1 after scaling
    b = np.zeros((45, 70), np.uint8)  # grey: repeated to 3 channels, 0 -> -1
    flow = raft(frame(0, a), frame(1, b))
    assert probe.calls == [((1, 3, 48, 72), 3)]
    assert flow.shape == (45, 70, 2) and flow.dtype == np.float32
    np.testing.assert_allclose(flow[..., 0], 1.0 + np.arange(70)[None, :].repeat(45, 0))
    np.testing.assert_allclose(flow[..., 1], -1.0 + 48)


def test_raft_errors_name_the_problem(tmp_path):
    with pytest.raises(ValueError, match="name a weight file"):
        RaftFlow()
    with pytest.raises(FileNotFoundError, match=r"missing.pth not found \(nothing is downloaded"):
        flow_source("raft", None, weights=tmp_path / "missing.pth")
    with pytest.raises(ValueError, match="RAFT model 'raft_huge'"):
        load_raft(tmp_path / "missing.pth", "raft_huge")
    with pytest.raises(ValueError, match="flow_updates: expected >= 1"):
        RaftFlow(network=ProbeNetwork(), flow_updates=0)
    raft = RaftFlow(network=ProbeNetwork())
    with pytest.raises(ValueError, match=r"frame 1 \(current\) image must be uint8"):
        raft(frame(0, np.zeros((8, 8, 3), np.uint8)), frame(1, np.zeros((8, 8, 3), np.float32)))
    with pytest.raises(ValueError, match="frames 0 and 1 differ in image size"):
        raft(frame(0, np.zeros((8, 8, 3), np.uint8)), frame(1, np.zeros((8, 16, 3), np.uint8)))


# --- the plain-torch RAFT network -----------------------------------------------------------

from pathlib import Path  # noqa: E402

from twistslam.perception import raft_model  # noqa: E402
from twistslam.perception.raft_blocks import (CorrelationPyramid, upsample_bilinear,  # noqa: E402
                                              upsample_convex)

DATA = Path(__file__).parent / "data"
#: raft_small-like tiny model (bottleneck encoders, one 3x3 GRU, bilinear upsampling); 2
#: pyramid levels so that 1/8-resolution maps of 5 cells (40 px images) are enough
TINY_SMALL = raft_model.RaftConfig(
    feature_layers=(8, 8, 8, 12, 16), context_layers=(8, 8, 8, 12, 16), corr_levels=2, corr_radius=1,
    motion_corr_layers=(8,), motion_flow_layers=(8, 4), motion_channels=10, hidden_size=8, flow_head_hidden=8)
#: raft_large-like tiny model (residual encoders, batch-norm context, separable GRUs, convex mask)
TINY_LARGE = raft_model.RaftConfig(
    feature_layers=(8, 8, 8, 8, 12), feature_block="residual", context_layers=(8, 8, 8, 8, 12),
    context_block="residual", context_norm="batch", corr_levels=2, corr_radius=1, motion_corr_layers=(8, 8),
    motion_flow_layers=(8, 4), motion_channels=10, hidden_size=6, gru_kernels=((1, 5), (5, 1)),
    flow_head_hidden=8, mask_hidden=8)
#: torchvision's documented parameter counts (Raft_Small_Weights / Raft_Large_Weights metadata)
DOCUMENTED_PARAMS = {"raft_small": 0.99e6, "raft_large": 5.26e6}


def textured_pair(h, w, shift_x=2, seed=0):
    """A smooth random texture and the same texture moved ``shift_x`` px to the right."""
    rng = np.random.default_rng(seed)
    coarse = rng.uniform(0, 255, (h // 4 + 2, w // 4 + 3, 3))
    image = np.kron(coarse, np.ones((4, 4, 1)))  # 4 px blocks: structure the network can match
    return (image[:h, shift_x:shift_x + w].astype(np.uint8),
            image[:h, :w].astype(np.uint8))


@pytest.mark.parametrize("config", [TINY_SMALL, TINY_LARGE], ids=["small-like", "large-like"])
def test_tiny_untrained_raft_end_to_end_through_raftflow(config):
    torch.manual_seed(0)
    network = raft_model.RAFT(config)
    a, b = textured_pair(37, 100)
    flow = RaftFlow(network=network, flow_updates=4)(frame(0, a), frame(1, b))
    assert flow.shape == (37, 100, 2) and flow.dtype == np.float32
    assert np.isfinite(flow).all() and np.abs(flow).max() > 0
    # the crop is the top-left of the network's flow on the replicate-padded 40 x 104 images
    padded = [torch.nn.functional.pad(torch.from_numpy(x).permute(2, 0, 1)[None].float() / 127.5 - 1,
                                      (0, 4, 0, 3), mode="replicate") for x in (a, b)]
    with torch.inference_mode():
        predictions = network(*padded, num_flow_updates=4)
    assert len(predictions) == 4 and all(p.shape == (1, 2, 40, 104) for p in predictions)
    np.testing.assert_allclose(flow, predictions[-1][0, :, :37, :100].permute(1, 2, 0).numpy(), atol=1e-5)


def test_state_dict_round_trip_gives_identical_flow(tmp_path):
    torch.manual_seed(1)
    trained = raft_model.RAFT(TINY_LARGE)
    with torch.no_grad():  # non-default batch-norm statistics: the buffers must travel too
        trained.context_encoder.convnormrelu[1].running_var.uniform_(0.5, 2.0)
    torch.save(trained.state_dict(), tmp_path / "tiny.pth")
    torch.manual_seed(2)
    fresh = raft_model.RAFT(TINY_LARGE)
    a, b = textured_pair(40, 104, seed=3)
    before = RaftFlow(network=fresh)(frame(0, a), frame(1, b))
    fresh.load_state_dict(torch.load(tmp_path / "tiny.pth", weights_only=True), strict=True)
    expected = RaftFlow(network=trained)(frame(0, a), frame(1, b))
    after = RaftFlow(network=fresh)(frame(0, a), frame(1, b))
    np.testing.assert_array_equal(after, expected)
    assert not np.allclose(before, expected)  # the load changed the network


def test_load_raft_reads_a_raft_small_state_dict_and_rejects_others(tmp_path):
    torch.manual_seed(4)
    source = raft_model.raft_small()
    torch.save(source.state_dict(), tmp_path / "small.pth")
    loaded = load_raft(tmp_path / "small.pth", "raft_small")
    assert not loaded.training
    for key, value in source.state_dict().items():
        assert torch.equal(loaded.state_dict()[key], value), key
    a, b = textured_pair(128, 128, seed=5)  # 4 pyramid levels need 128 px per side
    flow = RaftFlow(tmp_path / "small.pth", flow_updates=2)(frame(0, a), frame(1, b))
    assert flow.shape == (128, 128, 2) and np.isfinite(flow).all()

    torch.save(raft_model.RAFT(TINY_SMALL).state_dict(), tmp_path / "tiny.pth")
    with pytest.raises(ValueError, match=r"tiny.pth: not a raft_small state dict \(RuntimeError"):
        load_raft(tmp_path / "tiny.pth", "raft_small")
    with pytest.raises(ValueError, match=r"small.pth: not a raft_large state dict"):
        load_raft(tmp_path / "small.pth", "raft_large")
    torch.save([torch.zeros(3)], tmp_path / "list.pth")
    with pytest.raises(ValueError, match=r"list.pth: not a raft_small state dict \(TypeError: the file holds a list"):
        load_raft(tmp_path / "list.pth")
    (tmp_path / "junk.pth").write_bytes(b"not a checkpoint")
    with pytest.raises(ValueError, match=r"junk.pth: not a raft_small state dict"):
        load_raft(tmp_path / "junk.pth")


def read_key_fixture(name):
    lines = [line.split() for line in (DATA / f"{name}_keys.txt").read_text().splitlines()
             if line and not line.startswith("#")]
    return {key: () if shape == "scalar" else tuple(int(n) for n in shape.split("x")) for key, shape in lines}


@pytest.mark.parametrize("name", ["raft_small", "raft_large"])
def test_state_dict_layout_is_torchvisions(name):
    network = getattr(raft_model, name)()
    expected = read_key_fixture(name)
    ours = {key: tuple(value.shape) for key, value in network.state_dict().items()}
    assert set(ours) == set(expected), sorted(set(ours) ^ set(expected))[:10]
    assert ours == expected
    n_params = sum(p.numel() for p in network.parameters())
    assert n_params == pytest.approx(DOCUMENTED_PARAMS[name], rel=0.01)


def test_correlation_lookup_is_the_scaled_dot_product_at_the_target():
    torch.manual_seed(5)
    f1, f2 = torch.randn(1, 6, 4, 5), torch.randn(1, 6, 4, 5)
    pyramid = CorrelationPyramid(f1, f2, levels=2, radius=1)
    targets = torch.zeros(1, 2, 4, 5)
    targets[:, 0], targets[:, 1] = 2.0, 1.0  # every pixel looks at (x=2, y=1) of image 2
    corr = pyramid.lookup(targets)
    assert corr.shape == (1, pyramid.channels, 4, 5) == (1, 2 * 9, 4, 5)
    # channel (dx + 1) * 3 + (dy + 1) of level 0 samples image 2 at (2 + dx, 1 + dy)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            expected = (f1[0] * f2[0, :, 1 + dy, 2 + dx, None, None]).sum(0) / 6 ** 0.5
            torch.testing.assert_close(corr[0, (dx + 1) * 3 + (dy + 1)], expected)
    # half-way between two cells: the mean of both
    targets[:, 0] = 2.5
    mid = pyramid.lookup(targets)[0, 4]
    torch.testing.assert_close(mid, 0.5 * (corr[0, 4] + corr[0, 7]))


def test_upsampling_scales_vectors_and_convex_weights_preserve_constant_flow():
    flow = torch.zeros(1, 2, 3, 4)
    flow[:, 0], flow[:, 1] = 1.5, -0.5  # coarse cells: 1.5 and -0.5 cells per frame
    up = upsample_bilinear(flow)
    assert up.shape == (1, 2, 24, 32)
    torch.testing.assert_close(up[0, 0], torch.full((24, 32), 12.0))
    torch.testing.assert_close(up[0, 1], torch.full((24, 32), -4.0))
    mask = torch.randn(1, 9 * 64, 3, 4)
    # inside the grid a convex mix of equal vectors is that vector (the border mixes in zeros)
    convex = upsample_convex(flow, mask)
    torch.testing.assert_close(convex[0, :, 8:16, 8:24], up[0, :, 8:16, 8:24])
    # a mask that puts all weight on the centre neighbour copies each coarse vector to its 8 x 8
    ramp = torch.arange(12.0).reshape(1, 1, 3, 4).repeat(1, 2, 1, 1)
    centre_only = torch.full((1, 9, 64, 3, 4), -1e4)
    centre_only[:, 4] = 0.0
    copied = upsample_convex(ramp, centre_only.reshape(1, 9 * 64, 3, 4))
    torch.testing.assert_close(copied, 8 * ramp.repeat_interleave(8, dim=2).repeat_interleave(8, dim=3))
