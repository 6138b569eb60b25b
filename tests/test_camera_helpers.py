"""Camera.orbit / fit / rotated / zoomed / from_pyvista / to_pyvista: eyes against hand-computed
positions, fit against the tightest framing found by bisection, and the PyVista round trip against
a plain PyVista render of the same view."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import geocull as gc
from geocull import data

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

BOX = ((1000.0, 2000.0, -300.0), (5000.0, 4000.0, -100.0))


def corners(lo, hi):
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def ndc_extent(cam: gc.Camera, pts: np.ndarray, aspect: float) -> tuple[float, float]:
    """Largest |x| and |y| of the points in normalised device coordinates, and the smallest depth."""
    v = cam.view_matrix()
    p = np.c_[pts * [1.0, 1.0, cam.z_scale], np.ones(len(pts))] @ v.T
    depth = -p[:, 2]
    t = math.tan(math.radians(cam.fov_y) / 2)
    return float(max(np.max(np.abs(p[:, 0] / depth)) / (t * aspect), np.max(np.abs(p[:, 1] / depth)) / t)), float(
        depth.min()
    )


def test_orbit_eyes_by_hand():
    t = (100.0, 200.0, -50.0)
    np.testing.assert_allclose(gc.Camera.orbit(t, 0, 0, 10).eye, (100, 210, -50))  # north of the target
    np.testing.assert_allclose(gc.Camera.orbit(t, 90, 0, 10).eye, (110, 200, -50))  # east
    np.testing.assert_allclose(gc.Camera.orbit(t, 270, 0, 10).eye, (90, 200, -50), atol=1e-12)
    np.testing.assert_allclose(gc.Camera.orbit(t, 0, 90, 10).eye, (100, 200, -40), atol=1e-12)
    h = 10 / math.sqrt(2)
    np.testing.assert_allclose(gc.Camera.orbit(t, 180, 45, 10).eye, (100, 200 - h, -50 + h))
    # azimuth 30, elevation 60: horizontal part 10 cos 60 = 5 at bearing 30 (x = 5 sin 30, y = 5 cos 30)
    np.testing.assert_allclose(gc.Camera.orbit(t, 30, 60, 10).eye, (102.5, 200 + 5 * math.cos(math.radians(30)),
                                                                    -50 + 10 * math.sin(math.radians(60))))
    # z_scale: laid out in render space, so the world eye is 10 / 4 above the target
    c = gc.Camera.orbit(t, 0, 90, 10, z_scale=4.0)
    np.testing.assert_allclose(c.eye, (100, 200, -47.5), atol=1e-12)
    assert c.z_scale == 4.0 and c.target == t
    assert c.orbit_angles() == pytest.approx((0.0, 90.0, 10.0))


def test_rotated_and_zoomed():
    c = gc.Camera.orbit((0, 0, 0), 350, 20, 100, fov_y=30)
    r = c.rotated(20, -5)
    assert r.orbit_angles() == pytest.approx((10.0, 15.0, 100.0))
    assert r.fov_y == 30 and r.target == c.target
    assert c.rotated(0, 200).orbit_angles()[1] == 90.0  # clamped
    z = c.zoomed(4)
    assert z.orbit_angles() == pytest.approx((350.0, 20.0, 25.0))
    o = gc.Camera.orbit((0, 0, 0), 0, 45, 100, projection="orthographic", ortho_height=50.0)
    oz = o.zoomed(2)
    assert oz.ortho_height == 25.0 and oz.eye == pytest.approx(o.eye)
    # None ortho_height: what fov_y sees at the target, then divided
    on = gc.Camera.orbit((0, 0, 0), 0, 45, 100, projection="orthographic", fov_y=90).zoomed(2)
    assert on.ortho_height == pytest.approx(100.0)
    for bad, arg in [(lambda: c.zoomed(0), "factor"), (lambda: c.rotated(math.nan), "d_azimuth"),
                     (lambda: gc.Camera.orbit((0, 0, 0), 0, 95, 1), "elevation"),
                     (lambda: gc.Camera.orbit((0, 0, 0), 0, 0, -1), "distance")]:
        with pytest.raises(gc.InputError, match=arg):
            bad()


@pytest.mark.parametrize(
    "az, el, aspect", [(30, 30, 1.0), (200, 10, 1.6), (0, 90, 0.5), (120, 60, 1.25), (300, -15, 1)],
)
def test_fit_frames_all_corners_within_10_percent_of_tightest(az, el, aspect):
    pts = corners(*BOX)
    cam = gc.Camera.fit(BOX, azimuth=az, elevation=el, aspect=aspect, fov_y=40)
    extent, near = ndc_extent(cam, pts, aspect)
    assert extent <= 1.0 and near > 0
    _, _, d_fit = cam.orbit_angles()
    assert cam.orbit_angles()[:2] == pytest.approx((az % 360 if el != 90 else 0, el))

    # Tightest distance along the same direction: bisection on "every corner inside".
    def inside(d):
        c = gc.Camera.orbit(cam.target, az, el, d, fov_y=40)
        e, n = ndc_extent(c, pts, aspect)
        return e <= 1.0 and n > 0

    lo, hi = 1e-3, d_fit * 4
    assert inside(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if inside(mid) else (mid, hi)
    assert hi <= d_fit <= 1.1 * hi, (d_fit, hi)
    # margin 0: the fit is the tightest itself
    d0 = gc.Camera.fit(BOX, azimuth=az, elevation=el, aspect=aspect, fov_y=40, margin=0).orbit_angles()[2]
    assert d0 == pytest.approx(hi, rel=1e-6)


def test_fit_orthographic_and_z_scale():
    pts = corners(*BOX)
    cam = gc.Camera.fit(BOX, 45, 30, projection="orthographic", margin=0, z_scale=3.0, aspect=1.5)
    v = cam.view_matrix()
    p = np.c_[pts * [1, 1, 3.0], np.ones(8)] @ v.T
    h = cam.ortho_height
    assert h is not None
    extent = max(np.max(np.abs(p[:, 0])) / (h * 1.5 / 2), np.max(np.abs(p[:, 1])) / (h / 2))
    assert extent == pytest.approx(1.0)
    assert np.all(-p[:, 2] > 0)  # every corner in front of the eye


def test_fit_a_scene_renders_inside_the_image(renderer_small):
    spec = data.stacked_test_scene(n=16, n_horizons=2)
    scene = spec.build(tiles=(2, 2), coarse_factor=4)
    r = renderer_small(64, 48)
    cam = gc.Camera.fit(scene, azimuth=210, elevation=35, aspect=64 / 48, margin=0.1)
    cov = np.isfinite(r.render(scene, cam, culling="none").depth)
    assert cov.any()
    # the margin keeps the border free, and the scene fills much of the image (the box's corners,
    # which frame it, are empty air, so the geometry need not touch the margin)
    assert not (cov[0].any() or cov[-1].any() or cov[:, 0].any() or cov[:, -1].any())
    rows, cols = np.nonzero(cov)
    assert cols.max() - cols.min() >= 0.4 * 64 and rows.max() - rows.min() >= 0.4 * 48
    with pytest.raises(gc.InputError, match="scene_or_bounds"):
        gc.Camera.fit(gc.Scene())
    with pytest.raises(gc.InputError, match="scene_or_bounds"):
        gc.Camera.fit([[0, 0], [1, 1]])


def test_pyvista_round_trip_renders_the_same_view(renderer_small):
    pv = pytest.importorskip("pyvista")
    from geocull import pyvista as gpv

    spec = data.stacked_test_scene(n=16, n_horizons=2)
    scene = spec.build(tiles=(2, 2), coarse_factor=4)
    w, h = 80, 64
    mb = gpv.scene_to_multiblock(scene)
    pl = pv.Plotter(off_screen=True, window_size=(w, h))
    pl.background_color = "black"
    for block in mb:
        pl.add_mesh(block, color="white", lighting=False)
    pl.camera_position = gc.Camera.fit(scene, 300, 40, fov_y=30, aspect=w / h, margin=0.2).to_pyvista()
    pl.camera.azimuth += 25  # a PyVista move: the camera now is PyVista's own
    pl.camera.elevation += 10
    pl.reset_camera_clipping_range()
    cp = pl.camera_position
    cov_pv = np.asarray(pl.screenshot(return_img=True)).any(axis=2)
    pl.close()

    cam = gc.Camera.from_pyvista(cp, fov_y=pl.camera.view_angle)
    assert cam.eye == pytest.approx(tuple(cp.position)) and cam.target == pytest.approx(tuple(cp.focal_point))
    back = cam.to_pyvista()
    np.testing.assert_allclose(back[0], cp.position)
    f = np.subtract(cp.focal_point, cp.position)
    f /= np.linalg.norm(f)
    u = np.asarray(cp.viewup) - (np.asarray(cp.viewup) @ f) * f  # VTK's view up, made orthogonal
    np.testing.assert_allclose(back[2], u / np.linalg.norm(u), atol=1e-9)
    cov_gc = np.isfinite(renderer_small(w, h).render(scene, cam, culling="none").depth)
    assert cov_pv.mean() > 0.05
    assert np.mean(cov_pv != cov_gc) < 0.02


def test_to_pyvista_with_z_scale_and_straight_down():
    c = gc.Camera.orbit((10.0, 20.0, -5.0), 0, 90, 8.0, z_scale=2.0)
    eye, focal, up = c.to_pyvista()
    assert eye == pytest.approx((10.0, 20.0, -2.0)) and focal == pytest.approx((10.0, 20.0, -10.0))
    assert up == pytest.approx((0.0, 1.0, 0.0))  # the axis the core uses when up is along the view
    back = gc.Camera.from_pyvista([eye, focal, up], fov_y=c.fov_y, z_scale=2.0)
    assert back.eye == pytest.approx(c.eye) and back.target == pytest.approx(c.target)
