"""The simulated world of one sequence: streets, static scene, agents, their trajectories,
textures, sun, calibration and the camera / LiDAR poses. Built once, then rendered frame by
frame. Every random choice draws from a generator seeded by ``(seed, component)``, so a
seed gives the same world whatever is rendered or written."""

from __future__ import annotations

import numpy as np

from twistslam.datasets import Calibration, read_calibration

from .buildings import build_static
from .car_material import car_row
from .car_mesh import CarShape, car_vehicle_mesh, vehicle_to_object
from .config import SimConfig
from .mesh import Mesh
from .motion import simulate
from .person_mesh import person_mesh
from .objects import MovingObjects
from .raycast import StaticScene, mesh_scene
from .road import StreetNetwork
from .terrain import Terrain
from .textures import TextureBank
from .traffic import spawn_agents

KITTI_SIZE = (1242, 375)  # px; calibration files are taken to be for this size
RENDER_RADIUS = 130.0  # m; objects farther from the ego car are not put in the scene
CAMERA_AHEAD = 0.3  # m; reference camera ahead of the ego car's centre
# rotation taking camera-frame vectors (x right, y down, z fwd) into the vehicle frame
R_V_C = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
# KITTI tracking training sequence 0000's calibration (calib/0000.txt, every digit), the
# default: built in, so that a seed gives the same sequence whether or not KITTI is at hand
DEFAULT_CALIB = dict(
    P0=[[721.5377, 0, 609.5593, 0], [0, 721.5377, 172.854, 0], [0, 0, 1, 0]],
    P1=[[721.5377, 0, 609.5593, -387.5744], [0, 721.5377, 172.854, 0], [0, 0, 1, 0]],
    P2=[[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791], [0, 0, 1, 0.002745884]],
    P3=[[721.5377, 0, 609.5593, -339.5242], [0, 721.5377, 172.854, 2.199936], [0, 0, 1, 0.002729905]],
    R_rect=[[0.9999239, 0.00983776, -0.007445048], [-0.009869795, 0.9999421, -0.004278459],
            [0.007402527, 0.004351614, 0.9999631]],
    Tr_velo_cam=[[0.007533745, -0.9999714, -0.000616602, -0.004069766],
                 [0.01480249, 0.0007280733, -0.9998902, -0.07631618],
                 [0.9998621, 0.00752379, 0.01480755, -0.2717806]],
    Tr_imu_velo=[[0.9999976, 0.0007553071, -0.002035826, -0.8086759],
                 [-0.0007854027, 0.9998898, -0.01482298, 0.3195559],
                 [0.002024406, 0.01482454, 0.9998881, -0.7997231]],
)
# independent random streams, one per component
STREAMS = {"layout": 1, "side": 2, "traffic": 3, "motion": 4, "textures": 5, "light": 6}


def rng_for(seed: int, component: str, *more: int) -> np.random.Generator:
    return np.random.default_rng([int(seed), STREAMS[component], *more])


def load_calibration(path: str | None, width: int, height: int) -> Calibration:
    """KITTI calibration from ``path`` (default: tracking sequence 0000), with P0..P3 scaled
    from 1242x375 to ``width x height`` (pixel centres kept at pixel centres)."""
    if path is None:
        calib = Calibration(**{k: np.array(v, dtype=np.float64) for k, v in DEFAULT_CALIB.items()},
                            source="KITTI tracking 0000 (built in)")
    else:
        calib = read_calibration(path)
    sx, sy = width / KITTI_SIZE[0], height / KITTI_SIZE[1]
    if (sx, sy) != (1.0, 1.0):
        A = np.array([[sx, 0.0, 0.5 * (sx - 1)], [0.0, sy, 0.5 * (sy - 1)], [0.0, 0.0, 1.0]])
        for name in ("P0", "P1", "P2", "P3"):
            setattr(calib, name, A @ getattr(calib, name))
    return calib


