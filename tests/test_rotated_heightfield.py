"""Height fields on rotated grids (issue 16): ``add_heightfield(..., rotation=, yflip=)``.

What is checked:
- a rotated (30°, -110°, 90°, 180°) and yflipped field with a hole renders, in every culling mode,
  with the same coverage and depth, pixel for pixel, as the same surface given to ``add_mesh`` with
  its vertices rotated by numpy (rendered unculled), from a top-down and a low oblique view;
- every culling mode gives the unculled image of the rotated field (three_pass in its exact
  setting: coarse_factor 1, pixel_threshold 0), and horizon culling still culls on a rotated ridge;
- 90° and 180° put the samples exactly where a quarter / half turn does (no 6e-17 residue);
- yflip: rows run towards -y in the grid's frame; a non-bool yflip (xtgeo's 1 / -1) and a
  non-finite rotation are InputErrors naming the argument.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import geocull as gc

W, H = 96, 72


@pytest.fixture(scope="module")
def renderer() -> gc.Renderer:
    return gc.Renderer(W, H)


def cos_sin(deg: float) -> tuple[float, float]:
    """Exact at multiples of 90°, as the core."""
    r = deg % 360.0
    exact = {0.0: (1.0, 0.0), 90.0: (0.0, 1.0), 180.0: (-1.0, 0.0), 270.0: (0.0, -1.0)}
    return exact.get(r, (math.cos(math.radians(deg)), math.sin(math.radians(deg))))


def rotated_mesh(z, origin, spacing, deg, yflip):
    """The height field's triangles as a mesh: grid-frame positions (i*dx, ±j*dy) turned by numpy
    about the origin; unreferenced (hole) vertices dropped."""
    v, f = gc.data.heightfield_mesh(z, (0.0, 0.0), spacing)
    u, w = v[:, 0], v[:, 1] * (-1.0 if yflip else 1.0)
    c, s = cos_sin(deg)
    v = np.stack([origin[0] + (c * u - s * w), origin[1] + (s * u + c * w), v[:, 2]], axis=1)
    used = np.unique(f)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def surface(n=41, seed=0):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    z = 6.0 * np.sin(x / 7.0) * np.cos(y / 9.0) + 0.3 * rng.standard_normal((n, n))
    z[14:19, 20:27] = np.nan  # an interior hole
    return z


ORIGIN, SPACING = (1000.0, 2000.0), (2.5, 2.0)


def views(z, origin, spacing, deg, yflip):
    """A top-down orthographic view and a low oblique perspective view of the turned field."""
    ny, nx = z.shape
    c, s = cos_sin(deg)
    u, w = 0.5 * (nx - 1) * spacing[0], 0.5 * (ny - 1) * spacing[1] * (-1 if yflip else 1)
    cx, cy = origin[0] + c * u - s * w, origin[1] + s * u + c * w
    ext = max(nx * spacing[0], ny * spacing[1])
    top = gc.Camera.look_at((cx, cy, 200.0), (cx, cy, 0.0), up=(0, 1, 0), projection="orthographic",
                            ortho_height=1.6 * ext)
    low = gc.Camera.look_at((cx - 0.9 * ext, cy - 0.5 * ext, 25.0), (cx, cy, 0.0), fov_y=50.0)
    return top, low


@pytest.mark.parametrize("deg,yflip", [(30.0, False), (30.0, True), (-110.0, False), (90.0, True), (180.0, False)])
def test_rotated_field_renders_like_the_rotated_mesh(renderer, deg, yflip):
    z = surface()
    a, b = gc.Scene(), gc.Scene()
    a.add_heightfield(z, ORIGIN, SPACING, tiles=(4, 4), rotation=deg, yflip=yflip)
    b.add_mesh(*rotated_mesh(z, ORIGIN, SPACING, deg, yflip))
    assert a.n_triangles == b.n_triangles
    for cam in views(z, ORIGIN, SPACING, deg, yflip):
        rb = renderer.render(b, cam)
        for mode in gc.CULLING_MODES:  # the mesh unculled against the height field in every mode
            ra = renderer.render(a, cam, culling=mode, pixel_threshold=0)
            assert ra.coverage.sum() > 0.1 * W * H
            np.testing.assert_array_equal(ra.coverage, rb.coverage, err_msg=mode)
            np.testing.assert_allclose(ra.depth[ra.coverage], rb.depth[rb.coverage], rtol=1e-5, err_msg=mode)


@pytest.mark.parametrize("deg,yflip", [(30.0, False), (-110.0, True), (90.0, False), (180.0, True)])
def test_every_culling_mode_gives_the_unculled_image(renderer, deg, yflip):
    z = surface(seed=1)
    s = gc.Scene()
    s.add_heightfield(z, ORIGIN, SPACING, tiles=(5, 5), rotation=deg, yflip=yflip)
    for cam in views(z, ORIGIN, SPACING, deg, yflip):
        ref = renderer.render(s, cam, culling="none")
        for mode in gc.CULLING_MODES:
            res = renderer.render(s, cam, culling=mode, pixel_threshold=0)
            np.testing.assert_array_equal(res.image, ref.image, err_msg=mode)
            np.testing.assert_array_equal(res.depth, ref.depth, err_msg=mode)


@pytest.mark.parametrize("deg,yflip", [(30.0, False), (145.0, True)])
def test_horizon_still_culls_a_rotated_ridge(renderer, deg, yflip):
    """A ridge across the grid's row 20 hides the valley behind it, seen low from the front (the
    grid's -y side, turned with the grid): horizon culls tiles and the image is the unculled one."""
    n = 65
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    z = 12.0 * np.exp(-(((y - 20.0) / 4.0) ** 2)) + 0.3 * np.sin(0.7 * x) * np.cos(0.5 * y) + 0.3
    origin = (5000.0, -300.0)
    s = gc.Scene()
    s.add_heightfield(z, origin, (1.0, 1.0), tiles=(8, 8), rotation=deg, yflip=yflip)
    c, sn = cos_sin(deg)
    sy = -1.0 if yflip else 1.0

    def world(u, w):  # grid frame -> world
        return origin[0] + c * u - sn * w * sy, origin[1] + sn * u + c * w * sy

    cam = gc.Camera.look_at((*world(32.0, -20.0), 6.0), (*world(32.0, 40.0), 5.5), fov_y=60.0)
    ref = renderer.render(s, cam, culling="none")
    hz = renderer.render(s, cam, culling="horizon")
    oracle = renderer.render(s, cam, culling="oracle")
    assert not (oracle.tile_drawn & ~hz.tile_drawn).any()
    assert hz.stats["nodes_culled"] > 0 and hz.tile_drawn.sum() < 0.75 * s.n_tiles
    np.testing.assert_array_equal(hz.image, ref.image)
    np.testing.assert_array_equal(hz.depth, ref.depth)


