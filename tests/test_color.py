"""Colour by data: z and values through colour maps, clim ends, NaN colour, defaults, errors.

The lit pass multiplies an object's base colour by its shading, so each test renders a white
flat-coloured copy of the same geometry and view as the shading reference: a pixel coloured
through a colour map must be (map entry) x (white pixel) within rounding.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import geocull as gc

W, H = 64, 48
VIRIDIS_LO = np.array([68, 1, 84]) / 255.0
VIRIDIS_HI = np.array([253, 231, 37]) / 255.0


def top_view() -> gc.Camera:
    # Orthographic, straight down on the 0..10 x 0..10 square: x to the right, y up the image.
    return gc.Camera.look_at((5, 5, 50), (5, 5, 0), up=(0, 1, 0), projection="orthographic", ortho_height=12)


def flat_square(**kw) -> gc.Scene:
    s = gc.Scene()
    s.add_heightfield(np.zeros((11, 11)), spacing=(1, 1), **kw)
    return s


def shade(renderer_small) -> np.ndarray:
    img = renderer_small(W, H).render(flat_square(color=(1, 1, 1)), top_view()).image
    return img[..., :3] / 255.0


def test_clim_ends_map_to_the_colour_map_ends(renderer_small):
    # Left half at the low end of clim, right half at the high end (and beyond: clamped).
    v = np.zeros((11, 11))
    v[:, :5] = -3.0
    v[:, 6:] = 7.0
    img = renderer_small(W, H).render(flat_square(values=v, clim=(-3, 5)), top_view()).image[..., :3] / 255.0
    ref = shade(renderer_small)
    left, right = (H // 2, W // 2 - 12), (H // 2, W // 2 + 12)
    np.testing.assert_allclose(img[left], VIRIDIS_LO * ref[left], atol=2 / 255)
    np.testing.assert_allclose(img[right], VIRIDIS_HI * ref[right], atol=2 / 255)


def test_a_table_colour_map_and_nan_colour(renderer_small):
    v = np.ones((11, 11))
    v[:, 6:] = np.nan  # no data: the triangles touching it draw in nan_color
    red_to_blue = [[1, 0, 0], [0, 0, 1]]
    s = flat_square(values=v, cmap=red_to_blue, clim=(0, 1), nan_color=(0, 1, 0))
    img = renderer_small(W, H).render(s, top_view()).image[..., :3] / 255.0
    ref = shade(renderer_small)
    left, right = (H // 2, W // 2 - 12), (H // 2, W // 2 + 12)
    np.testing.assert_allclose(img[left], np.array([0, 0, 1]) * ref[left], atol=2 / 255)
    np.testing.assert_allclose(img[right], np.array([0, 1, 0]) * ref[right], atol=2 / 255)


def test_masked_values_are_no_data(renderer_small):
    v = np.ma.masked_array(np.ones((11, 11)), mask=np.zeros((11, 11), bool))
    v.mask[:, 6:] = True
    s = flat_square(values=v, cmap=[[1, 0, 0], [0, 0, 1]], clim=(0, 1), nan_color=(0, 1, 0))
    img = renderer_small(W, H).render(s, top_view()).image
    assert img[H // 2, W // 2 + 12, 1] > 100 and img[H // 2, W // 2 + 12, 2] == 0


def test_height_fields_are_coloured_by_z_by_default(renderer_small):
    # A ramp in y: bottom row z = 0, top row z = 10; viridis over the object's own z range.
    z = np.repeat(np.linspace(0, 10, 11)[:, None], 11, axis=1)
    s = gc.Scene()
    a = s.add_heightfield(z, spacing=(1, 1))
    info = s.object_info(a)
    assert (info["color_by"], info["cmap"], info["clim"]) == ("z", "viridis", (0.0, 10.0))
    img = renderer_small(W, H).render(s, gc.Camera.look_at((5, 5, 60), (5, 5, 5), up=(0, 1, 0))).image
    ys = np.nonzero(img[:, W // 2, :3].sum(axis=-1) > 0)[0]
    top, bottom = img[ys.min() + 1, W // 2, :3].astype(float), img[ys.max() - 1, W // 2, :3].astype(float)
    # viridis: yellow at the top (high z), purple at the bottom; compare hues, shading aside.
    assert top[1] > top[2] and bottom[2] > bottom[1]
    # Meshes stay flat unless asked.
    m = s.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    assert s.object_info(m)["color_by"] is None


def test_mesh_vertex_values_and_set_color_by(renderer_small):
    v = [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]]
    f = [[0, 1, 2], [0, 2, 3]]
    s = gc.Scene()
    a = s.add_mesh(v, f, values=[0.0, 0.0, 0.0, 0.0], cmap=[[1, 0, 0], [0, 0, 1]], clim=(0, 1))
    r = renderer_small(W, H)
    img = r.render(s, top_view()).image
    assert img[H // 2, W // 2, 0] > 0 and img[H // 2, W // 2, 2] == 0
    s.set_color_by(a, "values", cmap=[[1, 0, 0], [0, 0, 1]], clim=(-1, 0))
    img = r.render(s, top_view()).image
    assert img[H // 2, W // 2, 2] > 0 and img[H // 2, W // 2, 0] == 0
    s.set_color(a, (0, 1, 0))
    assert s.object_info(a)["color_by"] is None
    img = r.render(s, top_view()).image
    assert img[H // 2, W // 2, 1] > 0 and img[H // 2, W // 2, 0] == img[H // 2, W // 2, 2] == 0


def test_a_triangle_touching_no_data_is_no_data_to_its_valid_corners(renderer_small):
    # Values 1, 1 and NaN, the NaN corner 1 km off: in view, no data's weight is under 1.2 %, where
    # the map's low end (red) once showed (only a weight above 3 % was no data). Every pixel of the
    # triangle is the NaN colour.
    s = gc.Scene()
    s.add_mesh([[0, 0, 0], [10, 0, 0], [5, 1000, 0]], [[0, 1, 2]], values=[1.0, 1.0, np.nan],
               cmap=[[1, 0, 0], [0, 0, 1]], clim=(0, 1), nan_color=(0, 1, 0))
    img = renderer_small(W, H).render(s, top_view()).image[..., :3].astype(int)
    lit = img.sum(axis=-1) > 0
    assert lit.sum() > 500
    assert (img[lit][:, 0] == 0).all() and (img[lit][:, 2] == 0).all() and (img[lit][:, 1] > 0).all()


def test_colouring_survives_pickling(renderer_small):
    v = np.random.default_rng(1).random((11, 11))
    s = flat_square(values=v, cmap="seismic")
    t = pickle.loads(pickle.dumps(s))
    r = renderer_small(W, H)
    np.testing.assert_array_equal(r.render(s, top_view()).image, r.render(t, top_view()).image)
    assert t.object_info(0)["cmap"] == "seismic"


@pytest.mark.parametrize(
    ("kw", "arg"),
    [
        (dict(values=np.zeros((10, 11))), "values"),
        (dict(values=np.zeros((11, 11)), color=(1, 0, 0)), "color"),
        (dict(cmap="no-such-map"), "cmap"),
        (dict(cmap=[[0, 0, 2], [1, 1, 1]]), "cmap"),
        (dict(clim=(1, 1)), "clim"),
        (dict(clim=(0, 1e31)), "clim"),
        (dict(color_by="values"), "values"),
        (dict(color_by="depth"), "color_by"),
        (dict(values=np.full((11, 11), np.inf)), "values"),
        (dict(nan_color=(2, 0, 0), values=np.zeros((11, 11))), "nan_color"),
    ],
)
def test_errors_name_the_argument(kw, arg):
    with pytest.raises(gc.InputError, match=rf"^{arg}"):
        flat_square(**kw)


def test_set_color_by_values_needs_values():
    s = gc.Scene()
    a = s.add_heightfield(np.zeros((3, 3)), color=(1, 1, 1))
    with pytest.raises(gc.InputError, match="^color_by"):
        s.set_color_by(a, "values")
    s.set_color_by(a, "z", cmap="gray")
    assert s.object_info(a)["cmap"] == "gray"


def test_a_vertical_well_seen_from_the_side_covers_its_column(renderer_small):
    # Orthographic side view, 2 m per pixel: pixel centres at x = 2 col - 99 and z = 49 - 2 row. The
    # tube's silhouette half-width lies in [r cos(pi / 8), r] = [4.16, 4.5]: columns with centres
    # |x| <= 3 (48..51) are covered, |x| >= 5 not; the well spans z in [-100, 0]: rows 25..74.
    s = gc.Scene()
    s.add_well([[0, 0, 0], [0, 0, -40], [0, 0, -100]], radius=4.5, color=(1, 1, 1))
    cam = gc.Camera.look_at((0, -500, -50), (0, 0, -50), projection="orthographic", ortho_height=200)
    cov = renderer_small(100, 100).render(s, cam).coverage
    want = np.zeros((100, 100), bool)
    want[25:75, 48:52] = True
    np.testing.assert_array_equal(cov, want)


def test_a_well_log_colours_the_tube(renderer_small):
    s = gc.Scene()
    s.add_well([[0, 0, 0], [0, 0, -100]], radius=20, values=[0.0, 1.0], cmap=[[1, 0, 0], [0, 0, 1]])
    img = renderer_small(100, 100).render(
        s, gc.Camera.look_at((0, -500, -50), (0, 0, -50), projection="orthographic", ortho_height=200)).image
    top, bottom = img[27, 50], img[72, 50]
    assert top[0] > top[2] and bottom[2] > bottom[0]
    with pytest.raises(gc.InputError, match="^values"):
        s.add_well([[0, 0, 0], [0, 0, -100]], values=[1.0, 2.0, 3.0])
    with pytest.raises(gc.InputError, match="^path"):
        s.add_well([[0, 0, 0]])


def salt_ball() -> tuple[gc.Volume, np.ndarray]:
    # A ball of radius 30 m (distance field) about (50, 50, -60), sampled every 5 m, at UTM-sized
    # coordinates; and the sample positions' x, y, z.
    o = np.array([456000.0, 6780000.0, -120.0])
    x, y, z = np.meshgrid(*(o[a] + 5.0 * np.arange(n) for a, n in enumerate((21, 21, 25))), indexing="ij")
    d = np.sqrt((x - o[0] - 50) ** 2 + (y - o[1] - 50) ** 2 + (z + 60) ** 2).astype(np.float32)
    return gc.Volume(d, origin=o, spacing=(5, 5, 5), order="xyz"), np.stack([x, y, z])


def test_an_isosurface_shows_a_second_volume_through_the_colour_map(renderer_small):
    # (The values at the vertices, interpolated along their edges, are checked exactly in
    # iso::mesh's tests; here what the surface shows.) Amplitude 1, no data east of x0 + 62 m.
    vol, (x, y, z) = salt_ball()
    amp = np.where(x > x.min() + 62, np.nan, 1.0)
    avol = gc.Volume(amp, origin=vol.origin, spacing=vol.spacing, order="xyz")
    s = gc.Scene()
    s.add_isosurface(vol, 30.0, tiles=4, values=avol, cmap=[[1, 0, 0], [0, 0, 1]], clim=(0, 1), nan_color=(0, 1, 0))
    white = gc.Scene()
    white.add_isosurface(vol, 30.0, tiles=4, color=(1, 1, 1))
    r = renderer_small(64, 48)
    c = np.array(vol.origin) + [50, 50, 60]
    for cam in (gc.Camera.look_at(c + [0, -100, 0], c), gc.Camera.look_at(c + [70, 50, 40], c)):
        img = r.render(s, cam).image[..., :3] / 255.0
        ref = r.render(white, cam).image[..., :3] / 255.0
        lit = ref.sum(axis=-1) > 0.1
        # Each lit pixel is the map's blue (amplitude 1) or the no-data green, times the shading.
        blue = np.abs(img - np.array([0, 0, 1]) * ref).max(axis=-1) <= 2 / 255
        green = np.abs(img - np.array([0, 1, 0]) * ref).max(axis=-1) <= 2 / 255
        assert (blue | green)[lit].all()
        assert blue[lit].sum() > 100 and green[lit].sum() > 100, (blue[lit].sum(), green[lit].sum())
    # Coloured by them, clim defaults to the second volume's finite range, as its slices' would.
    lin = gc.Volume(0.1 * (x - x.min()) - 0.05 * z, origin=vol.origin, spacing=vol.spacing, order="xyz")
    t = s.add_isosurface(vol, 30.0, values=lin)
    info = s.object_info(t)
    assert info["color_by"] == "values"
    assert info["clim"] == pytest.approx((-0.05 * z.max(), 0.1 * 100 - 0.05 * z.min()), rel=1e-6)


@pytest.mark.parametrize(
    ("kw", "arg"),
    [
        (dict(values=np.zeros((21, 21, 25))), "values"),
        (dict(values="shape"), "values"),
        (dict(values="spacing"), "values"),
        (dict(color_by="values"), "values"),
        (dict(values="same", color=(1, 0, 0)), "color"),
        (dict(values="same", color_by="z"), "values"),
    ],
)
def test_isosurface_values_errors_name_the_argument(kw, arg):
    vol, _ = salt_ball()
    other = {
        "same": gc.Volume(np.zeros((21, 21, 25), np.float32), origin=vol.origin, spacing=vol.spacing, order="xyz"),
        "shape": gc.Volume(np.zeros((21, 21, 24), np.float32), origin=vol.origin, spacing=vol.spacing, order="xyz"),
        "spacing": gc.Volume(np.zeros((21, 21, 25), np.float32), origin=vol.origin, spacing=(5, 5, 4), order="xyz"),
    }
    if isinstance(kw.get("values"), str):
        kw = {**kw, "values": other[kw["values"]]}
    with pytest.raises(gc.InputError, match=rf"^{arg}"):
        gc.Scene().add_isosurface(vol, 30.0, **kw)
