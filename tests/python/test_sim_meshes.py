"""The procedural car family, pedestrians, the PLY and 16-bit PNG codecs."""

import zlib

import numpy as np
import pytest

from twistslam.sim.car_mesh import car_mesh, sample_car_shape
from twistslam.sim.mesh import read_ply, write_ply
from twistslam.sim.person_mesh import person_mesh, sample_person_shape
from twistslam.datasets.png16 import read_png16, write_png16


def test_car_meshes_are_watertight_and_fill_their_box():
    rng = np.random.default_rng(0)
    sizes = []
    for _ in range(30):
        shape = sample_car_shape(rng)
        mesh = car_mesh(shape)
        assert mesh.is_watertight()
        assert mesh.signed_volume() > 0.4 * shape.length * shape.width * shape.height
        lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
        # object frame: x = length, y = height (down), z = width; origin at the box centre
        np.testing.assert_allclose(hi - lo, [shape.length, shape.height, shape.width], atol=2e-3)
        np.testing.assert_allclose(hi + lo, 0.0, atol=2e-3)
        sizes.append((shape.length, shape.width, shape.height))
    sizes = np.array(sizes)
    assert sizes[:, 0].min() < 3.8 and sizes[:, 0].max() > 4.5  # spans real car sizes
    assert sizes[:, 2].max() - sizes[:, 2].min() > 0.25


def test_car_components_do_not_intersect():
    """Body and wheels are disjoint: every wheel vertex lies outside the body's arches."""
    from twistslam.sim.car_mesh import _bottom, car_vehicle_mesh

    shape = sample_car_shape(np.random.default_rng(1))
    mesh, n_body = car_vehicle_mesh(shape)
    wheel_vertices = np.unique(mesh.faces[n_body:].ravel())
    v = mesh.vertices[wheel_vertices]
    assert (v[:, 2] < _bottom(shape, v[:, 0]) + 1e-6).all()


def test_person_mesh():
    shape = sample_person_shape(np.random.default_rng(2))
    mesh = person_mesh(shape)
    assert mesh.is_watertight() and mesh.signed_volume() > 0
    lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
    np.testing.assert_allclose((hi - lo)[[0, 2, 1]], shape.size, atol=2e-3)


def test_ply_round_trip(tmp_path):
    mesh = car_mesh(sample_car_shape(np.random.default_rng(3)))
    write_ply(tmp_path / "car.ply", mesh)
    back = read_ply(tmp_path / "car.ply")
    np.testing.assert_allclose(back.vertices, mesh.vertices, atol=1e-6)
    np.testing.assert_array_equal(back.faces, mesh.faces)


@pytest.mark.parametrize("shape", [(5, 7), (4, 6, 3)])
def test_png16_round_trip(tmp_path, shape):
    values = np.random.default_rng(0).integers(0, 2**16, size=shape, dtype=np.uint16)
    write_png16(tmp_path / "a.png", values)
    np.testing.assert_array_equal(read_png16(tmp_path / "a.png"), values)


def test_png16_reads_filtered_rows(tmp_path):
    """Files from other tools use PNG row filters; the reader undoes all five."""
    import struct

    values = np.random.default_rng(1).integers(0, 2**16, size=(5, 4, 3), dtype=np.uint16)
    rows = values.astype(">u2").reshape(5, -1).view(np.uint8).astype(np.int32)
    bpp = 6
    raw = []
    prev = np.zeros(rows.shape[1], np.int32)
    for y, kind in enumerate([0, 1, 2, 3, 4]):
        line = rows[y]
        left = np.concatenate([np.zeros(bpp, np.int32), line[:-bpp]])
        up_left = np.concatenate([np.zeros(bpp, np.int32), prev[:-bpp]])
        if kind == 1:
            f = line - left
        elif kind == 2:
            f = line - prev
        elif kind == 3:
            f = line - (left + prev) // 2
        elif kind == 4:
            p = left + prev - up_left
            pa, pb, pc = np.abs(p - left), np.abs(p - prev), np.abs(p - up_left)
            f = line - np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, prev, up_left))
        else:
            f = line
        raw.append(bytes([kind]) + (f % 256).astype(np.uint8).tobytes())
        prev = line

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 5, 16, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"".join(raw))) + chunk(b"IEND", b""))
    (tmp_path / "f.png").write_bytes(data)
    np.testing.assert_array_equal(read_png16(tmp_path / "f.png"), values)