def test_quarter_and_half_turns_are_exact():
    z = np.arange(6.0).reshape(2, 3)  # 3 columns, 2 rows
    s = gc.Scene()
    for deg, yflip, want in [
        (90.0, False, {(100.0, 200.0): 0.0, (100.0, 220.0): 2.0, (95.0, 200.0): 3.0, (95.0, 220.0): 5.0}),
        (180.0, False, {(80.0, 200.0): 2.0, (100.0, 195.0): 3.0, (80.0, 195.0): 5.0}),
        (-90.0, False, {(100.0, 180.0): 2.0, (105.0, 200.0): 3.0}),
        (450.0, True, {(100.0, 220.0): 2.0, (105.0, 200.0): 3.0}),
        (0.0, True, {(120.0, 200.0): 2.0, (100.0, 195.0): 3.0}),
    ]:
        oid = s.add_heightfield(z, (100.0, 200.0), (10.0, 5.0), rotation=deg, yflip=yflip)
        v, _ = s.geometry(oid)
        got = {(float(p[0]), float(p[1])): float(p[2]) for p in v}
        for xy, h in want.items():
            assert got.get(xy) == h, (deg, yflip, xy, sorted(got))


def test_yflip_and_rotation_arguments():
    z = np.zeros((3, 3))
    s = gc.Scene()
    up = s.add_heightfield(z, (0.0, 0.0), (1.0, 1.0))
    down = s.add_heightfield(z, (0.0, 0.0), (1.0, 1.0), yflip=True)
    assert s.geometry(up)[0][:, 1].min() == 0.0 and s.geometry(up)[0][:, 1].max() == 2.0
    assert s.geometry(down)[0][:, 1].min() == -2.0 and s.geometry(down)[0][:, 1].max() == 0.0
    with pytest.raises(gc.InputError, match=r"^yflip: -1 is not a bool \(xtgeo's yflip=-1 is yflip=True\)"):
        s.add_heightfield(z, yflip=-1)  # type: ignore[arg-type]
    with pytest.raises(gc.InputError, match=r"^yflip: 1 is not a bool"):
        s.add_heightfield(z, yflip=1)  # type: ignore[arg-type]
    for bad in (math.inf, math.nan):
        with pytest.raises(gc.InputError, match=r"^rotation is (inf|NaN); expected a finite angle"):
            s.add_heightfield(z, rotation=bad)
    with pytest.raises(gc.InputError, match=r"^rotation: '30' is not a real number"):
        s.add_heightfield(z, rotation="30")  # type: ignore[arg-type]
    assert len(s.object_ids()) == 2


