"""Hostile numeric input (issue 39): byte order, infinities, coordinate limits and messages that
name the user's own argument and its first bad element."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc


def _ball(n=12, base=1e8 + 0.5):
    """A float64 volume whose values are ``base`` plus the distance from the grid's centre."""
    c = np.linspace(-1.0, 1.0, n)
    return base + np.sqrt(c[:, None, None] ** 2 + c[None, :, None] ** 2 + c[None, None, :] ** 2)


# ----------------------------------------------------------------------------- byte order (item 3)


@pytest.mark.parametrize("dtype", [">f8", ">f4", ">i8", ">i4", ">u2"])
def test_non_native_byte_order_is_read_by_value(dtype):
    # float64 at 1e8 + 0.5 needs its residuals about the midrange: a big-endian '>f8' used to be
    # cast to float32 (its dtype is not `== np.float64`), where 1e8 + 0.5 and 1e8 + 1.2 are one value.
    base = 1e8 + 0.5 if dtype.endswith("8") and dtype[1] == "f" else 0.0
    scale = 1.0 if dtype[1] == "f" else 1000.0  # integers: a ball of radius 500 in thousandths
    native = np.round(_ball(base=0.0) * scale) if dtype[1] != "f" else _ball(base=base) * scale
    native = native.astype(np.dtype(dtype).newbyteorder("="))
    swapped = native.astype(dtype)
    assert not swapped.dtype.isnative
    a, b = gc.Volume(native), gc.Volume(swapped)
    assert a.offset == b.offset
    assert a.to_bytes() == b.to_bytes()
    w = base + 0.7 * scale
    va, fa = gc.extract_isosurface(a, w)
    vb, fb = gc.extract_isosurface(b, w)
    assert len(fa) > 100
    np.testing.assert_array_equal(va, vb)
    np.testing.assert_array_equal(fa, fb)


def test_big_endian_float64_keeps_float64_precision():
    v = _ball()  # 1e8 + 0.5 + r: float32 holds 1e8 and 1e8 + 8 only
    vol = gc.Volume(v.astype(">f8"))
    assert vol.offset > 1e8  # float64 values are stored as residuals about their midrange
    verts, faces = gc.extract_isosurface(vol, 1e8 + 0.5 + 0.7)
    # the isosurface is the sphere of radius 0.7 about the centre (grid units: 11 cells over 2)
    r = np.linalg.norm(verts * (2 / 11) - 1.0, axis=1)
    assert len(faces) > 100 and np.abs(r - 0.7).max() < 0.05


def test_long_double_volumes_keep_float64_precision():
    v = _ball().astype(np.longdouble)
    assert gc.Volume(v).to_bytes() == gc.Volume(_ball()).to_bytes()


def test_every_array_input_reads_non_native_byte_order_by_value():
    # The scene built from big-endian arrays is the one built from native ones, byte for byte.
    def be(a, dt):
        return np.asarray(a).astype(np.dtype(dt).newbyteorder(">"))

    rng = np.random.default_rng(3)
    z = 1e4 + rng.random((6, 7))
    v = 450_000.0 + rng.random((5, 3))
    f = np.array([[0, 1, 2], [2, 3, 4]])
    path = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -10.0], [1.0, 1.0, -20.0]])
    corners = np.zeros((1, 1, 1, 8, 3))
    for c in range(8):
        corners[0, 0, 0, c] = [c & 1, (c >> 1) & 1, -((c >> 2) & 1)]
    scenes = []
    for conv in (lambda a, dt: np.asarray(a).astype(dt), be):
        s = gc.Scene()
        s.add_heightfield(conv(z, "f8"), origin=conv([1.5, 2.5], "f8"), spacing=conv([1, 2], "f4"),
                          tiles=conv([2, 2], "i8"), values=conv(z, "f8"), clim=conv([1e4, 1e4 + 1], "f8"))
        s.add_heightfield(conv(np.round(z * 10), "i4"), null_value=100005)
        s.add_mesh(conv(v, "f8"), conv(f, "i8"), values=conv([1, 2, 3, 4, 5], "f8"))
        s.add_mesh(conv(v, "f8"), conv(f, "u4"), cmap=conv([[0, 0, 0], [1, 1, 1]], "f8"))
        s.add_well(conv(path, "f8"), values=conv([1, 2, 3], "f8"))
        s.add_grid(conv(corners, "f8"), region=conv(np.zeros((1, 1, 1)), "i8"), values=conv(np.ones((1, 1, 1)), "f8"),
                   blocks=conv([8, 8], "i4"))
        s.translate(0, conv([1, 1, 1], "f8"))
        scenes.append(s.to_bytes())
    assert scenes[0] == scenes[1]
    cams = [gc.Camera.look_at(conv([10, 10, 10], "f8"), conv([0, 0, 1e4], "f8")) for conv in
            (lambda a, dt: np.asarray(a).astype(dt), be)]
    assert cams[0].eye == cams[1].eye and cams[0].target == cams[1].target


