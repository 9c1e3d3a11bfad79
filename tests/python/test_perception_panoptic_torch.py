"""The "torch" panoptic source: plain-torch Mask R-CNN (things) fused with a DeepLabV3 / FCN
(stuff), end to end on tiny untrained networks built here; weight-file round trips and
errors; the building blocks (NMS, RoIAlign, box coding, mask pasting) against direct
computations; the full-size builders against torchvision's key layout (key lists extracted
from torchvision 0.28.0 into tests/python/data) and its documented parameter counts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from twistslam.datasets import Frame
from twistslam.perception import Panoptic, TorchPanoptic, panoptic_source
from twistslam.perception.panoptic import DEFAULT_DYNAMIC_CLASSES
from twistslam.perception.run_stages import perception_stages

import torch  # noqa: E402  the models extra, which make setup installs: a missing torch fails here

from twistslam.perception.torch_models import box_ops  # noqa: E402
from twistslam.perception.torch_models.box_ops import BoxCoder, batched_nms, nms  # noqa: E402
from twistslam.perception.torch_models.deeplab import (SegmentationNet, deeplabv3_resnet50,  # noqa: E402
                                                       fcn_resnet50)
from twistslam.perception.torch_models.maskrcnn import (ImageResize, MaskRCNN,  # noqa: E402
                                                        MaskRCNNShape, maskrcnn_resnet50_fpn)
from twistslam.perception.torch_models.resnet import ResNetShape  # noqa: E402
from twistslam.perception.torch_models.roi_align import roi_align  # noqa: E402
from twistslam.perception.torch_models.roi_heads import paste_masks  # noqa: E402

DATA = Path(__file__).parent / "data"
H, W = 48, 72
TINY_BACKBONE = ResNetShape(blocks=(1, 1, 1, 1), width=4)
TINY_DETECTOR_SIZE = (64, 96)  # shorter side, longer-side cap of the tiny detector
TINY_SEMANTIC_SIZE = 40
# COCO category ids the tiny detector is biased towards: person, car, dog (dog has no
# Cityscapes class: it must never be painted)
PERSON, CAR, DOG = 1, 3, 18
# the tiny semantic net's 4 outputs -> road, building, sky, and one unmapped index
SEMANTIC_CLASSES = {0: 7, 1: "building", 2: "sky"}
SCORE = 0.5  # the default detection score threshold
BOX_HEAD_GAIN = 6.0  # scales the tiny box head's weights: spread-out scores, a few above SCORE


def frame(index: int, image: np.ndarray) -> Frame:
    return Frame(index=index, timestamp=0.1 * index, image_left=image, image_right=None,
                 points_c=None, points_velo=None, calib=None)


def tiny_detector(seed: int = 0) -> MaskRCNN:
    """An untrained tiny Mask R-CNN whose heads are biased so that it does detect: person,
    car and dog get large class biases, and the box head's weights are scaled up so that its
    features (tiny with random weights) spread the scores: a few detections pass SCORE."""
    torch.manual_seed(seed)
    model = MaskRCNN(MaskRCNNShape(backbone=TINY_BACKBONE, fpn_channels=8, box_head_width=16,
                                   mask_channels=8), resize=ImageResize(*TINY_DETECTOR_SIZE))
    with torch.no_grad():
        predictor = model.roi_heads.box_predictor
        predictor.cls_score.weight.normal_(0, 0.5)
        predictor.cls_score.bias.zero_()
        predictor.cls_score.bias[[PERSON, CAR, DOG]] = torch.tensor([5.5, 6.0, 5.0])
        predictor.bbox_pred.weight.normal_(0, 0.05)
        model.roi_heads.box_head.fc6.weight.mul_(BOX_HEAD_GAIN)
        model.roi_heads.box_head.fc7.weight.mul_(BOX_HEAD_GAIN)
        model.roi_heads.mask_predictor.mask_fcn_logits.bias.zero_()
    return model.eval()


def tiny_semantic(head: str = "deeplabv3", seed: int = 1) -> SegmentationNet:
    """An untrained tiny semantic network whose batch-norm statistics are measured on four
    random images (as after training), so its eval-mode outputs vary across the image."""
    torch.manual_seed(seed)
    net = SegmentationNet(head, 4, aux=True, backbone=TINY_BACKBONE, head_channels=8)
    for module in net.modules():
        if isinstance(module, torch.nn.BatchNorm2d):
            module.momentum = None  # plain average over the calibration batch
    net.train()
    with torch.no_grad():
        net(torch.rand(4, 3, 40, 60, generator=torch.Generator().manual_seed(seed)))
    return net.eval()


def textured_image(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    image = rng.integers(0, 255, (H, W, 3), dtype=np.uint8)
    image[10:30, 20:50] = (200, 40, 40)  # a flat block: something for masks to sit on
    return image


def stage(**kwargs) -> TorchPanoptic:
    defaults = dict(detector=tiny_detector(), semantic=tiny_semantic(),
                    semantic_classes=SEMANTIC_CLASSES, semantic_min_size=TINY_SEMANTIC_SIZE)
    return TorchPanoptic(**{**defaults, **kwargs})


def expected_labels(source: TorchPanoptic, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fusion rule recomputed pixel by pixel from the networks' raw outputs: the most
    confident mapped detection covering a pixel wins; otherwise the semantic class."""
    x = torch.from_numpy(image).permute(2, 0, 1).float() / 255
    with torch.no_grad():
        det = source.detector([x])[0]
        class_id = source._stuff(x)
    scores, labels = det["scores"].numpy(), det["labels"].numpy()
    masks = det["masks"][:, 0].numpy() > source.mask_threshold
    painted = [k for k in range(len(scores))
               if scores[k] >= SCORE and int(labels[k]) in (PERSON, CAR)]
    best = np.full((H, W), -1.0)
    winner = np.full((H, W), -1)
    for k in painted:
        better = masks[k] & (scores[k] > best)
        best[better], winner[better] = scores[k], k
    instance_id = np.zeros((H, W), np.int32)
    for rank, k in enumerate(sorted(painted, key=lambda k: -scores[k]), start=1):
        class_id = np.where(winner == k, {PERSON: 24, CAR: 26}[int(labels[k])], class_id)
        instance_id[winner == k] = rank
    return class_id, instance_id