@pytest.mark.parametrize("deg,yflip", [(0.0, False), (30.0, True), (90.0, False), (-200.0, True)])
def test_heightfield_mesh_is_the_same_surface(deg, yflip):
    """gc.data.heightfield_mesh(rotation=, yflip=, drop_holes=True) gives exactly the numpy-rotated
    mesh above (finite vertices only, so add_mesh takes it) and the height field's triangles."""
    z = surface(n=31, seed=3)
    v, f = gc.data.heightfield_mesh(z, ORIGIN, SPACING, rotation=deg, yflip=yflip, drop_holes=True)
    rv, rf = rotated_mesh(z, ORIGIN, SPACING, deg, yflip)
    np.testing.assert_array_equal(v, rv)
    np.testing.assert_array_equal(f, rf)
    s = gc.Scene()
    a = s.add_heightfield(z, ORIGIN, SPACING, rotation=deg, yflip=yflip)
    b = s.add_mesh(v, f)
    tri = lambda oid: np.sort(np.sort(s.geometry(oid)[0][s.geometry(oid)[1]], axis=1).reshape(len(f), -1), axis=0)  # noqa: E731
    np.testing.assert_allclose(tri(a), tri(b), atol=1e-6)
    with pytest.raises(gc.InputError, match=r"^vertices\[\d+, 2\] is NaN"):
        s.add_mesh(*gc.data.heightfield_mesh(z, ORIGIN, SPACING))  # the NaN samples kept without drop_holes


def test_pickled_rotated_fields_keep_their_frame(renderer):
    """A pickled scene keeps a field's rotation and yflip (horizon culling rebuilds its grid in that
    frame): the copy renders the same image with horizon culling."""
    import pickle

    z = surface(seed=4)
    s = gc.Scene()
    s.add_heightfield(z, ORIGIN, SPACING, tiles=(4, 4), rotation=-63.0, yflip=True)
    t = pickle.loads(pickle.dumps(s))
    for cam in views(z, ORIGIN, SPACING, -63.0, True):
        a, b = renderer.render(s, cam, culling="horizon"), renderer.render(t, cam, culling="horizon")
        np.testing.assert_array_equal(a.image, b.image)
        np.testing.assert_array_equal(a.tile_drawn, b.tile_drawn)