class World:
    def __init__(self, cfg: SimConfig) -> None:
        self.cfg = cfg
        seed = cfg.seed
        cam = cfg.camera
        self.width, self.height = cam.width, cam.height
        self.calib = load_calibration(cam.calib_path, cam.width, cam.height)
        self.dt = cfg.frame_period
        travel = cfg.traffic.ego_speed[1] * cfg.frames * self.dt
        st = cfg.street
        self.terrain = Terrain(rng_for(seed, "layout"), st.terrain_amplitude, st.terrain_wavelength)
        median = 1.0 if cfg.side.guard_rails and st.lanes_per_direction > 1 else 0.0
        self.net = StreetNetwork(st, rng_for(seed, "layout", 1), travel + st.ahead, median)
        static = build_static(self.net, self.terrain, cfg.side, rng_for(seed, "side"))
        self.facade_params = static.facade_params
        groups = {
            "terrain": self.net.ground_mesh(self.terrain), "road": self.net.road_mesh(self.terrain),
            "sidewalk": self.net.sidewalk_mesh(self.terrain), "wall": static.walls, "roof": static.roofs,
            "trunk": static.trunks, "canopy": static.canopies, "pole": static.poles, "sign": static.signs,
            "rail": static.rails,
        }
        s0 = self.net.ego_s0
        window = (s0 - RENDER_RADIUS, s0 + travel + RENDER_RADIUS)
        margin = max(cfg.traffic.moving_speed[1], 1.0) * cfg.frames * self.dt
        self.agents = spawn_agents(self.net, cfg.traffic, rng_for(seed, "traffic"), window, margin)
        if len(self.agents) > 999:
            raise ValueError(f"{len(self.agents)} objects: the panoptic encoding allows at most 998")
        self.traj = simulate(self.agents, self.terrain, cfg.traffic, cfg.frames, self.dt, rng_for(seed, "motion"))
        self.textures = TextureBank(rng_for(seed, "textures"))
        light = rng_for(seed, "light")
        elevation = np.radians(light.uniform(*cfg.light.sun_elevation))
        azimuth = light.uniform(0, 2 * np.pi)
        self.sun = np.array([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                             np.sin(elevation)])  # unit vector towards the sun, map frame
        T_v_c = np.eye(4)
        T_v_c[:3, :3] = R_V_C
        T_v_c[:3, 3] = [CAMERA_AHEAD, 0.0, cam.camera_height]
        self.T_m_c = self.traj.T_m_v[0] @ T_v_c  # (N, 4, 4) reference camera poses in the map
        self.T_w_c = np.linalg.inv(self.T_m_c[0]) @ self.T_m_c  # world = camera at frame 0 (docs/design.md)
        self._build_object_meshes()
        # objects that never move (parked cars) join the static scene, built once
        parked = [i for i in np.flatnonzero(self.near.any(axis=1) & ~self.moving) if self.meshes[i] is not None]
        placed = [(i, self.meshes[i].transformed(self.object_pose(i, 0))) for i in parked]
        self.static_scene = StaticScene(groups, placed)
        # every tracked object's mesh in a ray-casting scene of its own, in its object frame
        # (built once: rays are moved into the object frame instead of the mesh; the moving
        # objects of a frame and the amodal masks of labels are cast this way)
        self.object_scenes = {int(a): mesh_scene(self.meshes[a].vertices, self.meshes[a].faces)
                              for a in np.flatnonzero(self.track_id >= 0) if self.meshes[a] is not None}

    def _build_object_meshes(self) -> None:
        """Object-frame meshes, the car material table and per-agent class / track ids."""
        n_agents = len(self.agents)
        self.meshes: list[Mesh | None] = [None] * n_agents
        self.car_table = np.zeros((n_agents, 16))
        self.heights = np.array([a.size[2] for a in self.agents])
        self.colours = np.array([a.colour for a in self.agents], dtype=np.float32)
        self.is_car = np.array([a.kind == "car" for a in self.agents])
        self.is_person = np.array([a.kind == "person" for a in self.agents])
        self.moving = np.array([a.kind != "ego" and a.speed > 0 for a in self.agents])
        for i, a in enumerate(self.agents):
            if isinstance(a.shape, CarShape):
                mesh_v, n_body = car_vehicle_mesh(a.shape)
                self.meshes[i] = vehicle_to_object(mesh_v, a.shape.height)
                self.car_table[i] = car_row(a.shape, a.colour, n_body)
            elif a.kind == "person":
                self.meshes[i] = person_mesh(a.shape)
        # object-frame boxes (min, max corner) of the meshes: which rays may hit an object
        self.mesh_bounds = np.zeros((n_agents, 2, 3))
        for i, mesh in enumerate(self.meshes):
            if mesh is not None:
                self.mesh_bounds[i] = mesh.vertices.min(0), mesh.vertices.max(0)
        # track ids: objects that are ever near the ego camera, numbered in agent order
        self.track_id = np.full(n_agents, -1)
        cam = self.T_m_c[:, :3, 3]
        pos = self.traj.T_m_o[:, :, :3, 3]
        near = (np.linalg.norm(pos - cam[None], axis=-1) < RENDER_RADIUS) & self.traj.active
        near[0] = False  # the ego car
        self.near = near
        ids = np.flatnonzero(near.any(axis=1))
        self.track_id[ids] = np.arange(len(ids))

    def moving_objects(self, n: int) -> MovingObjects:
        """The moving objects near the ego car at state ``n``, for ray casting (parked cars
        are part of the static scene)."""
        idx = np.array([i for i in np.flatnonzero(self.near[:, n] & self.moving) if self.meshes[i] is not None],
                       dtype=np.int64)
        return MovingObjects(idx, self.traj.T_m_o[idx, n], [self.object_scenes[a] for a in idx],
                             self.mesh_bounds[idx])

    def object_pose(self, a: int, n: int) -> np.ndarray:
        """``T_m_o`` of agent ``a`` as placed in the ray-casting scenes at state ``n`` (parked
        cars stay where the static scene holds them)."""
        return self.traj.T_m_o[a, n if self.moving[a] else 0]

    @property
    def T_c_velo(self) -> np.ndarray:
        return self.calib.T_c_velo