# ------------------------------------------------------------------ volume coordinates (item 5)


@pytest.mark.parametrize(("kw", "arg", "words"), [
    (dict(origin=(1e300, 0.0, 0.0)), "origin", "component 0 is 1e+300"),
    (dict(origin=(0.0, -2e12, 0.0)), "origin", "component 1 is -2e+12"),
    (dict(origin=(0.0, 0.0, 1e13), z_positive="down"), "origin", "component 2"),
    (dict(spacing=(1e11, 1.0, 1.0)), "spacing", "component 0: the grid reaches 9e+11"),  # fits: no error
    (dict(spacing=(2e11, 1.0, 1.0)), "spacing", "component 0: the grid reaches 1.8e+12"),
    (dict(origin=(9e11, 0.0, 0.0), spacing=(1.0, 1e11, 1.0), rotation=-90.0), "spacing", "component 0"),
    (dict(origin=(0.0, 0.0, 5e11), spacing=(1.0, 1.0, 1e11), z_positive="down"), "spacing", "component 2"),
])
def test_volume_coordinates_are_within_the_limit_of_every_object(kw, arg, words):
    v = np.zeros((10, 10, 10))
    if kw.get("spacing") == (1e11, 1.0, 1.0):
        assert gc.Volume(v, **kw).bounds[1][0] == 9e11  # at the limit's side: accepted
        return
    with pytest.raises(gc.InputError, match=f"^{arg}: ") as e:
        gc.Volume(v, **kw)
    assert words in str(e.value) and "1e+12" in str(e.value)


def test_volume_bytes_beyond_the_coordinate_limit_name_data():
    b = bytearray(gc.Volume(np.zeros((3, 3, 3)), origin=(10.0, 0.0, 0.0)).to_bytes())
    at = b.index(np.float64(10.0).tobytes())
    b[at:at + 8] = np.float64(1e300).tobytes()
    with pytest.raises(gc.InputError, match="^data: origin component 0 is 1e\\+300"):
        gc.Volume.from_bytes(bytes(b))


def test_a_volume_far_away_fails_at_once_not_in_later_calls():
    # It used to be accepted, and a later slice or camera named `vertices` or `eye`.
    with pytest.raises(gc.InputError, match="^origin: "):
        gc.Volume(np.random.default_rng(0).random((4, 4, 4)), origin=(1e300, 0, 0))


# ------------------------------------------------------------------------ infinities (item 4)
# One rule: +-inf in sampled data (volume samples of every dtype and reader, height-field z,
# colouring values) is refused, naming the user's argument and the first infinite element in the
# user's own index order; NaN (or a masked element) is no data.


def _with_inf(dtype, at=(2, 1, 4), value=-np.inf):
    v = np.random.default_rng(1).random((6, 7, 8)).astype(dtype)
    v[at] = value
    return v


@pytest.mark.parametrize("dtype", ["float32", "float16", ">f4", "float64"])
@pytest.mark.parametrize("kw", [{}, dict(order="xyz"), dict(z_positive="down"), dict(yflip=True)])
def test_infinite_volume_samples_are_refused_naming_the_users_index(dtype, kw):
    with pytest.raises(gc.InputError, match=r"^values\[2, 1, 4\] is -inf; use NaN for no data"):
        gc.Volume(_with_inf(dtype), **kw)


