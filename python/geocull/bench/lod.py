"""``python -m geocull bench --scene lod``: the LOD build of mesh tiles, geocull (meshoptimizer)
against fast-simplification, side by side.

geocull builds every mesh tile's levels of detail at ``add_mesh`` time: meshoptimizer's quadric
simplification of the previous level to about a quarter of its triangles, the tile's border
locked (so that tiles drawn at different levels meet without cracks), up to 5 levels
(``Scene.tile_table()``'s ``level_triangles`` / ``level_error``). The scene: the Gullfaks-like
spec's faults (one tile each) and its horizons as triangle meshes (``add_mesh`` with about
``TRIS_PER_TILE`` triangles per tile), so that every tile goes through meshoptimizer.

The baseline, fast-simplification (``pip install geocull[bench]``, imported on first use),
simplifies the *same tiles* (their fine triangles, read from ``Scene.to_bytes``) to the *same
triangle counts*, level by level from the previous one as geocull does, once with its
``preserve_border`` (the constraint geocull's levels keep) and once without.

Build time: geocull's is the wall time of ``add_mesh`` for all the scene's meshes (tiling, coarse
proxies, normals and the levels: an upper bound for its level building), on all cores and, in a
child process with ``RAYON_NUM_THREADS=1``, on one; fast-simplification's the sum of its calls, one
thread. Geometric error of each level against its
tile's fine surface (exact point-to-surface distances, VTK's ``vtkImplicitPolyDataDistance`` through
PyVista): from the level's vertices, triangle centres and edge midpoints to the fine surface, and
from the fine vertices and triangle centres to the level; ``max`` is the larger of the two
directions' maxima (a symmetric Hausdorff estimate), ``mean`` the mean over both samples; per level,
the worst tile's max and the mean over tiles, in metres. geocull's own estimate (meshoptimizer's
error, ``level_error``) is shown beside its measured error.
"""

from __future__ import annotations

import os
import struct
import sys
import time
from typing import Any

import numpy as np

__all__ = ["run", "format_table", "scene_tiles", "surface_distance", "level_error", "lod_config"]

#: About this many fine triangles per horizon-mesh tile (the height-field tiles of the Gullfaks-like
#: benchmark scene hold 3,500).
TRIS_PER_TILE = 4000
METHODS = ("meshoptimizer (geocull)", "fast-simplification, border kept", "fast-simplification, border free")
_SERIAL_VERSION = 12  # Scene.to_bytes's layout read by scene_tiles (src/scene/serial.rs)


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def lod_config(mode: str) -> dict[str, Any]:
    """The LOD benchmark's part of :func:`geocull.bench.cli.config` for ``mode`` tiny / quick / full:
    samples per horizon side, horizons and faults."""
    if mode == "tiny":
        return dict(size=40, n_horizons=1, n_faults=2, fault_triangles=(500, 2000))
    if mode == "quick":
        return dict(size=80, n_horizons=2, n_faults=4, fault_triangles=(2000, 20000))
    return dict(size=200, n_horizons=4, n_faults=16, fault_triangles=(2000, 20000))


class _Reader:
    """Little-endian reader of ``Scene.to_bytes``'s layout."""

    def __init__(self, data: bytes) -> None:
        self.b, self.i = memoryview(data), 0

    def take(self, fmt: str) -> tuple[Any, ...]:
        v = struct.unpack_from("<" + fmt, self.b, self.i)
        self.i += struct.calcsize("<" + fmt)
        return v

    def u8(self) -> int:
        return int(self.take("B")[0])

    def u32(self) -> int:
        return int(self.take("I")[0])

    def u64(self) -> int:
        return int(self.take("Q")[0])

    def text(self) -> str:
        n = self.u32()
        s = bytes(self.b[self.i:self.i + n]).decode()
        self.i += n
        return s

    def array(self, dtype: str) -> np.ndarray:
        n = self.u64()
        a = np.frombuffer(self.b, dtype=np.dtype(dtype).newbyteorder("<"), count=n, offset=self.i)
        self.i += 4 * n
        return a