def confident_labels(source: TorchPanoptic, image: np.ndarray) -> set[int]:
    x = torch.from_numpy(image).permute(2, 0, 1).float() / 255
    with torch.no_grad():
        det = source.detector([x])[0]
    return set(det["labels"][det["scores"] >= SCORE].tolist())


# ----------------------------------------------------------------- the stage end to end
def test_tiny_networks_end_to_end_follow_the_fusion_rule():
    source = stage()
    image = textured_image()
    # the detector is confident about a person and about a COCO class without a Cityscapes
    # class (which must not be painted)
    labels = confident_labels(source, image)
    assert PERSON in labels and labels - {PERSON, CAR}
    out = source(frame(0, image))
    assert isinstance(out, Panoptic) and out.shape == (H, W)
    assert out.class_id.dtype == np.int32 and out.instance_id.dtype == np.int32
    # class ids: the mapped stuff, unknown, or the two mapped thing classes; never a dog
    assert set(np.unique(out.class_id)) <= {0, 7, 11, 23, 24, 26}
    things = np.isin(out.class_id, DEFAULT_DYNAMIC_CLASSES)
    assert np.array_equal(out.instance_id > 0, things)  # instances exactly on thing pixels
    instances = out.instances()
    assert len(instances) >= 2 and set(instances.values()) <= {24, 26}  # painting happened
    assert 0.05 < things.mean() < 0.95 and len(set(np.unique(out.class_id)) & {7, 11, 23}) >= 2
    class_id, instance_id = expected_labels(source, image)
    np.testing.assert_array_equal(out.class_id, class_id)
    np.testing.assert_array_equal(out.instance_id, instance_id)