def test_masked_infinite_samples_are_no_data():
    v = np.ma.masked_invalid(_with_inf("float32"))
    vol = gc.Volume(v)
    verts, _ = gc.extract_isosurface(vol, 0.5)
    assert np.isfinite(verts).all()


def test_infinite_residuals_in_volume_bytes_are_damage():
    b = bytearray(gc.Volume(np.random.default_rng(2).random((4, 4, 4)).astype(np.float32)).to_bytes())
    b[-4:] = np.float32(np.inf).tobytes()  # the last sample's residual
    with pytest.raises(gc.InputError, match=r"^data: the residual of stored sample \[3, 3, 3\] is inf"):
        gc.Volume.from_bytes(bytes(b))


def test_damaged_volume_bytes_name_data_not_origin_or_spacing():
    b = bytearray(gc.Volume(np.zeros((3, 3, 3)), spacing=(1.0, 2.5, 1.0)).to_bytes())
    at = b.index(np.float64(2.5).tobytes())
    b[at:at + 8] = np.float64(-1.0).tobytes()
    with pytest.raises(gc.InputError, match="^data: damaged volume bytes: spacing: component 1 is -1"):
        gc.Volume.from_bytes(bytes(b))
    b[at:at + 8] = np.float64(np.nan).tobytes()
    with pytest.raises(gc.InputError, match="^data: "):
        gc.Volume.from_bytes(bytes(b))


def test_no_later_call_names_an_argument_the_user_did_not_pass():
    # A float32 volume with an inf sample used to load, then extract_isosurface returned NaN
    # vertices and add_isosurface / add_slice failed naming `vertices` / `values[30] (flat index)`.
    v = _with_inf("float32", at=(1, 1, 1), value=np.inf)
    with pytest.raises(gc.InputError) as e:
        s = gc.Scene()
        vol = gc.Volume(v)
        s.add_isosurface(vol, 0.5)
        s.add_slice(vol, "inline", 1)
    assert str(e.value).startswith("values[1, 1, 1] is inf")


def test_infinite_colouring_values_name_their_element():
    s = gc.Scene()
    z = np.random.default_rng(4).random((5, 6))
    vals = z.copy()
    vals[1, 2] = np.inf
    with pytest.raises(gc.InputError, match=r"^values\[1, 2\] is inf"):
        s.add_heightfield(z, values=vals)
    z[3, 4] = -np.inf
    with pytest.raises(gc.InputError, match=r"^z\[3, 4\] is -inf"):
        s.add_heightfield(z)
    with pytest.raises(gc.InputError, match=r"^values\[1\] is inf"):
        s.add_mesh(np.eye(3), [[0, 1, 2]], values=[0.0, np.inf, 1.0])


def test_infinite_segy_samples_are_refused_naming_the_file_and_trace(tmp_path):
    segyio = pytest.importorskip("segyio")
    from test_io_segy import write_cube

    path = str(write_cube(tmp_path / "cube.sgy"))
    with segyio.open(path, "r+", ignore_geometry=True) as f:
        tr = f.trace[40].copy()
        tr[7] = np.inf
        f.trace[40] = tr
        il, xl = f.header[40][segyio.TraceField.INLINE_3D], f.header[40][segyio.TraceField.CROSSLINE_3D]
    with pytest.raises(gc.InputError) as e:
        gc.Volume.from_segy(path)
    assert str(e.value).startswith(f"source: {path!r}: inline {il}, crossline {xl}, sample 7 (at 1028 in the "
                                   "file's units) is inf; infinite samples are refused")


# ----------------------------------------------------------- messages naming the right thing (item 6)


