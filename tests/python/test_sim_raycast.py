"""The simulator's fast paths give the answers of the plain ones: moving objects cast in their
own frames with candidate rays, flow visibility from the next frame's depth, mip textures
sampled in one gather, disparity from the pixel rays, fast PNGs, building meshes."""

import io

import numpy as np
import pytest
from PIL import Image

from twistslam.sim import extras
from twistslam.sim.camera_render import Camera, render
from twistslam.sim.lidar import Lidar
from twistslam.sim.mesh import rotate
from twistslam.datasets.png16 import encode_png
from twistslam.sim.raycast import GROUP, cast, occluded
from twistslam.sim.scenario import scenario_config
from twistslam.sim.textures import MipTexture, fractal_noise
from twistslam.sim.world import World


def _world(scenario: str, seed: int, frames: int = 6, width: int = 414, height: int = 125) -> World:
    cfg = scenario_config(scenario, lidar__azimuth_step=0.6)
    cfg.frames, cfg.seed, cfg.seq = frames, seed, "0000"
    cfg.camera.width, cfg.camera.height = width, height
    return World(cfg)


@pytest.fixture(scope="module")
def crowded() -> World:
    return _world("crowded", 1)  # many moving objects, some beside the camera


@pytest.mark.parametrize("n", [0, 5])
def test_object_candidates_find_every_object_hit(crowded, n):
    world = crowded
    objects = world.moving_objects(n)
    assert len(objects) > 50
    camera = Camera(world.calib.P2, world.width, world.height)
    origin, dirs = camera.map_rays(world.T_m_c[n])
    origins = np.broadcast_to(origin, dirs.shape)
    candidates = objects.pixel_candidates(camera.P, world.T_m_c[n], camera.width, camera.height)
    fast, plain = cast(world.static_scene, objects, origins, dirs, candidates), cast(world.static_scene, objects,
                                                                                   origins, dirs)
    assert (fast.group == 100).mean() > 0.2
    np.testing.assert_array_equal(fast.t, plain.t)
    np.testing.assert_array_equal(fast.agent, plain.agent)
    # shadow rays towards the sun
    lit = np.flatnonzero(np.isfinite(fast.t) & (fast.normal @ world.sun > 0))
    start = fast.point[lit] + 0.03 * fast.normal[lit]
    sun = np.broadcast_to(world.sun, start.shape)
    shadow = occluded(world.static_scene, objects, start, sun, 400.0, objects.shadow_candidates(start, world.sun))
    np.testing.assert_array_equal(shadow, occluded(world.static_scene, objects, start, sun, 400.0))
    assert 0.05 < shadow.mean() < 0.95
    # LiDAR rays
    lidar = Lidar(world.cfg.lidar)
    T = world.T_m_c[n] @ world.T_c_velo
    d = rotate(lidar.dirs32, T[:3, :3].astype(np.float32))
    o = np.broadcast_to(T[:3, 3], d.shape)
    grid = objects.grid_candidates(T, lidar.elevation, lidar.azimuth_step, lidar.n_azimuth)
    fast, plain = cast(world.static_scene, objects, o, d, grid), cast(world.static_scene, objects, o, d)
    np.testing.assert_array_equal(fast.t, plain.t)
    np.testing.assert_array_equal(fast.agent, plain.agent)


def test_flow_visibility_from_next_depth_matches_rays():
    world = _world("urban", 3)
    camera = Camera(world.calib.P2, world.width, world.height)
    for n in (1, 3):
        hits = render(world, camera, world.moving_objects(n), n, np.random.default_rng(0))[1]
        objects_next = world.moving_objects(n + 1)
        hits_next = render(world, camera, objects_next, n + 1, np.random.default_rng(0))[1]
        fl, occ, rays = extras.flow(world, camera, hits, n, objects_next)
        fl2, occ2, depth = extras.flow(world, camera, hits, n, objects_next, hits_next)
        np.testing.assert_array_equal(fl, fl2)
        np.testing.assert_array_equal(occ, occ2)
        assert rays.sum() > 0.5 * occ.sum() and (rays & ~occ).sum() == 0
        assert (rays != depth).sum() <= 1e-3 * occ.sum()  # only sub-pixel occluders differ