def test_deterministic_and_grey_images_accepted():
    source = stage(semantic=tiny_semantic("fcn"))
    image = textured_image(3)
    a, b = source(frame(0, image)), source(frame(0, image.copy()))
    np.testing.assert_array_equal(a.class_id, b.class_id)
    np.testing.assert_array_equal(a.instance_id, b.instance_id)
    grey = source(frame(1, image[..., 0]))
    assert grey.shape == (H, W)
    with pytest.raises(ValueError, match="frame 2 image must be uint8"):
        source(frame(2, image.astype(np.float32)))


def test_without_semantic_network_stuff_is_unknown():
    out = stage(semantic=None)(frame(0, textured_image()))
    assert set(np.unique(out.class_id)) <= {0, 24, 26}
    assert (out.class_id == 0).any() and (out.instance_id > 0).any()


def test_score_threshold_one_paints_nothing():
    source = stage(score_threshold=1.0)
    out = source(frame(0, textured_image()))
    assert not out.instance_id.any()
    assert set(np.unique(out.class_id)) <= {0, 7, 11, 23}


def test_weight_files_round_trip(tmp_path):
    detector, semantic = tiny_detector(), tiny_semantic()
    torch.save(detector.state_dict(), tmp_path / "maskrcnn.pth")
    # a training checkpoint of torchvision's reference scripts keeps the weights under "model"
    torch.save({"model": semantic.state_dict(), "epoch": 3}, tmp_path / "semantic.pth")
    image = textured_image(5)
    from_modules = stage(detector=detector, semantic=semantic)(frame(0, image))
    from_files = TorchPanoptic(maskrcnn_weights=tmp_path / "maskrcnn.pth",
                               semantic_weights=tmp_path / "semantic.pth",
                               semantic_classes=SEMANTIC_CLASSES, num_semantic_classes=4,
                               semantic_min_size=TINY_SEMANTIC_SIZE,
                               detector_size=TINY_DETECTOR_SIZE)(frame(0, image))
    assert from_modules.instance_id.any()
    np.testing.assert_array_equal(from_files.class_id, from_modules.class_id)
    np.testing.assert_array_equal(from_files.instance_id, from_modules.instance_id)


def test_weight_file_errors_name_the_file(tmp_path):
    with pytest.raises(ValueError, match="maskrcnn_weights"):
        TorchPanoptic()
    missing = tmp_path / "nowhere.pth"
    with pytest.raises(FileNotFoundError, match="nowhere.pth not found"):
        TorchPanoptic(maskrcnn_weights=missing)
    junk = tmp_path / "junk.pth"
    junk.write_bytes(b"not a torch file")
    with pytest.raises(ValueError, match=r"junk.pth: not a Mask R-CNN state dict"):
        TorchPanoptic(maskrcnn_weights=junk)
    torch.save(tiny_semantic().state_dict(), tmp_path / "semantic.pth")
    with pytest.raises(ValueError, match=r"semantic.pth: not a Mask R-CNN state dict"):
        TorchPanoptic(maskrcnn_weights=tmp_path / "semantic.pth")
    state = tiny_detector().state_dict()
    del state["roi_heads.mask_predictor.conv5_mask.bias"]
    torch.save(state, tmp_path / "partial.pth")
    with pytest.raises(ValueError, match=r"partial.pth: not a Mask R-CNN state dict.*conv5_mask"):
        TorchPanoptic(maskrcnn_weights=tmp_path / "partial.pth")
    torch.save(tiny_detector().state_dict(), tmp_path / "maskrcnn.pth")
    with pytest.raises(ValueError, match=r"maskrcnn.pth: not a semantic segmentation"):
        TorchPanoptic(maskrcnn_weights=tmp_path / "maskrcnn.pth",
                      semantic_weights=tmp_path / "maskrcnn.pth")
    with pytest.raises(ValueError, match="semantic.pth: the semantic network has 4 classes, "
                       "num_semantic_classes is 21"):
        TorchPanoptic(detector=tiny_detector(), semantic_weights=tmp_path / "semantic.pth",
                      num_semantic_classes=21)
    with pytest.raises(ValueError, match="pass semantic_classes"):
        TorchPanoptic(detector=tiny_detector(), semantic=tiny_semantic())  # 4 != 21 VOC classes
    with pytest.raises(ValueError, match="not a Cityscapes id"):
        stage(semantic_classes={0: 99})


