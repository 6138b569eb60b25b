"""Every backend the Renderer accepts renders the same image (issue 18): Vulkan (lavapipe) and GL
(EGL + llvmpipe) side by side on scenes that stress depth, and the GEOCULL_BACKEND variable that
``backend="auto"`` honours (``make test-gl`` runs the render test files on GL with it)."""

import math

import numpy as np
import pytest

import geocull as gc

# Depth tolerance between backends, relative. Vulkan rasterises depth as z/w from the triangle's
# plane equation; GL writes frag_depth = z/w from perspective-interpolated clip z and w (see
# common.wgsl: GL's own depth path keeps only ~2^-24 absolute precision of reverse-Z depth). Both
# are f32 evaluations of the same value, a few units of 2^-24 apart: measured at most 3e-6
# relative over these scenes; 2e-5 leaves margin and is still far below any depth-ordering effect
# (the UTM layers are 0.5 m apart at 20 km: 2.5e-5).
DEPTH_RTOL = 2e-5


def renderer(backend, w, h):
    """A renderer on ``backend``; skips only where the machine has no such adapter (any other
    DeviceError, e.g. a pipeline the backend rejects, fails the test)."""
    try:
        return gc.Renderer(w, h, backend=backend)
    except gc.DeviceError as e:
        if "no graphics adapter found" not in str(e):
            raise
        pytest.skip(f"no {backend} adapter here: {e}")


def terrain_scene():
    rng = np.random.default_rng(18)
    s = gc.Scene()
    z = rng.normal(size=(120, 160)).cumsum(0).cumsum(1) * 0.05
    z[40:55, 60:90] = np.nan  # a hole
    s.add_heightfield(z, origin=(451_000.0, 6_780_000.0), spacing=(25.0, 25.0), tiles=(6, 5), coarse_factor=4)
    s.add_heightfield(z - 40.0, origin=(451_000.0, 6_780_000.0), spacing=(25.0, 25.0), tiles=(3, 3),
                      color=(0.2, 0.4, 0.9))
    t = np.linspace(0, 1, 30)
    u, v = np.meshgrid(t, t)
    verts = np.stack([451_000.0 + 2000 + 0 * u.ravel(), 6_780_000.0 + 500 + 2000 * u.ravel(),
                      -300 + 400 * v.ravel()], axis=1)
    i = np.arange(29)
    a = (i[:, None] * 30 + i[None, :]).ravel()
    faces = np.concatenate([np.stack([a, a + 1, a + 31], 1), np.stack([a, a + 31, a + 30], 1)])
    s.add_mesh(verts, faces, kind="fault", tiles=4, color=(0.9, 0.9, 0.2))
    return s


def utm_layers():
    s = gc.Scene()
    n, size = 41, 4000.0
    d = size / (n - 1)
    s.add_heightfield(np.full((n, n), -2500.0), origin=(450_000.0, 6_780_000.0), spacing=(d, d), tiles=(4, 4),
                      color=(1.0, 0.0, 0.0))
    s.add_heightfield(np.full((n - 4, n - 4), -2500.5), origin=(450_000.0 + 2 * d, 6_780_000.0 + 2 * d),
                      spacing=(d, d), tiles=(4, 4), color=(0.0, 0.0, 1.0))
    return s


def cases():
    c = np.array([452_000.0, 6_781_500.0, -2500.0])
    e = math.radians(20)
    eye = c + 20_000.0 * np.array([0.3 * math.cos(e), -math.cos(e), math.sin(e)]) / math.hypot(
        0.3 * math.cos(e), math.cos(e), math.sin(e))
    return {
        "terrain_oblique": (terrain_scene, gc.Camera.look_at((449_000.0, 6_777_000.0, 1500.0),
                                                             (453_000.0, 6_781_000.0, -100.0), fov_y=40)),
        "terrain_ortho_z_scale": (terrain_scene, gc.Camera.look_at(
            (449_000.0, 6_777_000.0, 1500.0), (453_000.0, 6_781_000.0, -100.0), projection="orthographic",
            ortho_height=3000.0, z_scale=3.0)),
        # UTM layers 0.5 m apart from 20 km with a 1 mm near plane: any blue pixel is a depth failure.
        "utm_tiny_near": (utm_layers, gc.Camera.look_at(tuple(eye), tuple(c), fov_y=20, near=1e-3)),
        # Camera between the two layers, looking along them (the automatic near plane is 1e-6).
        "inside": (utm_layers, gc.Camera.look_at((452_000.0, 6_781_500.0, -2500.25),
                                                 (452_500.0, 6_781_500.0, -2500.25), fov_y=90)),
    }


