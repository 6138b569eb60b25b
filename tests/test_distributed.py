"""geocull.distributed.render_views on a LocalCluster of 2 worker processes: the same images as
serial renders, in the cameras' order, each worker building the scene once; the zarr store."""

from __future__ import annotations

import functools

import numpy as np
import pytest

import geocull as gc
from geocull import distributed as gd
from geocull.data import stacked_test_scene, standard_views

W, H = 48, 40


@pytest.fixture(scope="module")
def spec():
    return stacked_test_scene(n=16, n_horizons=2)


@pytest.fixture(scope="module")
def cameras(spec):
    base = [gc.Camera.look_at(**kw) for _, kw in standard_views(spec, aspect=W / H)[:3]]
    return base + [c.rotated(40.0, 5.0) for c in base]


@pytest.fixture(scope="module")
def serial(spec, cameras):
    scene = spec.build(tiles=(3, 3), coarse_factor=4)
    r = gc.Renderer(W, H)
    return [r.render(scene, c, culling="three_pass", pixel_threshold=5) for c in cameras]


@pytest.fixture(scope="module")
def client():
    dd = pytest.importorskip("distributed")
    with dd.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            dd.Client(cluster) as c:
        yield c


def test_serial_fallback_and_zarr_store(spec, cameras, serial, tmp_path):
    """Runs before the cluster exists (the module's client fixture is made by the later tests)."""
    pytest.importorskip("zarr")
    dd = pytest.importorskip("distributed")
    with pytest.raises(ValueError):
        dd.get_client()  # no client: render_views renders here
    source = functools.partial(spec.build, tiles=(3, 3), coarse_factor=4)
    g = gd.render_views(source, cameras[:2], None, W, H, store=str(tmp_path / "views.zarr"),
                        culling="three_pass", pixel_threshold=5)  # no client running: rendered here
    np.testing.assert_array_equal(np.asarray(g["image"][1]), serial[1].image)
    np.testing.assert_array_equal(np.asarray(g["depth"][0]), serial[0].depth)
    assert len(g.attrs["stats"]) == 2
    out = gd.render_views(source, cameras[2:3], None, W, H, culling="three_pass", pixel_threshold=5)
    np.testing.assert_array_equal(out[0].image, serial[2].image)
    assert out[0].worker == gd._worker_name()
    with pytest.raises(gc.InputError, match=r"cameras\[0\]"):
        gd.render_views(source, ["not a camera"], None, W, H)


def test_cluster_renders_the_serial_images(spec, cameras, serial, client):
    source = functools.partial(spec.build, tiles=(3, 3), coarse_factor=4)
    out = gd.render_views(source, cameras, client, W, H, culling="three_pass", pixel_threshold=5)
    assert len(out) == len(cameras)
    for got, want in zip(out, serial, strict=True):
        np.testing.assert_array_equal(got.image, want.image)
        np.testing.assert_array_equal(got.depth, want.depth)
        assert got.stats["tiles_drawn"] == want.stats["tiles_drawn"] and got.culling == "three_pass"
    # Again: nothing is rebuilt; every worker that rendered built the scene exactly once.
    again = gd.render_views(source, cameras, client, W, H, culling="three_pass", pixel_threshold=5)
    np.testing.assert_array_equal(again[-1].image, serial[-1].image)
    key = gd._spec_key(source)
    info = client.run(gd.worker_cache_info)
    builds = [i["builds"].get(key, 0) for i in info.values()]
    assert len(info) == 2 and sum(builds) >= 1 and max(builds) == 1, info
    assert gd._worker_name() not in {v.worker for v in out + again}  # rendered by the workers


def test_cluster_writes_a_zarr_store(spec, cameras, serial, client, tmp_path):
    pytest.importorskip("zarr")
    source = functools.partial(spec.build, tiles=(3, 3), coarse_factor=4)
    g = gd.render_views(source, cameras, client, W, H, store=str(tmp_path / "v.zarr"), culling="three_pass",
                        pixel_threshold=5)
    for i, want in enumerate(serial):
        np.testing.assert_array_equal(np.asarray(g["image"][i]), want.image)


def test_scene_objects_and_dict_cameras(spec, cameras, serial, client):
    scene = spec.build(tiles=(3, 3), coarse_factor=4)  # a built Scene travels as its bytes
    kw = dict(eye=cameras[0].eye, target=cameras[0].target, fov_y=cameras[0].fov_y)
    out = gd.render_views(scene, [kw], client, W, H, culling="three_pass", pixel_threshold=5)
    np.testing.assert_array_equal(out[0].image, serial[0].image)


def test_workers_build_a_lazy_volume_from_the_store(client, tmp_path):
    """VolumeStoreScene: only a description travels (no cube); each worker opens the zarr store
    itself, reads what its slice and isosurface need, and renders what a local build renders."""
    pytest.importorskip("zarr")
    import pickle

    from geocull.bench.big_volume import write_cube

    path = str(tmp_path / "cube.zarr")
    write_cube(path, 40)
    source = gd.VolumeStoreScene(path, spacing=(12.5, 12.5, 4.0), slices=(("inline", 20),), isovalue=0.0,
                                 cache_bytes=1 << 20)
    assert len(pickle.dumps(source)) < 1000
    local = source.build()
    assert local.n_triangles > 1000
    cams = [gc.Camera.fit(local, azimuth=az, elevation=25.0, aspect=W / H) for az in (30.0, 160.0, 250.0)]
    r = gc.Renderer(W, H)
    want = [r.render(local, c, culling="three_pass", pixel_threshold=0) for c in cams]
    out = gd.render_views(source, cams, client, W, H, culling="three_pass", pixel_threshold=0)
    for got, ref in zip(out, want, strict=True):
        np.testing.assert_array_equal(got.image, ref.image)
        np.testing.assert_array_equal(got.depth, ref.depth)
    assert gd._worker_name() not in {v.worker for v in out}
    with pytest.raises(gc.InputError, match="store"):
        gd.VolumeStoreScene(str(tmp_path / "missing.zarr")).build()
