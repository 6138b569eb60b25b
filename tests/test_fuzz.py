"""Property-based fuzzing of the public API: Scene.add_mesh / add_heightfield, Camera.look_at and
Renderer.render with random shapes, dtypes and values. Every call either succeeds or raises
geocull.InputError (never another exception, never a crash), and a successful render returns
arrays of the right shapes, dtypes and consistency.

GEOCULL_FUZZ_EXAMPLES (default 300) sets the number of examples; GEOCULL_FUZZ_RANDOM=1 draws new
examples on every run instead of the fixed, reproducible CI sequence.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import geocull as gc  # noqa: E402

W, H = 16, 16
EXAMPLES = int(os.environ.get("GEOCULL_FUZZ_EXAMPLES", "300"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=not os.environ.get("GEOCULL_FUZZ_RANDOM"),
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture, HealthCheck.data_too_large,
                           HealthCheck.filter_too_much],
)

# ----------------------------------------------------------------------------------- values

SPECIAL = [0.0, -0.0, 1.0, -1.0, 0.5, np.nan, np.inf, -np.inf, -999.25, 1e-320, 1e-45, 1e12, 1e13, 1e300, -1e300,
           450_000.0, 6_780_000.0, -2500.0, 2.0**31, 2.0**32]
floats = st.one_of(st.sampled_from(SPECIAL), st.floats(-100, 100), st.floats(allow_nan=True, allow_infinity=True))
small_ints = st.integers(-3, 40)
DTYPES = ["float64", "float32", "float16", "int64", "int32", "int8", "uint8", "uint64", "bool", "complex128",
          "object", "str", "datetime64[s]"]


@st.composite
def arrays(draw, shape=None, values=floats, kind="float"):
    """An array-like: mostly of a plausible shape and dtype, sometimes anything at all."""
    if shape is None or draw(st.integers(0, 9)) == 0:
        shape = tuple(draw(st.lists(st.integers(0, 5), min_size=0, max_size=3)))
    n = int(np.prod(shape)) if shape else 1
    if kind == "int":
        vals = draw(st.lists(st.one_of(small_ints, st.sampled_from([-1, 2**31, 2**40])), min_size=n, max_size=n))
        base = np.array(vals, dtype=np.int64).reshape(shape)
    else:
        vals = draw(st.lists(values, min_size=n, max_size=n))
        base = np.array(vals, dtype=np.float64).reshape(shape)
    dtype = draw(st.sampled_from([None] * 6 + DTYPES))
    if dtype is not None:
        with np.errstate(all="ignore"):
            if dtype == "object":
                base = base.astype(object)
            elif dtype == "str":
                base = base.astype(str)
            elif dtype == "datetime64[s]":
                base = np.zeros(shape, dtype)
            else:
                base = base.astype(dtype)
    form = draw(st.sampled_from(["array", "array", "list", "readonly", "strided", "fortran", "scalar"]))
    if form == "list":
        return base.tolist()
    if form == "readonly":
        base = base.copy()
        base.flags.writeable = False
    elif form == "strided" and base.ndim >= 1:
        big = np.repeat(base, 2, axis=0)
        base = big[::2]
    elif form == "fortran":
        base = np.asfortranarray(base)
    elif form == "scalar":
        return draw(st.one_of(floats, small_ints, st.none(), st.text(max_size=3)))
    return base


def vec(n):
    return st.one_of(st.tuples(*[floats] * n), arrays(shape=(n,)))


def grid_z():
    """Height fields: mostly small real grids with holes, sometimes junk."""

    @st.composite
    def good(draw):
        ny, nx = draw(st.integers(1, 7)), draw(st.integers(1, 7))
        z = np.array(draw(st.lists(st.floats(-50, 50), min_size=nx * ny, max_size=nx * ny))).reshape(ny, nx)
        mask = np.array(draw(st.lists(st.sampled_from([0, 0, 0, 1, 2]), min_size=nx * ny, max_size=nx * ny)))
        mask = mask.reshape(ny, nx)
        z[mask == 1] = np.nan
        z[mask == 2] = -999.25
        return z

    return st.one_of(good(), good(), good(), arrays(shape=(3, 4)))


def mesh_arrays():
    @st.composite
    def good(draw):
        n = draw(st.integers(0, 8))
        v = np.array(draw(st.lists(st.floats(-20, 20), min_size=3 * n, max_size=3 * n))).reshape(n, 3)
        m = draw(st.integers(0, 10))
        f = np.array(draw(st.lists(st.integers(-1, n), min_size=3 * m, max_size=3 * m)), np.int64).reshape(m, 3)
        if draw(st.sampled_from([True, True, True, False])) and n:
            f = np.clip(f, 0, n - 1)  # mostly valid indices
        return v, f

    return st.one_of(good(), good(), st.tuples(arrays(shape=(4, 3)), arrays(shape=(2, 3), kind="int")))


maybe = lambda s: st.one_of(st.none(), s)  # noqa: E731
numbers = st.one_of(floats, small_ints, st.sampled_from(["1", None, True, 1 + 2j]))


@pytest.fixture(scope="module")
def renderer(renderer_small):
    return renderer_small(W, H)


def call(f, *a, **kw):
    """f(*a, **kw), or None when it raised InputError; anything else fails the test."""
    try:
        return f(*a, **kw)
    except gc.InputError as e:
        assert str(e), "an InputError must say what is wrong"
        return None


def check_result(res, scene, cam=None):
    n = scene.n_tiles
    assert res.image.shape == (H, W, 4) and res.image.dtype == np.uint8
    assert res.depth.shape == (H, W) and res.depth.dtype == np.float32
    assert res.tile_pixels.shape == (n,) and res.tile_pixels.dtype == np.uint32
    assert res.tile_drawn.shape == (n,) and res.tile_drawn.dtype == bool
    assert not np.isnan(res.depth).any()
    # Distances from the eye: positive in perspective (the near plane is never at 0); an
    # orthographic view's eye may lie on a surface (its automatic near plane is then at 0).
    if cam is not None and cam.projection == "orthographic":
        assert (res.depth >= 0).all()
    else:
        assert (res.depth > 0).all()
    empty = np.isposinf(res.depth)
    assert (res.image[empty] == (0, 0, 0, 255)).all()
    assert (res.image[..., 3] == 255).all()
    assert res.stats["triangles_drawn"] <= res.stats["triangles_fine_total"] == scene.n_triangles
    assert np.isfinite(res.near) and 0 <= res.near < res.far  # orthographic near may be 0


@st.composite
def kwargs(draw, good, bad):
    """Keyword arguments: all plausible, then up to two of them replaced by junk (about half the
    calls get junk), so that successes and failures are both common."""
    kw = {k: draw(v) for k, v in good.items()}
    n_bad = draw(st.sampled_from([0, 0, 0, 1, 1, 2]))
    for k in draw(st.lists(st.sampled_from(sorted(bad)), min_size=n_bad, max_size=n_bad, unique=True)):
        kw[k] = draw(bad[k])
    return kw


unit = st.floats(0, 1)
HF_GOOD = {
    "z": grid_z(),
    "origin": st.sampled_from([(0.0, 0.0), (450_000.0, 6_780_000.0), (-5.0, 3.0)]),
    "spacing": st.tuples(st.floats(0.1, 10), st.floats(0.1, 10)),
    "tiles": st.tuples(st.integers(1, 3), st.integers(1, 3)),
    "coarse_factor": st.sampled_from([1.0, 2.0, 7.5]),
    "color": maybe(st.tuples(unit, unit, unit)),
    "null_value": maybe(st.just(-999.25)),
    "rotation": st.one_of(st.sampled_from([0.0, 30.0, 90.0, 180.0, -270.0]), st.floats(-720, 720)),
    "yflip": st.booleans(),
}
HF_BAD = {
    "z": arrays(shape=(3, 4)),
    "origin": vec(2),
    "spacing": vec(2),
    "tiles": st.one_of(st.tuples(small_ints, small_ints), arrays(shape=(2,), kind="int")),
    "coarse_factor": numbers,
    "color": vec(3),
    "null_value": numbers,
    "name": st.one_of(small_ints, st.text(max_size=3)),
    "rotation": numbers,
    "yflip": st.one_of(st.sampled_from([1, -1, 0, None, "yes"]), st.booleans()),
}
MESH_GOOD = {
    "tiles": maybe(st.integers(1, 4)),
    "coarse_factor": st.sampled_from([1.0, 2.0]),
    "color": maybe(st.tuples(unit, unit, unit)),
    "kind": st.sampled_from(["fault", "mesh"]),
}
MESH_BAD = {
    "tiles": maybe(small_ints),
    "coarse_factor": numbers,
    "color": vec(3),
    "kind": st.one_of(small_ints, st.none()),
}
CAM_GOOD = {
    "eye": st.tuples(st.floats(-30, 30), st.floats(-30, 30), st.floats(-30, 30)),
    "target": st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
    "up": st.one_of(st.just((0.0, 0.0, 1.0)), st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1))),
    "fov_y": st.floats(5, 150),
    "near": maybe(st.floats(0.01, 5)),
    "far": st.none(),
    "projection": st.sampled_from(["perspective", "orthographic"]),
    "ortho_height": maybe(st.floats(1, 80)),
    "z_scale": st.sampled_from([1.0, 5.0, 0.5]),
}
CAM_BAD = {
    "eye": vec(3), "target": vec(3), "up": vec(3), "fov_y": numbers, "near": numbers, "far": numbers,
    "projection": st.one_of(st.text(max_size=4), small_ints), "ortho_height": numbers, "z_scale": numbers,
}
RENDER_GOOD = {
    "culling": st.sampled_from(gc.CULLING_MODES),
    "pixel_threshold": st.sampled_from([0, 10, 2.5]),
    "prepass_scale": st.sampled_from([1.0, 0.5, 0.1]),
}
RENDER_BAD = {
    "culling": st.one_of(st.sampled_from(["Oracle", "", "none "]), small_ints, st.none()),
    "pixel_threshold": numbers,
    "prepass_scale": numbers,
}


@FUZZ
@given(
    hf=st.lists(kwargs(HF_GOOD, HF_BAD), max_size=2),
    meshes=st.lists(st.tuples(mesh_arrays(), kwargs(MESH_GOOD, MESH_BAD)), max_size=2),
    cam_kw=kwargs(CAM_GOOD, CAM_BAD),
    render_kw=kwargs(RENDER_GOOD, RENDER_BAD),
    ops=st.lists(st.tuples(st.sampled_from(["translate", "set_visible", "set_color", "remove"]),
                           st.one_of(st.integers(0, 1), st.integers(0, 1), small_ints),
                           st.one_of(st.tuples(unit, unit, unit), vec(3))),
                 max_size=2),
)
def test_fuzz_public_api(renderer, hf, meshes, cam_kw, render_kw, ops):
    scene = gc.Scene()
    for kw in hf:
        call(scene.add_heightfield, **kw)
    for (v, f), kw in meshes:
        call(scene.add_mesh, v, f, **kw)
    for op, oid, val in ops:
        if op == "translate":
            call(scene.translate, oid, val)
        elif op == "set_visible":
            call(scene.set_visible, oid, bool(oid % 2))
        elif op == "set_color":
            call(scene.set_color, oid, val)
        else:
            call(scene.remove, oid)
    assert len(scene.tile_table()) == scene.n_tiles
    cam = call(gc.Camera.look_at, **cam_kw)
    if cam is None:
        cam = gc.Camera.look_at((3.0, -8.0, 12.0), (2.0, 2.0, 0.0))
    res = call(renderer.render, scene, cam, **render_kw)
    if res is not None:
        check_result(res, scene, cam)
    # The same scene and camera always render in every mode with valid options.
    for m in gc.CULLING_MODES:
        check_result(renderer.render(scene, cam, culling=m, pixel_threshold=0), scene, cam)


@FUZZ
@given(z=grid_z(), tiles=st.tuples(st.integers(1, 4), st.integers(1, 4)), cf=st.sampled_from([1.0, 2.0, 7.5]),
       elev=st.floats(5, 90), az=st.floats(0, 360),
       rotation=st.one_of(st.just(0.0), st.sampled_from([90.0, 180.0]), st.floats(-360, 360)), yflip=st.booleans())
def test_fuzz_valid_heightfields_render_the_same_in_every_mode(renderer, z, tiles, cf, elev, az, rotation, yflip):
    """Valid height fields (holes, nulls, tiny grids, rotated and yflipped grids) seen from random
    directions: every mode gives the unculled image when nothing may be culled (threshold 0, coarse
    proxies only for three_pass)."""
    scene = gc.Scene()
    if call(scene.add_heightfield, z, tiles=tiles, coarse_factor=1.0, null_value=-999.25, rotation=rotation,
            yflip=yflip) is None:
        return
    ny, nx = np.shape(z)  # z may be a list (the add succeeded, so it is 2-D)
    t, sy = np.radians(rotation), (-1.0 if yflip else 1.0)
    c = np.array([nx / 2 * np.cos(t) - sy * ny / 2 * np.sin(t), nx / 2 * np.sin(t) + sy * ny / 2 * np.cos(t), 0.0])
    e, a = np.radians(elev), np.radians(az)
    eye = c + 30 * np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    cam = gc.Camera.look_at(eye, c, fov_y=50)
    ref = renderer.render(scene, cam, culling="none")
    check_result(ref, scene)
    for m in gc.CULLING_MODES[1:]:
        res = renderer.render(scene, cam, culling=m, pixel_threshold=0)
        check_result(res, scene)
        np.testing.assert_array_equal(res.image, ref.image, err_msg=m)
        np.testing.assert_array_equal(res.depth, ref.depth, err_msg=m)
    res = renderer.render(scene, cam, culling="three_pass", pixel_threshold=0, prepass_scale=0.5)
    check_result(res, scene)


def test_an_orthographic_eye_on_a_plane_sees_it_at_distance_zero(renderer_small):
    # Found by test_fuzz_public_api: the automatic near plane of an orthographic view is at the
    # eye (0), so a plane through the eye is drawn at distance 0 (never negative, never NaN).
    s = gc.Scene()
    s.add_heightfield(np.zeros((2, 2)))
    cam = gc.Camera.look_at((0, 0, 0), (0, 0, 1), up=(0, 0, 1), fov_y=5, projection="orthographic")
    res = renderer_small(16, 16).render(s, cam)
    check_result(res, s, cam)
    assert res.coverage.sum() > 0 and res.depth[res.coverage].max() == 0.0
