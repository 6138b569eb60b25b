"""geocull.pyvista: reference renders (pure PyVista with a stand-in scene) and, once the extension
is built, round trips and agreement with geocull's own unculled render."""

import math
import os

import numpy as np
import pytest

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
pytest.importorskip("pyvista")

from geocull import data  # noqa: E402
from geocull import pyvista as gpv  # noqa: E402
from geocull.compare import coverage_agreement, depth_error  # noqa: E402

ORIGIN = np.array([451000.0, 6780000.0, -2000.0])  # UTM-sized, as in real scenes


def _square_scene(half=10.0, z=0.0, color=(1.0, 0.0, 0.0)):
    sc = data.MeshScene()
    v = ORIGIN + np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    sc.add_mesh(v, [[0, 1, 2], [0, 2, 3]], kind="mesh", name="square", color=color)
    return sc


@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
@pytest.mark.parametrize("z_scale", [1.0, 2.5])
def test_flat_square_from_above_depth_is_distance(projection, z_scale):
    sc = _square_scene()
    dist = 100.0
    cam = dict(
        eye=tuple(ORIGIN + [0.0, 0.0, dist / z_scale]),  # world eye; render space multiplies z by z_scale
        target=tuple(ORIGIN),
        up=(0.0, 1.0, 0.0),
        fov_y=30.0,
        projection=projection,
        ortho_height=30.0,
        z_scale=z_scale,
    )
    r = gpv.reference_image(sc, cam, 64, 48)
    img, depth = r["image"], r["depth"]
    assert img.shape == (48, 64, 3) and img.dtype == np.uint8
    assert depth.shape == (48, 64) and depth.dtype == np.float32
    cov = np.isfinite(depth)
    # expected footprint: half-size 10 in a view of half-height 100*tan(15°) (perspective) or 15
    half_h = dist * math.tan(math.radians(15)) if projection == "perspective" else 15.0
    rows = int(np.count_nonzero(cov.any(axis=1)))
    assert abs(rows - 48 * 10 / half_h) <= 2
    np.testing.assert_allclose(depth[cov], dist, rtol=1e-3)
    assert np.isinf(depth[~cov]).all()
    assert (img[cov][:, 0] > 0).all() and (img[~cov] == 0).all()  # red on black


def test_orientation_row0_is_top_and_x_is_right():
    # a square only in the +x, +y quadrant, camera above looking down with north (+y) up
    sc = data.MeshScene()
    v = ORIGIN + np.array([[1.0, 1.0, 0], [10, 1, 0], [10, 10, 0], [1, 10, 0]])
    sc.add_mesh(v, [[0, 1, 2], [0, 2, 3]], color=(0.0, 1.0, 0.0))
    cam = dict(eye=tuple(ORIGIN + [0, 0, 100.0]), target=tuple(ORIGIN), up=(0, 1, 0), fov_y=30.0, near=1.0, far=1000.0)
    r = gpv.reference_image(sc, cam, 40, 40, lighting=False)
    cov = np.isfinite(r["depth"])
    assert cov[:20, 20:].any() and not cov[20:, :].any() and not cov[:, :20].any()
    assert r["near"] == 1.0 and r["far"] == 1000.0
    # unlit: exactly the object's colour
    assert (r["image"][cov] == [0, 255, 0]).all()


def test_tilted_plane_depth_gradient():
    sc = _square_scene(half=50.0)
    d = 100.0
    cam = dict(eye=tuple(ORIGIN + [0, -d / math.sqrt(2), d / math.sqrt(2)]), target=tuple(ORIGIN), fov_y=30.0)
    r = gpv.reference_image(sc, cam, 64, 48)
    col = r["depth"][:, 32]
    ok = np.isfinite(col)
    assert np.all(np.diff(col[ok]) < 0)  # farther at the top of the image
    # the rows straddling the centre bracket the target distance
    assert col[23] > d > col[24]
    # exact depth along the view axis of the ray through pixel row 24's centre
    t = math.tan(math.radians(15)) * (24.5 - 24) / 24  # below the axis by this slope
    # plane z=0; ray: eye + s*(fwd + t*down_cam); along-axis distance = s
    fwd = np.array([0, 1, -1]) / math.sqrt(2)
    down = -np.array([0, 1, 1]) / math.sqrt(2)
    eye_z = d / math.sqrt(2)
    s = eye_z / -(fwd[2] + t * down[2])
    assert col[24] == pytest.approx(s, rel=1e-3)


def test_empty_scene_and_bad_camera():
    sc = data.MeshScene()
    r = gpv.reference_image(sc, dict(eye=(0, 0, 10.0), target=(0, 0, 0.0)), 8, 6)
    assert np.isinf(r["depth"]).all() and (r["image"] == 0).all()
    with pytest.raises(ValueError, match="camera"):
        gpv.reference_image(sc, dict(eye=(0, 0, 0.0), target=(0, 0, 0.0)), 8, 6)