@pytest.mark.parametrize("kw", [{}, dict(order="xyz", z_positive="down")])
def test_a_sample_out_of_float32_range_is_named_not_a_valid_one(kw):
    v = np.random.default_rng(5).random((6, 6, 6))
    v[3, 1, 2] = 1e300  # values[0, 0, 0] is a valid ~0.5: the core named it (its residual overflowed)
    with pytest.raises(gc.InputError, match=r"^values\[3, 1, 2\] is 1e\+300, over 3.4e\+38 from the median"):
        gc.Volume(v, **kw)


def _grid_corners(nk=2, nj=3, ni=4):
    c = np.zeros((nk, nj, ni, 8, 3))
    k, j, i = np.meshgrid(np.arange(nk), np.arange(nj), np.arange(ni), indexing="ij")
    for n in range(8):
        c[..., n, 0] = i + (n & 1)
        c[..., n, 1] = j + ((n >> 1) & 1)
        c[..., n, 2] = -(k + ((n >> 2) & 1))
    return c


@pytest.mark.parametrize("dtype", ["int32", "int64", "uint8", ">i4"])
def test_an_integer_active_array_is_read_as_actnum(dtype):
    # It was told "expected real numbers (float or int)" (it was an int array).
    act = np.ones((2, 3, 4), dtype)
    act[0, 1, 2] = 0
    act[1, 2, 3] = 2  # ACTNUM 2 (dual porosity): active
    s, t = gc.Scene(), gc.Scene()
    s.add_grid(_grid_corners(), active=act)
    t.add_grid(_grid_corners(), active=act.astype(np.int64) != 0)
    assert s.to_bytes() == t.to_bytes()


def test_a_float_active_array_is_told_what_is_expected():
    with pytest.raises(gc.InputError, match=r"^active: dtype float64 is not supported; expected bools or integers$"):
        gc.Scene().add_grid(_grid_corners(), active=np.ones((2, 3, 4)))


# ------------------------------------------------------------------------ tiny scenes (item 7)


def _tiny_scene(size):
    s = gc.Scene()
    x = np.arange(9)[None, :] * np.ones((9, 1))
    s.add_heightfield(np.sin(x / 2.0) * size * 2, spacing=(size, size))
    return s


@pytest.mark.parametrize("size", [1e-8, 1e-10])
def test_scenes_smaller_than_the_least_near_plane_warn(renderer_small, size):
    # They rendered empty (or a few pixels: Camera.fit cannot bring the eye within the 1e-6 near
    # plane) without a warning; the near-plane warning said "pass a smaller near", which is refused.
    r = renderer_small(32, 32)
    s = _tiny_scene(size)
    for cam in (gc.Camera.fit(s), gc.Camera.look_at((14 * size, 14 * size, 10 * size), (4 * size, 4 * size, 0.0))):
        with pytest.warns(gc.GeocullWarning, match=r"^the scene spans only [0-9.e-]+ \(its largest side") as w:
            r.render(s, cam)
        assert len([x for x in w if issubclass(x.category, gc.GeocullWarning)]) == 1


def test_isosurfaces_of_tiny_volumes_warn(renderer_small):
    c = np.linspace(-1, 1, 8)
    v = gc.Volume(np.sqrt(c[:, None, None] ** 2 + c[None, :, None] ** 2 + c[None, None, :] ** 2), spacing=(1e-9,) * 3)
    cam = gc.Camera.look_at((2e-8, 1e-8, 1e-8), (3.5e-9,) * 3)
    with pytest.warns(gc.GeocullWarning, match="^the scene spans only 7e-09"):
        renderer_small(32, 32).render_isosurface(v, 0.5, cam)


def test_small_but_framable_scenes_do_not_warn(renderer_small):
    import warnings

    r = renderer_small(32, 32)
    s = _tiny_scene(1e-6)  # 8e-6 wide: the eye can stand beyond the near plane and see it
    with warnings.catch_warnings():
        warnings.simplefilter("error", gc.GeocullWarning)
        res = r.render(s, gc.Camera.fit(s))
    big = _tiny_scene(1.0)
    ref = r.render(big, gc.Camera.fit(big))  # the same view a million times larger
    assert ref.coverage.mean() > 0.1
    assert abs(res.coverage.mean() - ref.coverage.mean()) < 0.01
