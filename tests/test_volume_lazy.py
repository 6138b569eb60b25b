"""Volumes larger than memory: a lazy Volume (zarr, dask, xarray, np.memmap, SEG-Y) gives the slices,
isosurfaces and implicit images of the same volume in memory, reads only what it needs and keeps
its brick cache within its budget."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import geocull as gc

zarr = pytest.importorskip("zarr")

N = 64
BRICK = 4 * 32**3  # bytes of a cached brick


def salt(n: int = N, dtype: type = np.float32) -> np.ndarray:
    """Two overlapping blobs (a salt body), (z, y, x), negative inside, NaN in one corner."""
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float64) / (n - 1)
    a = np.minimum(np.sqrt((x - 0.4) ** 2 + (y - 0.5) ** 2 + (z - 0.45) ** 2) - 0.3,
                   np.sqrt((x - 0.7) ** 2 + (y - 0.45) ** 2 + (z - 0.6) ** 2) - 0.2)
    a += 0.02 * np.sin(17 * x) * np.cos(13 * y)
    a[:3, :3, :3] = np.nan
    return a.astype(dtype)


def as_zarr(a: np.ndarray, tmp_path, chunks=(16, 16, 16), name="v"):
    z = zarr.open_array(str(tmp_path / f"{name}.zarr"), mode="w", shape=a.shape, chunks=chunks, dtype=a.dtype)
    z[:] = a
    return z


GEOM = {"origin": (100.0, 200.0, -50.0), "spacing": (10.0, 12.5, 4.0)}


@pytest.fixture(scope="module")
def renderer():
    return gc.Renderer(64, 64)


def camera(v: gc.Volume) -> gc.Camera:
    lo, hi = v.bounds
    c = tuple((a + b) / 2 for a, b in zip(lo, hi, strict=True))
    span = max(b - a for a, b in zip(lo, hi, strict=True))
    return gc.Camera.look_at((c[0] + 1.6 * span, c[1] - 1.1 * span, c[2] + 0.8 * span), c)


def test_a_zarr_volume_is_lazy_and_equals_the_numpy_one(tmp_path):
    a = salt()
    v = gc.Volume(a, **GEOM)
    lz = gc.Volume(as_zarr(a, tmp_path), **GEOM, cache_bytes=2 * BRICK)
    assert lz.is_lazy and not v.is_lazy and lz.bytes_read == 0, "nothing read at construction"
    assert (lz.shape, lz.origin, lz.spacing, lz.offset) == (v.shape, v.origin, v.spacing, v.offset)
    assert lz.max_depth() == v.max_depth()
    assert lz.bytes_read <= 4 * a.size * 9 // 8 + 4 * N * N, "one streaming pass"
    # (The stored depths; finer ones scan samples node by node: the Rust tests compare those.)
    for d in range(v.max_depth() - 2):
        for k in ("min", "max", "index"):
            np.testing.assert_array_equal(lz.nodes(d)[k], v.nodes(d)[k])
    for w in (0.0, 0.05):
        va, fa = gc.extract_isosurface(v, w)
        vb, fb = gc.extract_isosurface(lz, w)
        np.testing.assert_array_equal(va, vb)
        np.testing.assert_array_equal(fa, fb)
    scenes = [gc.Scene() for _ in range(2)]
    for s, vol in zip(scenes, (v, lz), strict=True):
        s.add_isosurface(vol, 0.02, values=vol, color_by="values")
    assert scenes[0].to_bytes() == scenes[1].to_bytes(), "add_isosurface, coloured by a lazy volume's values"
    budget, held, peak = lz.cache_info
    assert budget == 2 * BRICK and held <= budget and peak <= budget


@pytest.mark.parametrize("order,z_positive,yflip", [("zyx", "up", False), ("xyz", "down", True)])
def test_layouts_read_the_same_samples(tmp_path, order, z_positive, yflip):
    a = salt(40)
    if order == "xyz":
        a = np.ascontiguousarray(a.transpose(2, 1, 0))
    kw = dict(GEOM, order=order, z_positive=z_positive, yflip=yflip, rotation=30.0)
    v = gc.Volume(a, **kw)
    lz = gc.Volume(as_zarr(a, tmp_path, (8, 16, 8)), **kw)
    assert (lz.origin, lz.bounds) == (v.origin, v.bounds)
    for w in (0.0, 0.1):
        va, fa = gc.extract_isosurface(v, w)
        vb, fb = gc.extract_isosurface(lz, w)
        np.testing.assert_array_equal(va, vb)
        np.testing.assert_array_equal(fa, fb)


def test_float64_dask_and_xarray_sources(tmp_path):
    da = pytest.importorskip("dask.array")
    xr = pytest.importorskip("xarray")
    a = salt(40, np.float64) + 1e8  # residuals about the midrange, as in memory
    v = gc.Volume(a, **GEOM)
    d = da.from_array(a, chunks=(16, 16, 16))
    lz = gc.Volume(d, **GEOM)
    assert lz.is_lazy and lz.offset == v.offset
    np.testing.assert_array_equal(gc.extract_isosurface(lz, 1e8)[0], gc.extract_isosurface(v, 1e8)[0])
    x = xr.DataArray(d, dims=("depth", "y", "x"),
                     coords={"depth": 50.0 + 4.0 * np.arange(40), "y": 200 + 12.5 * np.arange(40),
                             "x": 100 + 10.0 * np.arange(40)})
    lx, vx = gc.Volume(x), gc.Volume(x.compute())
    assert lx.is_lazy and not vx.is_lazy and lx.origin == vx.origin
    np.testing.assert_array_equal(gc.extract_isosurface(lx, 1e8)[0], gc.extract_isosurface(vx, 1e8)[0])


def test_a_memmap_is_read_lazily_when_asked(tmp_path):
    a = salt(40)
    m = np.lib.format.open_memmap(str(tmp_path / "v.npy"), mode="w+", dtype=np.float32, shape=a.shape)
    m[:] = a
    assert not gc.Volume(m).is_lazy, "a memory map is loaded unless lazy=True"
    lz = gc.Volume(m, lazy=True, cache_bytes=0)
    assert lz.is_lazy
    np.testing.assert_array_equal(gc.extract_isosurface(lz, 0.0)[0], gc.extract_isosurface(gc.Volume(a), 0.0)[0])
    assert lz.cache_info[1] == 0, "a budget of 0 keeps no brick"
    assert not gc.Volume(as_zarr(a, tmp_path), lazy=False).is_lazy


def test_slices_equal_and_a_move_reads_its_bricks_once(tmp_path, renderer):
    a = salt()
    v = gc.Volume(a, **GEOM)
    lz = gc.Volume(as_zarr(a, tmp_path), **GEOM)
    scenes = []
    for vol in (v, lz):
        s = gc.Scene()
        s.add_slice(vol, "inline", 20)
        scenes.append((s, s.add_slice(vol, "sample", 10)))
    cam = camera(v)
    assert np.array_equal(renderer.render(scenes[0][0], cam).image, renderer.render(scenes[1][0], cam).image)
    before = lz.bytes_read
    for (s, sid) in scenes:
        s.set_slice_index(sid, 40)
    assert lz.bytes_read - before == 4 * N * N * 32, "the 64 x 64 x 32 bricks of layers 32..63"
    assert np.array_equal(renderer.render(scenes[0][0], cam).image, renderer.render(scenes[1][0], cam).image)
    before = lz.bytes_read
    for (s, sid) in scenes:
        s.set_slice_index(sid, 63)
    assert lz.bytes_read == before, "a move within the same bricks reads nothing"
    assert np.array_equal(renderer.render(scenes[0][0], cam).image, renderer.render(scenes[1][0], cam).image)
    # A cache whose quarter the bricks do not fit in: each move reads its plane alone.
    small = gc.Volume(as_zarr(a, tmp_path, name="small"), cache_bytes=4 * 4 * N * N * 32 - 4, **GEOM)
    s = gc.Scene()
    sid = s.add_slice(small, "sample", 10)
    before = small.bytes_read
    s.set_slice_index(sid, 11)
    assert small.bytes_read - before == 4 * N * N, "one plane of 64 x 64 float32"
    assert small.cache_info[1] == 0
    # A scene pickles its slices' geometry, not their volume (lazy or not).
    again = pickle.loads(pickle.dumps(scenes[1][0]))
    assert np.array_equal(renderer.render(again, cam).image, renderer.render(scenes[0][0], cam).image)


def test_implicit_frames_equal_the_numpy_ones_and_count_bytes_read(tmp_path, renderer):
    a = salt()
    v = gc.Volume(a, **GEOM)
    lz = gc.Volume(as_zarr(a, tmp_path), **GEOM, cache_bytes=16 * BRICK)
    cam = camera(v)
    d = v.max_depth() - 3
    want = renderer.render_isosurface(v, 0.0, cam, occluder_depth=d, cull_depth=d)
    got = renderer.render_isosurface(lz, 0.0, cam)
    assert (got.stats["occluder_depth"], got.stats["cull_depth"]) == (d, d), "a lazy volume's defaults"
    np.testing.assert_array_equal(got.image, want.image)
    assert want.stats["bytes_read"] == 0
    assert 0 < got.stats["bytes_read"] <= lz.bytes_read
    assert got.stats["brick_cache_bytes"] <= 16 * BRICK
    again = renderer.render_isosurface(lz, 0.0, cam)
    assert again.stats["bytes_read"] == 0, "the patches are cached"
    np.testing.assert_array_equal(again.image, want.image)
    none = renderer.render_isosurface(lz, 0.0, cam, culling="none", cache=False)
    np.testing.assert_array_equal(none.image, want.image)


def test_bad_inputs_name_their_argument(tmp_path):
    a = salt(16)
    z = as_zarr(a, tmp_path)
    with pytest.raises(gc.InputError, match="^cache_bytes"):
        gc.Volume(z, cache_bytes=-1)
    with pytest.raises(gc.InputError, match="^cache_bytes"):
        gc.Volume(a, cache_bytes=1 << 20)
    with pytest.raises(gc.InputError, match="^lazy"):
        gc.Volume(z, lazy="yes")
    with pytest.raises(gc.InputError, match="^values"):
        gc.Volume([[[1.0]]], lazy=True)
    with pytest.raises(gc.InputError, match="^values"):
        gc.Volume(zarr.zeros((4, 1, 4), dtype="f4"))
    with pytest.raises(gc.InputError, match="^spacing"):
        gc.Volume(z, spacing=(1, 0, 1))
    bad = a.copy()
    bad[5, 6, 7] = np.inf
    lz = gc.Volume(as_zarr(bad, tmp_path, name="bad"), z_positive="up")
    with pytest.raises(gc.InputError, match="^values.*infinite"):
        lz.max_depth()
    with pytest.raises(gc.InputError, match="^values.*infinite"):
        lz.to_bytes()
    with pytest.raises(gc.InputError, match="^volume: a lazy volume is not pickled"):
        pickle.dumps(gc.Volume(z))
    assert gc.Volume.from_bytes(gc.Volume(z).to_bytes()).shape == (16, 16, 16), "to_bytes reads every sample"


def test_read_errors_are_input_errors(tmp_path):
    class Broken:
        shape, dtype, ndim = (8, 8, 8), np.dtype(np.float32), 3

        def __getitem__(self, key):
            raise OSError("disk on fire")

    lz = gc.Volume(Broken(), lazy=True)
    with pytest.raises(gc.InputError, match="^values: reading the volume's samples failed.*disk on fire"):
        lz.max_depth()


def test_bench_big_volume_tiny():
    from geocull.bench import big_volume, cli

    cfg = cli.config(cli.parser().parse_args(["--scene", "big-volume", "--tiny"]))
    assert (cfg["big_n"], cfg["cache_mib"]) == (48, 16)
    res = big_volume.run(dict(cfg, width=48, height=48))
    # Moves 16 -> 23, 30, 37, 44: only 37 leaves the bricks of x 0..31 (and reads x 32..47).
    assert (res["slice_moves"], res["slice_moves_cold"]) == (4, 1)
    assert res["slice_move_read"] == 4 * 16 * 48 * 48, "a move reads its plane's bricks"
    assert res["cache_peak"] <= 16 << 20 and res["peak_rss"] > 0
    assert [v["equal"] for v in res["views"]] == [True] * 3
    assert all(0 < v["bytes_read"] <= res["cube_bytes"] for v in res["views"])
    assert "peak RSS" in big_volume.format_table(res)


@pytest.mark.parametrize("kind", ["inline", "crossline", "missing_and_dead"])
def test_a_segy_file_opened_lazily_reads_nothing_and_equals_the_loaded_one(tmp_path, kind):
    pytest.importorskip("segyio")
    from test_io_segy import write_cube

    kw: dict = {"sorting": "crossline"} if kind == "crossline" else {}
    if kind == "missing_and_dead":
        kw = {"skip": {(1, 2), (3, 3)}, "dead": {(0, 0), (2, 5)}}
    path = write_cube(tmp_path / "c.sgy", rotation=-30.0, handed=-1.0, **kw)
    v = gc.Volume.from_segy(path)
    lz = gc.Volume.from_segy(path, lazy=True, cache_bytes=1 << 20)
    assert lz.is_lazy and lz.bytes_read == 0
    assert (lz.shape, lz.origin, lz.spacing, lz.rotation) == (v.shape, v.origin, v.spacing, v.rotation)
    np.testing.assert_array_equal(lz.inlines, v.inlines)
    w = float(np.nanmedian(v.nodes(0)["min"]) + np.nanmedian(v.nodes(0)["max"])) / 2
    for a, b in zip(gc.extract_isosurface(lz, w), gc.extract_isosurface(v, w), strict=True):
        np.testing.assert_array_equal(a, b)
    scenes = [gc.Scene() for _ in range(2)]
    for s, vol in zip(scenes, (v, lz), strict=True):
        s.add_slice(vol, "crossline", 3)
    np.testing.assert_array_equal(scenes[0].to_bytes(), scenes[1].to_bytes())