@pytest.mark.parametrize("kw,arg", [(dict(near=10.0, far=1.0), "far"), (dict(near=5.0, far=5.0), "far"),
                                    (dict(near=-1.0), "near"), (dict(far=float("nan")), "far")])
def test_bad_clipping_range_is_an_error(kw, arg):
    sc = _square_scene()
    cam = dict(eye=tuple(ORIGIN + [0.0, 0.0, 100.0]), target=tuple(ORIGIN), up=(0.0, 1.0, 0.0))
    with pytest.raises(ValueError, match=f"^{arg}"):
        gpv.reference_image(sc, cam, 8, 6, **kw)
    with pytest.raises(ValueError, match=f"^{arg}"):
        gpv.timed_render(sc, cam, 8, 6, n=1, **kw)


def test_stacked_scene_reference_and_timed_render():
    spec = data.stacked_test_scene(n=24)
    ms = spec.mesh_scene()
    name, cam = data.standard_views(spec)[0]
    r = gpv.reference_image(ms, cam, 80, 64, msaa=True)
    cov = np.isfinite(r["depth"])
    assert 0.1 < cov.mean() < 0.95
    assert r["near"] < np.min(r["depth"][cov]) and np.max(r["depth"][cov]) < r["far"]
    assert r["ms"] > 0
    assert gpv.timed_render(ms, cam, 80, 64, n=2) > 0


def test_polydata_roundtrip_with_stand_in_scene():
    sc = _square_scene(color=(0.2, 0.4, 0.6))
    pd = gpv.to_polydata(sc, 0)
    assert pd.n_points == 4 and pd.n_cells == 2
    assert str(pd.field_data["name"][0]) == "square"
    np.testing.assert_allclose(pd.field_data["color"], (0.2, 0.4, 0.6))
    new = gpv.from_polydata(sc, pd)
    v0, f0 = sc.geometry(0)
    v1, f1 = sc.geometry(new)
    np.testing.assert_array_equal(v0, v1)
    np.testing.assert_array_equal(f0, f1)
    assert sc.object_info(new)["name"] == "square"
    mb = gpv.scene_to_multiblock(sc)
    assert len(mb) == 2 and "square" in mb.keys()


def test_from_polydata_triangulates_quads():
    import pyvista as pv

    sc = data.MeshScene()
    plane = pv.Plane(i_resolution=3, j_resolution=2)  # 6 quads
    oid = gpv.from_polydata(sc, plane, name="plane")
    v, f = sc.geometry(oid)
    assert f.shape == (12, 3) and v.shape == (12, 3)
    # a volume mesh goes in as its outer surface
    oid = gpv.from_polydata(sc, pv.Cube().cast_to_unstructured_grid())
    assert sc.geometry(oid)[1].shape == (12, 3)


# ---------------------------------------------------------------- with the compiled extension


@pytest.fixture(scope="module")
def gc():
    pytest.importorskip("geocull._geocull")
    import geocull

    if not all(hasattr(geocull, n) for n in ("Scene", "Camera", "Renderer")):
        pytest.skip("geocull does not export Scene/Camera/Renderer yet")
    return geocull


def test_roundtrip_with_geocull_scene(gc):
    spec = data.stacked_test_scene(n=16, n_horizons=1)
    scene = spec.build(tiles=(2, 2), coarse_factor=4)
    fid = scene.object_ids()[-1]
    pd = gpv.to_polydata(scene, fid)
    new = gpv.from_polydata(scene, pd)
    v0, f0 = scene.geometry(fid)
    v1, f1 = scene.geometry(new)
    np.testing.assert_allclose(v1, v0, rtol=0, atol=1e-6 * max(1.0, np.abs(v0).max()))
    np.testing.assert_array_equal(f1, f0)
    assert scene.object_info(new)["name"] == scene.object_info(fid)["name"]


def test_coverage_agrees_with_geocull_unculled(gc):
    spec = data.stacked_test_scene(n=32)
    scene = spec.build(tiles=(2, 2), coarse_factor=4)
    w, h = 96, 80
    renderer = gc.Renderer(w, h)
    for name, kw in data.standard_views(spec)[:2]:
        cam = gc.Camera.look_at(**kw)
        res = renderer.render(scene, cam, culling="none")
        ref = gpv.reference_image(scene, cam, w, h, near=res.near, far=res.far)
        agree = coverage_agreement(res.depth, ref["depth"])
        assert agree >= 0.99, (name, agree)
        err = depth_error(res.depth, ref["depth"], rel_tol=1e-2)
        assert err["fraction_over_tol"] < 0.02, (name, err)
