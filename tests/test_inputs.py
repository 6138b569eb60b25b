"""Bad input to every public entry point raises geocull.InputError (a ValueError) whose message
starts with the argument's name and points at the first offending element; awkward but valid
arrays (non-contiguous, read-only, Fortran order, other real dtypes) are accepted."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc

Z = np.zeros((4, 5))
V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]], float)
F = np.array([[0, 1, 2], [1, 3, 2]])
EYE, TGT = (1.0, 2.0, 30.0), (1.0, 2.0, 0.0)


def hf(**kw):
    return gc.Scene().add_heightfield(**{"z": Z, **kw})


def mesh(**kw):
    return gc.Scene().add_mesh(**{"vertices": V, "faces": F, **kw})


def cam(**kw):
    return gc.Camera.look_at(**{"eye": EYE, "target": TGT, **kw})


def with_nan_at(shape, idx, value=np.nan):
    a = np.zeros(shape)
    a[idx] = value
    return a


def obj_array():
    a = np.empty((3, 3), dtype=object)
    a[:] = 1.0
    return a


# (label, call, message prefix: the argument's name, and text naming the first bad element)
BAD = [
    # --- add_heightfield: z
    ("z str", lambda: hf(z=np.full((3, 3), "a")), "z", "dtype"),
    ("z object", lambda: hf(z=obj_array()), "z", "object"),
    ("z complex", lambda: hf(z=np.zeros((3, 3), complex)), "z", "complex"),
    ("z bool", lambda: hf(z=np.zeros((3, 3), bool)), "z", "bool"),
    ("z 1-D", lambda: hf(z=np.zeros(9)), "z", "(9,)"),
    ("z 3-D", lambda: hf(z=np.zeros((3, 3, 1))), "z", "(3, 3, 1)"),
    ("z one row", lambda: hf(z=np.zeros((1, 5))), "z", "(1, 5)"),
    ("z empty", lambda: hf(z=np.zeros((0, 0))), "z", "(0, 0)"),
    ("z ragged", lambda: hf(z=[[0.0, 1.0], [2.0]]), "z", "array"),
    ("z +inf", lambda: hf(z=with_nan_at((3, 4), (1, 2), np.inf)), "z[1, 2]", "inf"),
    ("z -inf after nan", lambda: hf(z=np.array([[np.nan, 0, 0], [0, -np.inf, np.inf]])), "z[1, 1]", "-inf"),
    ("z huge", lambda: hf(z=np.array([[0.0, 0.0], [0.0, 1e300]])), "z[1, 1]", "1e300"),
    ("z None", lambda: hf(z=None), "z", "object"),
    # --- add_heightfield: other arguments
    ("origin nan", lambda: hf(origin=(0.0, np.nan)), "origin", "component 1"),
    ("origin inf", lambda: hf(origin=(np.inf, 0.0)), "origin", "component 0"),
    ("origin shape", lambda: hf(origin=(0.0, 0.0, 0.0)), "origin", "(3,)"),
    ("origin huge", lambda: hf(origin=(1e300, 0.0)), "origin", "component 0"),
    ("spacing zero", lambda: hf(spacing=(0.0, 1.0)), "spacing", "component 0"),
    ("spacing negative", lambda: hf(spacing=(1.0, -2.0)), "spacing", "component 1"),
    ("spacing nan", lambda: hf(spacing=(np.nan, 1.0)), "spacing", "component 0"),
    ("spacing inf", lambda: hf(spacing=(1.0, np.inf)), "spacing", "component 1"),
    ("spacing scalar", lambda: hf(spacing=1.0), "spacing", "()"),
    ("spacing str", lambda: hf(spacing=("1", "1")), "spacing", "dtype"),
    ("spacing huge extent", lambda: hf(spacing=(1e300, 1.0)), "spacing", "component 0"),
    ("tiles zero", lambda: hf(tiles=(0, 1)), "tiles[0]", "0"),
    ("tiles negative", lambda: hf(tiles=(1, -3)), "tiles[1]", "-3"),
    ("tiles too many x", lambda: hf(tiles=(5, 1)), "tiles", "tiles[0] is 5"),
    ("tiles too many y", lambda: hf(tiles=(1, 4)), "tiles", "tiles[1] is 4"),
    ("tiles float", lambda: hf(tiles=(1.5, 1)), "tiles", "dtype"),
    ("tiles scalar", lambda: hf(tiles=2), "tiles", "()"),
    ("tiles huge", lambda: hf(tiles=(2**40, 1)), "tiles[0]", str(2**40)),
    ("coarse_factor < 1", lambda: hf(coarse_factor=0.5), "coarse_factor", "0.5"),
    ("coarse_factor 0", lambda: hf(coarse_factor=0), "coarse_factor", "0"),
    ("coarse_factor -2", lambda: hf(coarse_factor=-2), "coarse_factor", "-2"),
    ("coarse_factor nan", lambda: hf(coarse_factor=np.nan), "coarse_factor", "NaN"),
    ("coarse_factor str", lambda: hf(coarse_factor="4"), "coarse_factor", "'4'"),
    ("color > 1", lambda: hf(color=(0.5, 1.5, 0.0)), "color", "component 1"),
    ("color < 0", lambda: hf(color=(-0.1, 0.5, 0.0)), "color", "component 0"),
    ("color nan", lambda: hf(color=(0.0, 0.0, np.nan)), "color", "component 2"),
    ("color 255", lambda: hf(color=(255, 0, 0)), "color", "component 0"),
    ("color rgba", lambda: hf(color=(0, 0, 0, 1)), "color", "(4,)"),
    ("color name", lambda: hf(color="red"), "color", "dtype"),
    ("null_value inf", lambda: hf(null_value=np.inf), "null_value", "inf"),
    ("null_value str", lambda: hf(null_value="-999.25"), "null_value", "'-999.25'"),
    ("name int", lambda: hf(name=3), "name", "3"),
    # --- add_mesh
    ("vertices nan", lambda: mesh(vertices=with_nan_at((4, 3), (2, 1))), "vertices[2, 1]", "NaN"),
    ("vertices inf", lambda: mesh(vertices=with_nan_at((4, 3), (3, 2), -np.inf)), "vertices[3, 2]", "-inf"),
    ("vertices first nan", lambda: mesh(vertices=np.full((4, 3), np.nan)), "vertices[0, 0]", "NaN"),
    ("vertices huge", lambda: mesh(vertices=with_nan_at((4, 3), (1, 0), 1e300)), "vertices[1, 0]", "1e300"),
    ("vertices (n, 2)", lambda: mesh(vertices=np.zeros((4, 2))), "vertices", "(4, 2)"),
    ("vertices 1-D", lambda: mesh(vertices=np.zeros(12)), "vertices", "(12,)"),
    ("vertices str", lambda: mesh(vertices=np.full((4, 3), "x")), "vertices", "dtype"),
    ("vertices object", lambda: mesh(vertices=np.array([[None] * 3] * 4)), "vertices", "object"),
    ("vertices complex", lambda: mesh(vertices=V.astype(complex)), "vertices", "complex"),
    ("faces negative", lambda: mesh(faces=np.array([[0, 1, 2], [1, -1, 2]])), "faces[1, 1]", "-1"),
    ("faces out of range", lambda: mesh(faces=np.array([[0, 1, 2], [1, 3, 4]])), "faces[1, 2]", "4"),
    ("faces first of two bad", lambda: mesh(faces=np.array([[0, 9, 2], [1, 3, -4]])), "faces[0, 1]", "9"),
    ("faces float", lambda: mesh(faces=F.astype(float)), "faces", "float64"),
    ("faces bool", lambda: mesh(faces=F.astype(bool)), "faces", "bool"),
    ("faces (m, 4)", lambda: mesh(faces=np.array([[0, 1, 2, 3]])), "faces", "(1, 4)"),
    ("faces uint64 huge", lambda: mesh(faces=np.array([[0, 1, 2**64 - 1]], np.uint64)), "faces", "large"),
    ("faces str", lambda: mesh(faces=np.array([["0", "1", "2"]])), "faces", "dtype"),
    ("kind int", lambda: mesh(kind=3), "kind", "3"),
    ("mesh tiles 0", lambda: mesh(tiles=0), "tiles", "0"),
    ("mesh tiles float", lambda: mesh(tiles=2.0), "tiles", "2.0"),
    ("mesh coarse_factor", lambda: mesh(coarse_factor=0.99), "coarse_factor", "0.99"),
    ("mesh color", lambda: mesh(color=(0, 2, 0)), "color", "component 1"),
    # --- Camera.look_at
    ("eye == target", lambda: cam(target=EYE), "target", "eye"),
    ("eye nan", lambda: cam(eye=(0.0, np.nan, 1.0)), "eye", "component 1"),
    ("target inf", lambda: cam(target=(0.0, 0.0, -np.inf)), "target", "component 2"),
    ("eye shape", lambda: cam(eye=(0.0, 1.0)), "eye", "(2,)"),
    ("eye str", lambda: cam(eye="abc"), "eye", "dtype"),
    ("eye huge", lambda: cam(eye=(1e300, 0.0, 1.0)), "eye", "component 0"),
    ("eye too close", lambda: cam(eye=(0.0, 0.0, 1e-320), target=(0.0, 0.0, 0.0)), "target", "too short"),
    ("up zero", lambda: cam(up=(0, 0, 0)), "up", "non-zero"),
    ("fov 0", lambda: cam(fov_y=0), "fov_y", "0"),
    ("fov 180", lambda: cam(fov_y=180), "fov_y", "180"),
    ("fov negative", lambda: cam(fov_y=-10), "fov_y", "-10"),
    ("fov nan", lambda: cam(fov_y=np.nan), "fov_y", "NaN"),
    ("fov tiny", lambda: cam(fov_y=1e-300), "fov_y", "1e-300"),
    ("fov str", lambda: cam(fov_y="45"), "fov_y", "'45'"),
    ("near negative", lambda: cam(near=-1.0), "near", "-1"),
    ("near zero", lambda: cam(near=0.0), "near", "0"),
    ("near underflow", lambda: cam(near=1e-40), "near", "1e-40"),
    ("far < near", lambda: cam(near=10.0, far=5.0), "far", "near"),
    ("far nan", lambda: cam(far=np.nan), "far", "NaN"),
    ("far below the near floor", lambda: cam(far=1e-320), "far", "perspective"),
    ("projection", lambda: cam(projection="fisheye"), "projection", "fisheye"),
    ("projection int", lambda: cam(projection=1), "projection", "1"),
    ("ortho_height 0", lambda: cam(projection="orthographic", ortho_height=0.0), "ortho_height", "0"),
    ("ortho_height tiny", lambda: cam(projection="orthographic", ortho_height=1e-300), "ortho_height", "1e-300"),
    ("ortho_height huge", lambda: cam(projection="orthographic", ortho_height=1e300), "ortho_height", "1e300"),
    ("near huge", lambda: cam(near=1e300), "near", "1e300"),
    ("far huge", lambda: cam(far=1e300), "far", "1e300"),
    ("z_scale 0", lambda: cam(z_scale=0.0), "z_scale", "0"),
    ("z_scale negative", lambda: cam(z_scale=-5.0), "z_scale", "-5"),
    ("z_scale nan", lambda: cam(z_scale=np.nan), "z_scale", "NaN"),
    ("z_scale huge", lambda: cam(z_scale=1e300), "z_scale", "1e300"),
    # --- Renderer
    ("width 0", lambda: gc.Renderer(0, 8), "width", "0"),
    ("height 0", lambda: gc.Renderer(8, 0), "height", "0"),
    ("width negative", lambda: gc.Renderer(-8, 8), "width", "-8"),
    ("width float", lambda: gc.Renderer(8.0, 8), "width", "8.0"),
    ("width huge", lambda: gc.Renderer(2**40, 8), "width", str(2**40)),
    ("height too large", lambda: gc.Renderer(8, 10**6), "height", "1000000"),
    ("backend", lambda: gc.Renderer(8, 8, backend="directx9"), "backend", "directx9"),
    ("backend int", lambda: gc.Renderer(8, 8, backend=1), "backend", "1"),
]


@pytest.mark.parametrize("label,call,arg,detail", BAD, ids=[b[0] for b in BAD])
def test_bad_input_raises_input_error_naming_the_argument(label, call, arg, detail):
    with pytest.raises(gc.InputError) as e:
        call()
    assert isinstance(e.value, ValueError) and isinstance(e.value, gc.GeocullError)
    msg = str(e.value)
    assert msg.startswith(arg), f"{label}: {msg!r} does not start with {arg!r}"
    assert detail.lower() in msg.lower(), f"{label}: {msg!r} does not mention {detail!r}"


@pytest.fixture(scope="module")
def small_world(renderer_small):
    s = gc.Scene()
    hid = s.add_heightfield(np.zeros((5, 5)), tiles=(2, 2))
    return renderer_small(16, 16), s, hid, cam()


RENDER_BAD = [
    ({"culling": "fast"}, "culling", "fast"),
    ({"culling": "None"}, "culling", "None"),
    ({"culling": None}, "culling", "None"),
    ({"culling": "THREE_PASS"}, "culling", "THREE_PASS"),
    ({"pixel_threshold": -1}, "pixel_threshold", "-1"),
    ({"pixel_threshold": np.nan}, "pixel_threshold", "NaN"),
    ({"pixel_threshold": np.inf}, "pixel_threshold", "inf"),
    ({"pixel_threshold": "10"}, "pixel_threshold", "'10'"),
    ({"prepass_scale": 0}, "prepass_scale", "0"),
    ({"prepass_scale": -0.5}, "prepass_scale", "-0.5"),
    ({"prepass_scale": 1.5}, "prepass_scale", "1.5"),
    ({"prepass_scale": np.nan}, "prepass_scale", "NaN"),
]


@pytest.mark.parametrize("kw,arg,detail", RENDER_BAD,
                         ids=[f"{k}={v!r}" for (kw, _, _) in RENDER_BAD for k, v in kw.items()])
@pytest.mark.parametrize("culling", ["none", "three_pass", "oracle", "horizon"])
def test_bad_render_arguments(small_world, kw, arg, detail, culling):
    r, s, _, c = small_world
    kw = {"culling": culling, **kw}
    with pytest.raises(gc.InputError) as e:
        r.render(s, c, **kw)
    assert str(e.value).startswith(arg) and detail.lower() in str(e.value).lower(), str(e.value)


def test_render_scene_and_camera_types(small_world):
    r, s, _, c = small_world
    with pytest.raises(gc.InputError, match="^scene"):
        r.render(None, c)
    with pytest.raises(gc.InputError, match="^camera"):
        r.render(s, "camera")
    with pytest.raises(gc.InputError, match="^scene"):
        r.render(s._s, c)


def test_scene_methods_validate_ids_and_values(small_world):
    _, s, hid, _ = small_world
    for call in (lambda: s.remove(99), lambda: s.set_visible(99, True), lambda: s.translate(99, (0, 0, 0)),
                 lambda: s.set_color(99, (0, 0, 0)), lambda: s.geometry(99), lambda: s.object_info(99),
                 lambda: s.remove(-1), lambda: s.geometry("0"), lambda: s.remove(1.0)):
        with pytest.raises(gc.InputError, match="^id"):
            call()
    with pytest.raises(gc.InputError, match=r"^offset: component 2"):
        s.translate(hid, (0, 0, np.nan))
    with pytest.raises(gc.InputError, match=r"^offset: component 0"):
        s.translate(hid, (1e300, 0, 0))
    with pytest.raises(gc.InputError, match="^offset"):
        s.translate(hid, (0, 0))
    with pytest.raises(gc.InputError, match=r"^color: component 0"):
        s.set_color(hid, (2, 0, 0))
    assert s.object_info(hid)["offset"] == (0.0, 0.0, 0.0)  # failed calls change nothing


def test_failed_add_leaves_the_scene_unchanged():
    s = gc.Scene()
    s.add_heightfield(np.zeros((3, 3)), origin=(10, 20))
    before = (s.object_ids(), s.n_tiles, s.n_triangles, s.origin)
    for call in (lambda: s.add_heightfield(with_nan_at((3, 3), (2, 2), np.inf)),
                 lambda: s.add_mesh(V, [[0, 1, 7]]),
                 lambda: s.add_mesh(with_nan_at((4, 3), (0, 0)), F),
                 lambda: s.add_heightfield(np.zeros((3, 3)), color=(2, 0, 0))):
        with pytest.raises(gc.InputError):
            call()
    assert (s.object_ids(), s.n_tiles, s.n_triangles, s.origin) == before
    assert s.add_mesh(V, F) == 1


# ----------------------------------------------------------------- awkward but valid arrays


def _variants(a):
    ro = np.array(a)
    ro.flags.writeable = False
    big = np.zeros((a.shape[0] * 2, a.shape[1] * 3), a.dtype)
    big[::2, ::3] = a
    return {
        "list": a.tolist(),
        "read-only": ro,
        "non-contiguous": big[::2, ::3],
        "fortran": np.asfortranarray(a),
        "transposed-view": np.ascontiguousarray(a.T).T,
    }


def test_heightfield_accepts_any_real_layout_and_dtype():
    z = np.arange(12, dtype=float).reshape(3, 4) - 5
    ref = gc.Scene()
    ref.add_heightfield(z, origin=(451000, 6780000))
    v_ref, f_ref = ref.geometry(0)
    arrays = dict(_variants(z))
    for dt in (np.float32, np.float16, np.int8, np.int32, np.int64, np.uint16):
        arrays[np.dtype(dt).name] = (z + 5).astype(dt) - (5 if np.dtype(dt).kind != "u" else 0)
    for label, a in arrays.items():
        s = gc.Scene()
        s.add_heightfield(a, origin=(451000, 6780000))
        v, f = s.geometry(0)
        np.testing.assert_array_equal(f, f_ref, err_msg=label)
        if label != "uint16":
            np.testing.assert_allclose(v, v_ref, atol=1e-6, err_msg=label)
    ro = np.zeros((3, 3))
    ro.flags.writeable = False
    gc.Scene().add_heightfield(ro)
    assert not ro.flags.writeable and (ro == 0).all()  # never written to


def test_mesh_accepts_any_real_layout_and_dtype():
    ref = gc.Scene()
    ref.add_mesh(V, F)
    v_ref, f_ref = ref.geometry(0)
    for vl, va in list(_variants(V).items()) + [("float32", V.astype(np.float32)), ("int16", V.astype(np.int16))]:
        for fl, fa in list(_variants(F).items()) + [("int8", F.astype(np.int8)), ("uint32", F.astype(np.uint32)),
                                                    ("uint64", F.astype(np.uint64))]:
            s = gc.Scene()
            s.add_mesh(va, fa)
            v, f = s.geometry(0)
            np.testing.assert_array_equal(f, f_ref, err_msg=f"{vl} {fl}")
            np.testing.assert_allclose(v, v_ref, err_msg=f"{vl} {fl}")


def test_empty_mesh_is_accepted():
    s = gc.Scene()
    s.add_mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    s.add_mesh(V, np.zeros((0, 3), np.int32))
    assert s.n_triangles == 0


def test_numpy_scalars_and_sequences_are_accepted():
    s = gc.Scene()
    s.add_heightfield(Z, origin=np.array([1.0, 2.0]), spacing=[np.float32(2), np.int64(3)],
                      tiles=np.array([2, 1], np.uint8), coarse_factor=np.float64(2.0), color=np.array([0.1, 0.2, 0.3]),
                      null_value=np.float32(-999.25))
    s.add_mesh(V, F, tiles=np.int64(2), coarse_factor=np.int32(3))
    c = gc.Camera.look_at(np.array(EYE), list(TGT), fov_y=np.float32(30), near=np.float64(0.5), z_scale=np.int64(5))
    assert c.z_scale == 5 and c.near == 0.5
    info = s.object_info(0)
    assert np.allclose(info["color"], (0.1, 0.2, 0.3))
    assert s.geometry(0)[0][:, 0].max() == 1 + 2 * 4


def test_misaligned_float_arrays_are_accepted():
    # A float64 view at an odd byte offset (as Dask's out-of-band buffers can arrive).
    import geocull as gc

    buf = np.zeros(8 * 9 + 1, np.uint8)
    z = np.frombuffer(buf.data, dtype=np.float64, count=9, offset=1).reshape(3, 3)
    assert not z.flags.aligned
    s = gc.Scene()
    s.add_heightfield(z)
    assert s.n_triangles == 8