def scene_tiles(scene: Any) -> list[dict[str, Any]]:
    """Every tile of ``scene``'s mesh objects as stored, read from ``scene.to_bytes()`` (its layout,
    version 12, is documented in the core's ``scene/serial.rs``): dicts with object (id), kind (the
    mesh's label), positions (n, 3) float32 (relative to the scene's origin), fine (m, 3) uint32 and
    levels, a list of (error in metres, (k, 3) uint32 indices into positions) for levels 1, 2, ...
    Height-field and grid tiles (whose levels are lattices, not meshoptimizer's) are skipped."""
    r = _Reader(scene.to_bytes())
    if bytes(r.b[:8]) != b"GCSCENE\0":
        raise ValueError("scene_tiles: not a geocull scene")
    r.i = 8
    version = r.u32()
    if version != _SERIAL_VERSION:
        raise ValueError(f"scene_tiles reads Scene.to_bytes version {_SERIAL_VERSION}, got {version}: "
                         "update geocull.bench.lod to the new layout")
    n_objects = int(r.take("B3dII")[-1])  # has_origin, origin, next_id, n_objects
    out = []
    for _ in range(n_objects):
        oid = r.u32()
        r.text()  # name
        kind_tag = r.u8()
        label = ""
        if kind_tag == 0:  # height field: nx, ny, x0, y0, dx, dy, rotation, tx, ty
            r.take("QQdddddQQ")
        elif kind_tag == 1:
            label = r.text()
        elif kind_tag == 2:  # grid: dims, blocks, cell sizes, levels, block levels
            r.take("QQQQQ")
            r.array("f4")
            for _ in range(r.u32()):
                r.take("QQQQdQ")
            for _ in range(r.u32()):
                for _ in range(r.u32()):
                    r.take("QQQQdQ")
        else:
            raise ValueError(f"scene_tiles: unknown object kind {kind_tag}")
        r.take("fffBdddddd")  # color, visible, offset, origin
        if r.u8():  # color_by: cmap, lut, clim, nan_color
            r.text()
            r.array("f4")
            r.take("ddfff")
        r.take("fB")  # opacity, priority
        for _ in range(r.u32()):
            r.take("II6f")  # ix, iy, bbox
            pos = r.array("f4")
            for dt in ("f4", "u4", "u4", "f4", "f4"):  # values, normals, grid_uv, ring_z, stations
                r.array(dt)
            fine = r.array("u4")
            r.array("u4")  # coarse proxy
            r.take("f")  # proxy_error
            levels = []
            for _ in range(r.u32()):
                err, _shading, _error_z = r.take("fff")
                levels.append((float(err), r.array("u4").reshape(-1, 3)))
                r.take("f")  # group error (height fields' group variants, lod::groups)
                for _ in range(r.u32()):
                    r.array("u4")
            if kind_tag == 1 and len(fine):
                out.append(dict(object=oid, kind=label, positions=pos.reshape(-1, 3), fine=fine.reshape(-1, 3),
                                levels=levels))
    return out


