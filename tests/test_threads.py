"""One Renderer, Scene or Volume used from several Python threads: calls wait for each other
(the core objects sit behind a lock taken with the GIL released) instead of failing with PyO3's
"Already borrowed", and every frame equals the same frame rendered serially."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import geocull as gc


def _scene(n=33):
    s = gc.Scene()
    y, x = np.mgrid[0:n, 0:n]
    for k in range(3):
        z = np.sin(x / 5.0 + k) * 2 + np.cos(y / 7.0) - 6.0 * k
        s.add_heightfield(z, spacing=(1.0, 1.0), tiles=(4, 4), coarse_factor=4)
    return s


def _cams(n=8):
    out = []
    for i in range(n):
        a = 2 * np.pi * i / n
        out.append(gc.Camera.look_at((16 + 40 * np.cos(a), 16 + 40 * np.sin(a), 25.0), (16.0, 16.0, -6.0)))
    return out


def test_one_renderer_and_scene_from_many_threads():
    r = gc.Renderer(48, 40)
    s = _scene()
    cams = _cams()
    modes = ["none", "three_pass", "frustum", "horizon"]
    jobs = [(c, m) for c in cams for m in modes]
    serial = [r.render(s, c, culling=m).image for c, m in jobs]

    grown = gc.Scene()
    z = np.zeros((9, 9))

    def work(i):
        c, m = jobs[i]
        if i % 4 == 0:  # writers and readers of another scene interleave with the frames
            grown.add_heightfield(z + i, tiles=(2, 2))
            grown.n_triangles, grown.tile_table()
        s.tile_table(), s.n_tiles  # readers of the rendered scene
        return r.render(s, c, culling=m).image

    with ThreadPoolExecutor(max_workers=6) as ex:
        images = list(ex.map(work, range(len(jobs))))
    for a, b in zip(images, serial, strict=True):
        np.testing.assert_array_equal(a, b)
    assert len(grown.object_ids()) == len(range(0, len(jobs), 4))


def test_isosurfaces_from_many_threads():
    n = 24
    c = np.linspace(-1, 1, n)
    vals = np.sqrt(c[:, None, None] ** 2 + c[None, :, None] ** 2 + c[None, None, :] ** 2)
    vol = gc.Volume(vals, origin=(-1, -1, -1), spacing=(2 / (n - 1),) * 3)
    r = gc.Renderer(32, 32)
    cam = gc.Camera.look_at((3.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    isos = [0.3, 0.5, 0.7, 0.9] * 3
    serial = {w: r.render_isosurface(vol, w, cam).image for w in isos}
    with ThreadPoolExecutor(max_workers=6) as ex:
        images = list(ex.map(lambda w: r.render_isosurface(vol, w, cam, culling="implicit").image, isos))
    for w, im in zip(isos, images, strict=True):
        np.testing.assert_array_equal(im, serial[w])


def test_renderers_sharing_one_device_render_concurrently():
    # Renderers on one backend share the process's device (and its pipelines): each renders its own
    # scene at its own size on its own thread, and every frame equals the one rendered alone
    # (threshold 0: temporal's image then does not depend on which frame came before).
    scenes = [_scene(n) for n in (17, 25, 33)]
    renderers = [gc.Renderer(40 + 8 * k, 32 + 4 * k) for k in range(3)]
    cams = _cams(4)
    jobs = [(k, c, m) for k in range(3) for c in cams for m in ("none", "three_pass", "temporal")]
    serial = [renderers[k].render(scenes[k], c, culling=m, pixel_threshold=0).image for k, c, m in jobs]
    assert len({r.adapter_info for r in renderers}) == 1

    def work(i):
        k, c, m = jobs[i]
        return renderers[k].render(scenes[k], c, culling=m, pixel_threshold=0).image

    with ThreadPoolExecutor(max_workers=6) as ex:
        images = list(ex.map(work, range(len(jobs))))
    for a, b in zip(images, serial, strict=True):
        np.testing.assert_array_equal(a, b)


def _render_in_child(q, cam):
    # Scene building is the core's CPU work (its own thread pool in a forked child); a renderer
    # needs a device, which a child forked from a process with one may not open.
    out: dict = {"triangles": _scene().n_triangles}
    try:
        out["image"] = gc.Renderer(48, 40).render(_scene(), cam, culling="three_pass").image
    except gc.DeviceError as e:
        out["error"] = str(e)
    q.put(out)


@pytest.mark.parametrize("method", ["fork", "spawn"])
def test_worker_processes_after_the_parent_rendered(method):
    # A child forked after its parent opened a device inherits the driver's state without its
    # threads: it builds scenes (it used to wait forever for rayon's threads) and gets a clear
    # DeviceError for a renderer instead of a crash at random; a spawned child renders.
    import multiprocessing as mp

    if method not in mp.get_all_start_methods():
        pytest.skip(f"no {method} on this platform")
    cam = _cams(1)[0]
    r = gc.Renderer(48, 40)
    ref = r.render(_scene(), cam, culling="three_pass").image
    ctx = mp.get_context(method)
    q = ctx.Queue()
    p = ctx.Process(target=_render_in_child, args=(q, cam))
    p.start()
    p.join(120)
    if p.is_alive():
        p.kill()
        pytest.fail("the child hung")
    assert p.exitcode == 0
    out = q.get(timeout=10)
    assert out["triangles"] == _scene().n_triangles
    if method == "fork":
        assert "image" not in out and "spawn" in out["error"] and "forked" in out["error"]
    else:
        np.testing.assert_array_equal(out["image"], ref)