def test_source_and_run_stage_need_the_weights(tmp_path):
    with pytest.raises(ValueError, match="segmentation_weights=.*--maskrcnn-weights"):
        panoptic_source("torch")
    with pytest.raises(ValueError, match=r"unknown weights keys \['mask'\]"):
        panoptic_source("torch", weights={"maskrcnn": "a.pth", "mask": "b.pth"})
    with pytest.raises(FileNotFoundError, match="gone.pth not found"):
        perception_stages(None, "torch", None, segmentation_weights={"maskrcnn": tmp_path / "gone.pth"})
    torch.save(tiny_detector().state_dict(), tmp_path / "maskrcnn.pth")
    torch.save(tiny_semantic().state_dict(), tmp_path / "semantic.pth")
    stages = perception_stages(None, "torch", None, segmentation_weights={
        "maskrcnn": tmp_path / "maskrcnn.pth", "semantic": tmp_path / "semantic.pth",
        "semantic_classes": SEMANTIC_CLASSES})
    assert stages.segmentation_name == "torch" and isinstance(stages.segmentation, TorchPanoptic)
    assert stages.segmentation.semantic_lut.tolist() == [7, 11, 23, 0]


def test_cli_passes_the_weight_files(tmp_path, monkeypatch):
    from twistslam import cli

    seen = {}

    def fake_run(sequence, config, **kwargs):
        seen.update(kwargs)
        raise SystemExit(0)

    monkeypatch.setattr("twistslam.pipeline.run", fake_run)
    monkeypatch.setattr("twistslam.datasets.open_sequence", lambda *a, **k: None)
    args = ["run", str(tmp_path), "--seq", "0000", "--out", str(tmp_path / "out"),
            "--segmentation", "torch", "--maskrcnn-weights", "m.pth", "--semantic-weights", "s.pth"]
    with pytest.raises(SystemExit):
        cli.main(args)
    assert seen["segmentation"] == "torch"
    assert seen["segmentation_weights"] == {"maskrcnn": Path("m.pth"), "semantic": Path("s.pth")}


# ------------------------------------------------------------------------ building blocks
def brute_force_nms(boxes: np.ndarray, scores: np.ndarray, threshold: float,
                    groups: np.ndarray | None = None) -> list[int]:
    """O(n^2) greedy NMS written from the definition, in float64."""
    groups = np.zeros(len(boxes), int) if groups is None else groups
    kept: list[int] = []
    for i in sorted(range(len(boxes)), key=lambda i: -scores[i]):
        survives = True
        for j in kept:
            if groups[i] != groups[j]:
                continue
            w = min(boxes[i, 2], boxes[j, 2]) - max(boxes[i, 0], boxes[j, 0])
            h = min(boxes[i, 3], boxes[j, 3]) - max(boxes[i, 1], boxes[j, 1])
            inter = max(w, 0.0) * max(h, 0.0)
            area = lambda b: (b[2] - b[0]) * (b[3] - b[1])  # noqa: E731
            if inter / (area(boxes[i]) + area(boxes[j]) - inter) > threshold:
                survives = False
                break
        if survives:
            kept.append(i)
    return kept


def random_boxes(rng, n: int, extent: float = 100.0) -> np.ndarray:
    xy = rng.uniform(0, extent, (n, 2))
    wh = rng.uniform(2, extent / 3, (n, 2))
    return np.hstack([xy, xy + wh]).astype(np.float32)


