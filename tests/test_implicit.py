"""culling="implicit": conservative three_pass whose box test also sees the isosurfaces' enclosed
occluder boxes. On a salt body with horizons and a slice it gives the unculled image bit for bit
from any camera (inside the salt and its bounding box too, where the occluders are switched off), and culls the
isosurface's back where the first set's depth leaves gaps in front of the salt."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc

W, H = 320, 256
N = 48  # samples per axis of the salt volume


def salt_volume() -> gc.Volume:
    """A lumpy salt body (values > 0 inside, isovalue 0) in a 48^3 volume over
    x, y in [0, 1000], z in [-1000, 0], well inside the volume's box."""
    c = np.linspace(0.0, 1.0, N)
    z, y, x = c[:, None, None], c[None, :, None], c[None, None, :]
    r = np.sqrt((x - 0.5) ** 2 + (y - 0.5) ** 2 + ((z - 0.45) / 1.3) ** 2)
    wobble = 0.03 * np.sin(9 * x) * np.cos(7 * y) + 0.02 * np.sin(11 * z)
    vals = (0.26 + wobble - r).astype(np.float32)
    return gc.Volume(vals, origin=(0.0, 0.0, -1000.0), spacing=(1000 / (N - 1),) * 3)


def salt_scene() -> tuple[gc.Scene, int]:
    """The salt (32 tiles), a horizon above part of it, one below all of it, one beside it, and a
    slice through the volume's middle."""
    s = gc.Scene()
    vol = salt_volume()
    salt = s.add_isosurface(vol, 0.0, tiles=32, color=(0.9, 0.9, 0.9))
    g = np.linspace(-500.0, 1500.0, 41)
    xx, yy = np.meshgrid(g, g)
    above = np.where(xx < 300.0, -80.0 + 0.02 * yy, np.nan)
    s.add_heightfield(above, origin=(-500.0, -500.0), spacing=(50.0, 50.0), tiles=(4, 4))
    s.add_heightfield(-950.0 + 0.03 * xx, origin=(-500.0, -500.0), spacing=(50.0, 50.0), tiles=(4, 4))
    beside = np.where(xx > 1000.0, -500.0 + 0.05 * yy, np.nan)
    s.add_heightfield(beside, origin=(-500.0, -500.0), spacing=(50.0, 50.0), tiles=(4, 4))
    s.add_slice(vol, axis=1, index=N // 2)
    return s, salt


CAMERAS = {
    "above": ((600.0, 300.0, 2500.0), (500.0, 500.0, -500.0)),
    "beside": ((3200.0, 900.0, -400.0), (500.0, 500.0, -500.0)),
    "below": ((400.0, 700.0, -3500.0), (500.0, 500.0, -500.0)),
    "oblique": ((-1800.0, -1500.0, 900.0), (500.0, 500.0, -500.0)),
    # Inside the salt's bounding box (beside the body) and inside the body: no occluders.
    "inside_bbox": ((280.0, 280.0, -300.0), (500.0, 500.0, -500.0)),
    "inside_salt": ((500.0, 480.0, -450.0), (900.0, 500.0, -450.0)),
}
INSIDE = ("inside_bbox", "inside_salt")


def camera(name: str) -> gc.Camera:
    eye, target = CAMERAS[name]
    return gc.Camera.look_at(eye, target, up=(0.0, 0.0, 1.0), fov_y=40.0)


@pytest.fixture(scope="module")
def scene() -> tuple[gc.Scene, int]:
    return salt_scene()


@pytest.fixture(scope="module")
def renderer() -> gc.Renderer:
    return gc.Renderer(W, H)


def test_implicit_is_registered():
    assert "implicit" in gc.CULLING_MODES


@pytest.mark.parametrize("view", list(CAMERAS))
@pytest.mark.parametrize("prepass_scale", [None, 0.125])
def test_implicit_equals_none(scene, renderer, view, prepass_scale):
    s, salt = scene
    cam = camera(view)
    none = renderer.render(s, cam, culling="none")
    imp = renderer.render(s, cam, culling="implicit", pixel_threshold=0, prepass_scale=prepass_scale)
    np.testing.assert_array_equal(imp.image, none.image)
    np.testing.assert_array_equal(imp.depth, none.depth)
    missed = (none.tile_pixels > 0) & ~imp.tile_drawn
    assert not missed.any()
    used = imp.stats["implicit_objects"]
    assert used == (0 if view in INSIDE else 1)
    assert (imp.stats["implicit_occluder_boxes"] > 0) == (used > 0)


def iso_triangles(s: gc.Scene, salt: int, res: gc.RenderResult) -> int:
    t = s.tile_table()
    on = res.tile_drawn & (t["object"] == salt)
    return int(t["tris_fine"][on].sum())


def test_implicit_culls_more_of_the_salt_than_three_pass(scene, renderer):
    """From the oblique view the first set's depth leaves gaps in front of the salt's inside (pixels
    where the prepass did not choose the front tile), through which three_pass's box test sees some
    of the salt's back tiles; the occluder boxes close them. (Measured on lavapipe: 6976 isosurface
    triangles unculled, 3270 three_pass, 3052 implicit. The boxes never add depth where the first
    set drew the front surface, so in most views the two draw the same.)"""
    s, salt = scene
    cam = camera("oblique")
    tp = renderer.render(s, cam, culling="three_pass", pixel_threshold=0)
    imp = renderer.render(s, cam, culling="implicit", pixel_threshold=0)
    none = renderer.render(s, cam, culling="none")
    np.testing.assert_array_equal(imp.image, none.image)
    assert iso_triangles(s, salt, imp) < iso_triangles(s, salt, tp) < iso_triangles(s, salt, none)
    assert imp.stats["triangles_drawn"] < tp.stats["triangles_drawn"]


def test_scenes_read_from_bytes_have_no_occluders(scene, renderer):
    s, _ = scene
    back = gc.Scene.from_bytes(s.to_bytes())
    res = renderer.render(back, camera("beside"), culling="implicit", pixel_threshold=0)
    assert res.stats["implicit_objects"] == 0
    np.testing.assert_array_equal(res.image, renderer.render(back, camera("beside"), culling="none").image)


def blob_scene(rng: np.random.Generator, trial: int) -> gc.Scene:
    """A random isosurface of a few Gaussian blobs with a little noise in a 24^3 volume (every third
    with NaN samples; every other one enclosing the low side), under a rough plane."""
    c = np.linspace(0.0, 1.0, 24)
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    v = np.zeros_like(x)
    for _ in range(4):
        p, s = rng.uniform(0.3, 0.7, 3), rng.uniform(0.06, 0.12)
        v += np.exp(-((x - p[0]) ** 2 + (y - p[1]) ** 2 + (z - p[2]) ** 2) / (2 * s * s))
    v += 0.02 * rng.standard_normal(v.shape)
    if trial % 3 == 0:
        v[rng.random(v.shape) < 0.002] = np.nan
    iso = rng.uniform(0.3, 0.8)
    if trial % 2:
        v, iso = 1.5 - v, 1.5 - iso
    scene = gc.Scene()
    scene.add_isosurface(gc.Volume(v.astype(np.float32), origin=(0, 0, 0), spacing=(1, 1, 1)), iso, tiles=16)
    scene.add_heightfield(20.0 + rng.normal(0.0, 1.0, (9, 9)), origin=(-4, -4), spacing=(4, 4))
    return scene


def test_random_isosurfaces_from_random_cameras_equal_none():
    """Blobs, NaN samples, both sides, perspective and orthographic cameras near and far (some
    inside the surface's bounding box): the image and depth are none's, and the occluders are used
    in most frames."""
    rng = np.random.default_rng(7)
    r = gc.Renderer(160, 128)
    used = frames = 0
    for trial in range(8):
        scene = blob_scene(rng, trial)
        for k in range(6):
            d = rng.normal(size=3)
            eye = np.array([12.0, 12.0, 12.0]) + d / np.linalg.norm(d) * rng.uniform(6, 40)
            ortho = dict(projection="orthographic", ortho_height=30.0) if k % 3 == 2 else {}
            cam = gc.Camera.look_at(eye, (12 + rng.normal(0, 3), 12, 12), fov_y=rng.uniform(20, 60), **ortho)
            a = r.render(scene, cam, culling="none")
            b = r.render(scene, cam, culling="implicit", pixel_threshold=0)
            np.testing.assert_array_equal(b.image, a.image, err_msg=f"{trial} {k}")
            np.testing.assert_array_equal(b.depth, a.depth, err_msg=f"{trial} {k}")
            used += b.stats["implicit_objects"]
            frames += 1
    assert used > frames // 2