def test_disparity_from_pixel_rays_matches_projected_points():
    world = _world("urban", 2, frames=2)
    left, right = Camera(world.calib.P2, world.width, world.height), Camera(world.calib.P3, world.width, world.height)
    hits = render(world, left, world.moving_objects(1), 1, np.random.default_rng(0))[1]
    d = extras.disparity(world, left, right, hits, 1).ravel()
    uv, _ = right.project_map(hits.point, world.T_m_c[1])
    hit = np.isfinite(hits.t)
    np.testing.assert_allclose(d[hit], left.pixel_centres()[hit, 0] - uv[hit, 0], atol=1e-3)
    assert (d[~hit] == 0).all() and d[hit].min() > 0


def test_mip_texture_sample_is_bilinear_in_the_nearest_level():
    rng = np.random.default_rng(0)
    tex = MipTexture(1.0 + 0.2 * fractal_noise(rng, 64, 1.0), 0.05)
    u, v = rng.uniform(-40, 40, 5000), rng.uniform(-40, 40, 5000)
    fp = np.exp(rng.uniform(-6, 2, 5000))
    lod = np.clip(np.floor(np.log2(fp / tex.texel) + 0.5), 0, len(tex.levels) - 1).astype(int)
    expected = np.empty(len(u))
    for k in range(len(u)):
        img = tex.levels[lod[k]]
        x, y = u[k] / (tex.texel * 2.0 ** lod[k]) - 0.5, v[k] / (tex.texel * 2.0 ** lod[k]) - 0.5
        x0, y0 = int(np.floor(x)), int(np.floor(y))
        fx, fy = x - x0, y - y0
        s = len(img)
        c = [img[(y0 + j) % s, (x0 + i) % s] for j in (0, 1) for i in (0, 1)]
        expected[k] = (c[0] * (1 - fx) + c[1] * fx) * (1 - fy) + (c[2] * (1 - fx) + c[3] * fx) * fy
    np.testing.assert_allclose(tex.sample(u, v, fp), expected, rtol=1e-5)
    with pytest.raises(ValueError, match="power-of-two"):
        MipTexture(np.ones((48, 48)), 0.1)


@pytest.mark.parametrize("shape", [(7, 33, 3), (5, 20)])
def test_8bit_png_round_trip_through_pillow(shape):
    values = np.random.default_rng(1).integers(0, 256, size=shape, dtype=np.uint8)
    np.testing.assert_array_equal(np.asarray(Image.open(io.BytesIO(encode_png(values)))), values)
    with pytest.raises(ValueError):
        encode_png(values.astype(np.int32))


def test_building_meshes_index_their_own_vertices():
    world = _world("urban", 0, frames=2)
    for code, mesh in world.static_scene.mesh_of_group.items():
        assert mesh.faces.min() >= 0 and mesh.faces.max() < len(mesh.vertices), code
    # four wall quads and a roof quad per building: 8 + 2 triangles on 16 + 4 vertices
    walls, roofs = (world.static_scene.mesh_of_group[GROUP[g]] for g in ("wall", "roof"))
    assert len(walls.faces) * 2 == len(walls.vertices) and len(roofs.faces) * 2 == len(roofs.vertices)


def test_flow_png_of_pixels_without_a_surface_is_zero_and_quiet():
    # sky pixels hit nothing: their flow is NaN, which must neither warn nor reach the PNG
    fl = np.array([[[1.5, -2.0], [np.nan, np.nan]], [[np.inf, -np.inf], [0.25, 0.0]]])
    valid = np.array([[True, False], [False, True]])
    with np.errstate(all="raise"):
        out = extras.encode_flow(fl, valid)
    assert out.dtype == np.uint16 and out.shape == (2, 2, 3)
    np.testing.assert_array_equal(out[..., 2], valid.astype(np.uint16))
    assert (out[~valid] == 0).all()
    np.testing.assert_array_equal(out[0, 0, :2], np.rint(np.array([1.5, -2.0]) * extras.FLOW_SCALE + 2**15))
    np.testing.assert_array_equal(out[1, 1, :2], np.rint(np.array([0.25, 0.0]) * extras.FLOW_SCALE + 2**15))