@pytest.fixture(scope="module")
def renderers():
    return {b: renderer(b, 96, 72) for b in ("vulkan", "gl")}


@pytest.mark.parametrize("case", list(cases()))
def test_vulkan_and_gl_render_the_same_image_and_depth(renderers, case):
    make, cam = cases()[case]
    scene = make()
    for mode in gc.CULLING_MODES:
        vk = renderers["vulkan"].render(scene, cam, culling=mode, pixel_threshold=0)
        gl = renderers["gl"].render(scene, cam, culling=mode, pixel_threshold=0)
        assert vk.coverage.sum() > 100, (case, mode)
        # Colour by z (the height fields' default) maps an interpolated scalar through a 256-row colour
        # map: the backends' interpolation may round a pixel onto the neighbouring row (a step of at
        # most a few 1/255 in viridis). Coverage, depth and tiles below are exact.
        diff = np.abs(gl.image.astype(int) - vk.image.astype(int)).max(axis=-1)
        assert diff.max() <= 4 and (diff > 0).mean() <= 1e-3, (case, mode, diff.max(), (diff > 0).sum())
        np.testing.assert_array_equal(gl.coverage, vk.coverage, err_msg=f"{case} {mode}")
        cov = vk.coverage
        np.testing.assert_allclose(gl.depth[cov], vk.depth[cov], rtol=DEPTH_RTOL, err_msg=f"{case} {mode}")
        np.testing.assert_array_equal(gl.tile_drawn, vk.tile_drawn, err_msg=f"{case} {mode}")
        np.testing.assert_array_equal(gl.tile_pixels, vk.tile_pixels, err_msg=f"{case} {mode}")
        if case == "utm_tiny_near":
            blue = (vk.image[..., 2] > 0) & (vk.image[..., 0] == 0)
            assert not blue.any(), (case, mode)


def test_vulkan_and_gl_render_the_same_isosurface(renderers):
    vol = gc.Volume(np.fromfunction(lambda k, j, i: np.hypot(np.hypot(i - 15.5, j - 15.5), k - 15.5), (32, 32, 32)),
                    origin=(0, 0, 0), spacing=(1, 1, 1))
    for cam in [gc.Camera.look_at((60, 40, 30), (15.5, 15.5, 15.5), fov_y=40),
                gc.Camera.look_at((15.5, 15.5, 15.5), (40, 20, 15.5), fov_y=90)]:  # inside the volume
        res = {b: r.render_isosurface(vol, 10.0, cam, return_map=True) for b, r in renderers.items()}
        vk, gl = res["vulkan"], res["gl"]
        assert vk.coverage.sum() > 100
        # Smooth normals are normalised per fragment, by GLSL on GL: a colour may differ by one
        # unit where the product rounds at .5 (measured: 1 channel of 1 pixel); none by more.
        assert np.abs(gl.image.astype(int) - vk.image.astype(int)).max() <= 1
        assert (gl.image != vk.image).any(axis=-1).sum() <= 3
        cov = vk.coverage
        np.testing.assert_allclose(gl.depth[cov], vk.depth[cov], rtol=DEPTH_RTOL)
        np.testing.assert_array_equal(gl.tile_drawn, vk.tile_drawn)


def test_auto_honours_geocull_backend(monkeypatch):
    monkeypatch.setenv("GEOCULL_BACKEND", "gl")
    renderer("gl", 8, 8)  # skips where there is no GL adapter
    assert "Gl" in gc.Renderer(8, 8).adapter_info
    # An explicit backend wins over the variable.
    assert "Vulkan" in renderer("vulkan", 8, 8).adapter_info
    monkeypatch.setenv("GEOCULL_BACKEND", "directx9")
    with pytest.raises(gc.InputError, match="GEOCULL_BACKEND.*directx9"):
        gc.Renderer(8, 8)
    monkeypatch.setenv("GEOCULL_BACKEND", "")
    gc.Renderer(8, 8)