@pytest.mark.parametrize("seed", range(4))
def test_nms_matches_the_brute_force_definition(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    boxes = random_boxes(rng, 150)
    scores = rng.permutation(150).astype(np.float32) / 150  # distinct: one right answer
    groups = rng.integers(0, 4, 150)
    for threshold in (0.3, 0.5, 0.7):
        kept = nms(torch.from_numpy(boxes), torch.from_numpy(scores), threshold).tolist()
        assert kept == brute_force_nms(boxes.astype(np.float64), scores, threshold)
        expected = brute_force_nms(boxes.astype(np.float64), scores, threshold, groups)
        by_class = batched_nms(torch.from_numpy(boxes), torch.from_numpy(scores),
                               torch.from_numpy(groups), threshold).tolist()
        assert by_class == expected and len(expected) >= len(kept)
        if threshold == 0.3:  # the random boxes overlap enough for both to drop some
            assert len(expected) > len(kept) and len(expected) < len(boxes)
        # the group-by-group path taken for many boxes gives the same answer
        monkeypatch.setattr(box_ops, "OFFSET_TRICK_MAX_BOXES", 10)
        assert batched_nms(torch.from_numpy(boxes), torch.from_numpy(scores),
                           torch.from_numpy(groups), threshold).tolist() == expected
        monkeypatch.undo()
    assert nms(torch.zeros((0, 4)), torch.zeros(0), 0.5).tolist() == []


def test_roi_align_on_a_ramp_equals_the_direct_bilinear_average():
    """On f(y, x) = 3 + 2x - 0.5y bilinear interpolation is exact, so each bin is the average
    of the ramp at its 2 x 2 sample points; points past the last row / column take its value
    (clamped), points more than one cell outside count as zero."""
    height, width, ratio, out = 9, 12, 2, 3
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    ramp = 3 + 2 * xs - 0.5 * ys
    features = torch.from_numpy(np.stack([ramp, -ramp])).float()[None]  # (1, 2, H, W)
    boxes = np.array([[2.0, 4.0, 14.0, 10.0],    # scale 0.5 -> inside the map
                      [-1.0, 0.5, 3.0, 3.5],     # tiny: widened to one cell
                      [16.0, 12.0, 23.0, 21.0],  # past the last column and row
                      [-9.0, -9.0, -3.1, -3.0],  # wholly more than a cell outside
                      [10.3, 6.7, 19.9, 17.2]])
    scale = 0.5
    got = roi_align(features, torch.from_numpy(boxes).float(), torch.zeros(len(boxes), dtype=torch.int64),
                    out, scale, ratio).numpy()

    def value(y, x):
        if y < -1 or y > height or x < -1 or x > width:
            return 0.0
        y, x = min(max(y, 0), height - 1), min(max(x, 0), width - 1)
        return 3 + 2 * x - 0.5 * y

    for k, (x1, y1, x2, y2) in enumerate(boxes * scale):
        bw, bh = max(x2 - x1, 1) / out, max(y2 - y1, 1) / out
        for py in range(out):
            for px in range(out):
                samples = [value(y1 + (py + (iy + 0.5) / ratio) * bh, x1 + (px + (ix + 0.5) / ratio) * bw)
                           for iy in range(ratio) for ix in range(ratio)]
                np.testing.assert_allclose(got[k, 0, py, px], np.mean(samples), atol=1e-4)
                np.testing.assert_allclose(got[k, 1, py, px], -np.mean(samples), atol=1e-4)
    assert not got[3].any()


def test_box_coding_round_trip_and_clip():
    rng = np.random.default_rng(7)
    references = torch.from_numpy(random_boxes(rng, 50))
    boxes = torch.from_numpy(random_boxes(rng, 50))
    for weights in ((1.0, 1.0, 1.0, 1.0), (10.0, 10.0, 5.0, 5.0)):
        coder = BoxCoder(weights)
        codes = coder.encode(boxes, references)
        torch.testing.assert_close(coder.decode(codes, references)[:, 0], boxes, atol=1e-3, rtol=0)
    # a huge predicted scale is clipped to exp(log(1000 / 16)) times the reference size
    coder = BoxCoder((1.0, 1.0, 1.0, 1.0))
    decoded = coder.decode(torch.tensor([[0.0, 0.0, 50.0, 50.0]]), torch.tensor([[0.0, 0.0, 16.0, 8.0]]))
    torch.testing.assert_close(decoded[0, 0, 2] - decoded[0, 0, 0], torch.tensor(1000.0))
    torch.testing.assert_close(decoded[0, 0, 3] - decoded[0, 0, 1], torch.tensor(500.0))


def test_paste_masks_fills_the_box_and_clips_at_the_border():
    masks = torch.ones((2, 1, 28, 28))
    boxes = torch.tensor([[10.0, 5.0, 38.0, 33.0], [60.0, 40.0, 90.0, 70.0]])
    pasted = paste_masks(masks, boxes, (H, W)).numpy()[:, 0] > 0.5
    # the one-cell zero border around the mask fades out half a cell past the box
    assert pasted[0, 6:33, 11:38].all() and not pasted[0, :3].any() and not pasted[0, :, :8].any()
    assert pasted[1, 41:, 61:].all() and not pasted[1, :38].any()  # cut at the image border
    assert paste_masks(torch.zeros((0, 1, 28, 28)), torch.zeros((0, 4)), (H, W)).shape == (0, 1, H, W)


# ---------------------------------------------------------- full size against torchvision
def key_layout(model) -> list[str]:
    return [f"{k} {'x'.join(map(str, v.shape)) or 'scalar'}" for k, v in model.state_dict().items()]


@pytest.mark.parametrize("builder, keys, documented", [
    (maskrcnn_resnet50_fpn, "maskrcnn_resnet50_fpn_keys.txt", 44_401_393),
    (deeplabv3_resnet50, "deeplabv3_resnet50_keys.txt", 42_004_074),
    (fcn_resnet50, "fcn_resnet50_keys.txt", 35_322_218),
])
def test_full_size_models_have_torchvisions_layout(builder, keys, documented):
    model = builder()
    count = sum(p.numel() for p in model.parameters())
    assert abs(count - documented) <= 1e-3 * documented, count
    assert key_layout(model) == (DATA / keys).read_text().splitlines()


def test_run_with_the_torch_segmentation(tmp_path, monkeypatch):
    """twistslam.run(segmentation="torch", segmentation_weights=...) on a tiny sequence (the
    core replaced by the pipeline tests' double): the core receives the stage's labels."""
    import twistslam
    from test_pipeline import SEQ, FakeSystem, write_tiny_sequence

    FakeSystem.instances = []
    monkeypatch.setattr("twistslam.slam._new_system", FakeSystem)
    root = write_tiny_sequence(tmp_path / "data", frames=2)
    torch.save(tiny_detector().state_dict(), tmp_path / "maskrcnn.pth")
    torch.save(tiny_semantic().state_dict(), tmp_path / "semantic.pth")
    weights = {"maskrcnn": tmp_path / "maskrcnn.pth", "semantic": tmp_path / "semantic.pth",
               "semantic_classes": SEMANTIC_CLASSES}
    with pytest.warns(UserWarning):  # the tiny sequence has no LiDAR
        result = twistslam.run((root, SEQ), progress=False, segmentation="torch", flow="none",
                               segmentation_weights=weights)
    assert result.segmentation == "torch" and len(result) == 2
    calls = FakeSystem.instances[-1].calls
    image = np.asarray(Image.open(root / "training" / "image_02" / SEQ / "000001.png"))
    expected = TorchPanoptic(maskrcnn_weights=weights["maskrcnn"], semantic_weights=weights["semantic"],
                             semantic_classes=SEMANTIC_CLASSES)(frame(1, image))
    np.testing.assert_array_equal(calls[1]["labels"], expected.class_id)
    np.testing.assert_array_equal(calls[1]["instances"], expected.instance_id)
    assert expected.instance_id.any() and len(np.unique(expected.class_id)) >= 3  # not trivial