def surface_distance(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Distance (n,) from each of ``points`` (n, 3) to the nearest point of the triangle surface
    (``vertices``, ``faces``): VTK's vtkImplicitPolyDataDistance (needs PyVista)."""
    import pyvista as pv
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkDoubleArray
    from vtkmodules.vtkFiltersCore import vtkImplicitPolyDataDistance

    f = np.asarray(faces, np.int64)
    mesh = pv.PolyData(np.asarray(vertices, np.float64), np.hstack([np.full((len(f), 1), 3), f]).ravel())
    fn = vtkImplicitPolyDataDistance()
    fn.SetInput(mesh)
    out = vtkDoubleArray()
    pts = numpy_to_vtk(np.ascontiguousarray(points, np.float64), deep=True)
    fn.FunctionValue(pts, out)
    return np.abs(vtk_to_numpy(out))


def _samples(v: np.ndarray, f: np.ndarray, midpoints: bool) -> np.ndarray:
    """The points of a mesh the distances are taken from: its vertices (those in use), triangle
    centres and (``midpoints``) edge midpoints."""
    t = v[f]
    pts = [v[np.unique(f)], t.mean(axis=1)]
    if midpoints:
        pts += [(t[:, 0] + t[:, 1]) / 2, (t[:, 1] + t[:, 2]) / 2, (t[:, 2] + t[:, 0]) / 2]
    return np.concatenate(pts)


def level_error(fine_v: np.ndarray, fine_f: np.ndarray, v: np.ndarray, f: np.ndarray) -> tuple[float, float]:
    """(max, mean) distance between a level (``v``, ``f``) and its fine surface (``fine_v``,
    ``fine_f``), both directions (see the module's docs), metres."""
    if len(f) == 0:
        return float("nan"), float("nan")
    a = surface_distance(_samples(v, f, True), fine_v, fine_f)
    b = surface_distance(_samples(fine_v, fine_f, False), v, f)
    return float(max(a.max(), b.max())), float(np.concatenate([a, b]).mean())


def _fs() -> Any:
    try:
        import fast_simplification
    except ImportError as e:
        raise ImportError("bench --scene lod compares with fast-simplification, which is not installed: "
                          "pip install 'geocull[bench]' (or pip install fast-simplification)") from e
    return fast_simplification


def _fs_levels(v: np.ndarray, f: np.ndarray, counts: list[int], border: bool) -> list[tuple[np.ndarray, np.ndarray,
                                                                                          float]]:
    """fast-simplification's levels of one tile: each from the previous one to ``counts[k]``
    triangles; (vertices, faces, seconds) per level."""
    fs = _fs()
    out = []
    cur_v, cur_f = v.astype(np.float64), f.astype(np.int32)
    for n in counts:
        t0 = time.perf_counter()
        nv, nf = fs.simplify(cur_v, cur_f, target_count=int(n), preserve_border=border)
        dt = time.perf_counter() - t0
        out.append((nv, nf, dt))
        cur_v, cur_f = nv, nf.astype(np.int32)
    return out


def build_scene(cfg: dict[str, Any]) -> tuple[Any, float, int]:
    """The benchmark's scene: the Gullfaks-like spec's faults and horizons, all as meshes; returns
    (scene, seconds in add_mesh, fine triangles)."""
    import geocull as gc

    from ..data import gullfaks_like, heightfield_mesh

    spec = gullfaks_like(nx=cfg["size"], ny=cfg["size"], n_horizons=cfg["n_horizons"], n_faults=cfg["n_faults"],
                         fault_triangles=tuple(cfg["fault_triangles"]))
    meshes = [(*heightfield_mesh(h["z"], origin=h["origin"], spacing=h["spacing"], drop_holes=True), "horizon")
              for h in spec.horizons]
    meshes += [(f["vertices"], f["faces"], "fault") for f in spec.faults]
    scene = gc.Scene()
    build_s = 0.0
    for v, f, kind in meshes:
        tiles = max(1, round(len(f) / TRIS_PER_TILE)) if kind == "horizon" else None
        t0 = time.perf_counter()
        scene.add_mesh(v, f, kind=kind, tiles=tiles)
        build_s += time.perf_counter() - t0
    return scene, build_s, sum(len(f) for _, f, _ in meshes)


def _build_seconds_one_thread(cfg: dict[str, Any]) -> float | None:
    """:func:`build_scene`'s add_mesh seconds in a child process whose core runs on one thread
    (``RAYON_NUM_THREADS=1``), or None if that fails."""
    import json
    import subprocess

    keys = ("size", "n_horizons", "n_faults", "fault_triangles")
    code = ("import json, sys; from geocull.bench.lod import build_scene; "
            "print(json.dumps(build_scene(json.loads(sys.argv[1]))[1]))")
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    p = subprocess.run([sys.executable, "-c", code, json.dumps({k: cfg[k] for k in keys})], env=env,
                       capture_output=True, text=True, timeout=1800)
    try:
        return float(p.stdout.strip().splitlines()[-1])
    except (IndexError, ValueError):
        _say(f"bench[lod]: the one-thread build failed: {p.stderr.strip()[-500:]}")
        return None


def run(cfg: dict[str, Any]) -> dict[str, Any]:
    """Run the LOD build benchmark described by ``cfg`` (:func:`lod_config`); returns summary and rows."""
    _fs()  # fail early, before the scene is built
    t_start = time.perf_counter()
    _say("bench[lod]: building the scene (every object a mesh)")
    scene, build_s, n_fine = build_scene(cfg)
    tiles = scene_tiles(scene)
    _say("bench[lod]: the same build on one thread (a child process)")
    build_1t = _build_seconds_one_thread(cfg)
    n_levels = max((len(t["levels"]) for t in tiles), default=0)
    # per method and level: triangles, seconds, (max, mean) per tile, geocull's estimates
    acc: dict[tuple[str, int], dict[str, Any]] = {}

    def add(method: str, level: int, tris: int, secs: float, err: tuple[float, float], est: float | None) -> None:
        a = acc.setdefault((method, level), dict(tiles=0, triangles=0, target=0, seconds=0.0, max=[], mean=[],
                                                  estimate=[]))
        a["tiles"] += 1
        a["triangles"] += tris
        a["seconds"] += secs
        a["max"].append(err[0])
        a["mean"].append(err[1])
        if est is not None:
            a["estimate"].append(est)

    fs_total = {m: 0.0 for m in METHODS[1:]}
    for k, t in enumerate(tiles):
        if k % 20 == 0:
            _say(f"bench[lod]: tile {k + 1}/{len(tiles)}")
        v = t["positions"].astype(np.float64)
        fine = t["fine"].astype(np.int64)
        counts = [len(ix) for _, ix in t["levels"]]
        for lvl, (est, ix) in enumerate(t["levels"], start=1):
            add(METHODS[0], lvl, len(ix), 0.0, level_error(v, fine, v, ix.astype(np.int64)), est)
            acc[(METHODS[0], lvl)]["target"] += len(ix)
        for method, border in ((METHODS[1], True), (METHODS[2], False)):
            for lvl, (nv, nf, secs) in enumerate(_fs_levels(v, fine, counts, border), start=1):
                add(method, lvl, len(nf), secs, level_error(v, fine, nv, nf), None)
                acc[(method, lvl)]["target"] += counts[lvl - 1]
                fs_total[method] += secs
    rows = []
    for method in METHODS:
        for lvl in range(1, n_levels + 1):
            a = acc.get((method, lvl))
            if a is None:
                continue
            mx = [x for x in a["max"] if np.isfinite(x)]
            mn = [x for x in a["mean"] if np.isfinite(x)]
            rows.append(dict(method=method, level=lvl, tiles=a["tiles"], triangles=a["triangles"],
                             target_triangles=a["target"],
                             seconds=None if method == METHODS[0] else a["seconds"],
                             max_error_m=max(mx) if mx else None, mean_error_m=float(np.mean(mn)) if mn else None,
                             estimate_max_m=max(a["estimate"]) if a["estimate"] else None))
    import fast_simplification

    summary = dict(n_tiles=len(tiles), n_fine_triangles=n_fine, n_levels=n_levels,
                   geocull_add_mesh_s=build_s, geocull_add_mesh_1thread_s=build_1t, fast_simplification_s=fs_total,
                   cpu_count=os.cpu_count(),
                   fast_simplification_version=getattr(fast_simplification, "__version__", "?"),
                   wall_s=time.perf_counter() - t_start, **{k: cfg[k] for k in ("size", "n_horizons", "n_faults")})
    return dict(summary=summary, rows=rows)


def _f(v: Any, fmt: str) -> str:
    return "–" if v is None else format(v, fmt)


def format_table(result: dict[str, Any]) -> str:
    """The benchmark's table: per method and level, triangles, build seconds and errors."""
    s, rows = result["summary"], result["rows"]
    lines = [f"LOD build: {s['n_tiles']} mesh tiles, {s['n_fine_triangles']:,} fine triangles "
             f"({s['n_horizons']} horizons of {s['size']}x{s['size']} samples as meshes + {s['n_faults']} faults), "
             f"{s['n_levels']} levels", "",
             f"{'method':<34} {'level':>5} {'tiles':>5} {'triangles':>10} {'x target':>8} {'build s':>8} {'max m':>9} "
             f"{'mean m':>9} {'estimate m':>10}"]
    for r in rows:
        ratio = r["triangles"] / r["target_triangles"] if r["target_triangles"] else None
        lines.append(f"{r['method']:<34} {r['level']:>5} {r['tiles']:>5} {r['triangles']:>10,} {_f(ratio, '.3f'):>8} "
                     f"{_f(r['seconds'], '.3f'):>8} {_f(r['max_error_m'], '.3f'):>9} {_f(r['mean_error_m'], '.4f'):>9} "
                     f"{_f(r['estimate_max_m'], '.3f'):>10}")
    lines.append("")
    fs = s["fast_simplification_s"]
    one = s.get("geocull_add_mesh_1thread_s")
    lines.append(f"build: geocull add_mesh {s['geocull_add_mesh_s']:.2f} s on {s['cpu_count']} cores"
                 + (f", {one:.2f} s on 1 thread" if one is not None else "")
                 + " (everything: tiles, proxies, normals, levels); "
                 f"fast-simplification {s['fast_simplification_version']}, the levels only, 1 thread: "
                 f"border kept {fs[METHODS[1]]:.2f} s, border free {fs[METHODS[2]]:.2f} s; wall {s['wall_s']:.0f} s")
    lines.append("columns: tiles = tiles with that level; x target = triangles / meshoptimizer's count (the "
                 "target); max m = worst tile's symmetric "
                 "Hausdorff estimate, mean m = mean distance (both directions, over tiles), to the tile's fine "
                 "surface; estimate m = worst tile's geocull level_error (meshoptimizer's own estimate)")
    return "\n".join(lines)
