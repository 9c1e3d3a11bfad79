"""RAFT flow source: image preparation (scaling to [-1, 1], padding to multiples of 8,
cropping back) with a stand-in network, weight-file errors, and -- where torchvision is
installed -- a tiny untrained raft_small loaded from a state-dict file the test writes."""

import numpy as np
import pytest

from twistslam.datasets import Frame
from twistslam.perception import RaftFlow, flow_source, load_raft

torch = pytest.importorskip("torch")


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


def test_without_torchvision_the_error_says_what_to_install(tmp_path):
    try:
        import torchvision  # noqa: F401
        pytest.skip("torchvision is installed")
    except ImportError:
        pass
    (tmp_path / "w.pth").write_bytes(b"")
    with pytest.raises(ImportError, match="RAFT flow needs torchvision"):
        load_raft(tmp_path / "w.pth")
