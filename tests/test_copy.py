"""copy.copy / copy.deepcopy of a Scene are independent scenes; Scene, Camera and Volume pickle
(to ship them to other processes) and come back rendering exactly the same images."""

from __future__ import annotations

import copy
import pickle
import subprocess
import sys

import numpy as np
import pytest

import geocull as gc

W, H = 48, 40


@pytest.fixture(scope="module")
def r():
    return gc.Renderer(W, H)


def _scene():
    s = gc.Scene()
    y, x = np.mgrid[0:17, 0:21]
    z = np.sin(x / 3.0) * 20 + np.cos(y / 4.0) * 10 - 2500.0
    z[5, 6] = np.nan
    s.add_heightfield(z, origin=(451000.0, 6780000.0), spacing=(25.0, 25.0), tiles=(3, 2), coarse_factor=4,
                      name="top", color=(0.9, 0.5, 0.2))
    v = np.array([[451000, 6780000, -2600], [451500, 6780000, -2400], [451000, 6780400, -2450.0]])
    s.add_mesh(v, [[0, 1, 2]], kind="fault", name="f1")
    s.add_heightfield(z - 60.0, origin=(451000.0, 6780000.0), spacing=(25.0, 25.0), tiles=(2, 2))
    s.translate(1, (10.0, 0.0, 5.0))
    s.set_visible(2, False)
    return s


def _cam():
    return gc.Camera.look_at((450600.0, 6779500.0, -1900.0), (451250.0, 6780200.0, -2500.0), fov_y=50.0)


def _same_scene(a: gc.Scene, b: gc.Scene):
    assert a.object_ids() == b.object_ids() and a.origin == b.origin
    for i in a.object_ids():
        assert a.object_info(i) == b.object_info(i)
        for x, y in zip(a.geometry(i), b.geometry(i), strict=True):
            np.testing.assert_array_equal(x, y)
    ta, tb = a.tile_table(), b.tile_table()
    assert ta.dtype == tb.dtype
    for k in ta.dtype.names or ():
        np.testing.assert_array_equal(ta[k], tb[k])


@pytest.mark.parametrize("how", ["copy", "deepcopy", "method"])
def test_copies_are_independent_scenes(r, how):
    s, cam = _scene(), _cam()
    before = r.render(s, cam).image
    c = {"copy": copy.copy, "deepcopy": copy.deepcopy, "method": gc.Scene.copy}[how](s)
    assert c is not s and c._s is not s._s
    _same_scene(s, c)
    np.testing.assert_array_equal(r.render(c, cam).image, before)
    # edits of the original do not reach the copy (nor the renderer's upload of it), and back
    s.remove(0)
    s.set_color(1, (0.1, 0.9, 0.1))
    s.add_heightfield(np.full((5, 5), -2300.0), origin=(451000.0, 6780000.0), spacing=(100.0, 100.0))
    edited = r.render(s, cam).image
    assert not np.array_equal(edited, before)
    np.testing.assert_array_equal(r.render(c, cam).image, before)
    c.translate(1, (0.0, 0.0, 50.0))
    np.testing.assert_array_equal(r.render(s, cam).image, edited)
    # a copy's new objects get the ids the original would give
    assert c.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]) == 3


@pytest.mark.parametrize("protocol", [2, pickle.HIGHEST_PROTOCOL])
def test_pickled_scene_camera_renders_the_same(r, protocol):
    s, cam = _scene(), _cam()
    s2 = pickle.loads(pickle.dumps(s, protocol=protocol))
    cam2 = pickle.loads(pickle.dumps(cam, protocol=protocol))
    _same_scene(s, s2)
    for k in ("eye", "target", "up", "fov_y", "near", "far", "projection", "ortho_height", "z_scale"):
        assert getattr(cam2, k) == getattr(cam, k)
    for culling in ("none", "three_pass", "horizon"):
        a, b = r.render(s, cam, culling=culling), r.render(s2, cam2, culling=culling)
        np.testing.assert_array_equal(a.image, b.image)
        np.testing.assert_array_equal(a.depth, b.depth)
        np.testing.assert_array_equal(a.tile_pixels, b.tile_pixels)
    assert gc.Scene.from_bytes(s.to_bytes()).to_bytes() == s.to_bytes()
    ortho = gc.Camera.look_at((0, 0, 10.0), (0, 0, 0), up=(0, 1, 0), projection="orthographic", ortho_height=3.0,
                              near=1.0, far=20.0, z_scale=2.0)
    o2 = copy.deepcopy(pickle.loads(pickle.dumps(ortho)))
    assert (o2.projection, o2.ortho_height, o2.near, o2.far, o2.z_scale) == ("orthographic", 3.0, 1.0, 20.0, 2.0)
    with pytest.raises(gc.InputError, match="^data"):
        gc.Scene.from_bytes(s.to_bytes()[:-3])


def test_pickled_volume_renders_the_same(r):
    n = 20
    c = np.linspace(-1, 1, n)
    vals = np.sqrt(c[:, None, None] ** 2 + c[None, :, None] ** 2 + c[None, None, :] ** 2) + 1e8
    vals[3, 4, 5] = np.nan
    v = gc.Volume(vals, origin=(-1, -1, -1), spacing=(2 / (n - 1),) * 3)
    v2 = pickle.loads(pickle.dumps(v))
    assert (v2.shape, v2.origin, v2.spacing, v2.offset) == (v.shape, v.origin, v.spacing, v.offset)
    assert copy.copy(v) is v and copy.deepcopy(v) is v  # immutable
    cam = gc.Camera.look_at((3.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    a, b = r.render_isosurface(v, 1e8 + 0.6, cam), r.render_isosurface(v2, 1e8 + 0.6, cam)
    assert a.stats["surface_triangles"] > 0
    np.testing.assert_array_equal(a.image, b.image)
    for d in range(v.max_depth() + 1):
        np.testing.assert_array_equal(v.nodes(d)["min"], v2.nodes(d)["min"])


def test_a_pickled_scene_renders_the_same_in_another_process(r, tmp_path):
    s, cam = _scene(), _cam()
    (tmp_path / "job.pkl").write_bytes(pickle.dumps((s, cam)))
    code = (
        "import pickle, sys, numpy as np, geocull as gc\n"
        "s, cam = pickle.loads(open(sys.argv[1], 'rb').read())\n"
        f"np.save(sys.argv[2], gc.Renderer({W}, {H}).render(s, cam).image)\n"
    )
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path / "job.pkl"), str(tmp_path / "img.npy")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-2000:]
    np.testing.assert_array_equal(np.load(tmp_path / "img.npy"), r.render(s, cam).image)
