"""The larger-than-memory volume benchmark (``python -m geocull bench --scene big-volume``, issue 41):
a salt body in an n³ float32 zarr cube (1024³ = 4 GiB by default, written once, slab by slab, into a
temporary directory; ``--quick`` 128³, ``--big-n`` any size), opened lazily with a brick cache of
``--cache-mib`` MiB (default 512), in a child process whose peak RSS is the one reported (the parent
later loads the cube in memory to compare images, which the child never does). Reported: the
octree's streaming pass (time, bytes read), slice moves (``set_slice_index`` of an inline slice,
4 moves of 7 samples: the worst move into bricks not yet read, with its bytes, and the worst move
within bricks the cache holds; beside them the same moves of the volume in memory), and per view
a cold implicit isosurface frame (brick and patch caches cleared): the bytes it read (% of the
cube), its time, and whether its image equals the same frame of the cube in memory (same occluder
and cull depths). Nothing is asserted; the acceptance of issue 41 (1024³, 512 MiB cache) is peak
RSS <= 1.2 GB, a slice move <= 0.1 s, a frame reading <= 25 % of the cube, images equal.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from typing import Any

import numpy as np

__all__ = ["run", "format_table", "salt_slab", "write_cube"]

#: Slice moves measured (7 samples each from a third of the way in: with bricks of 32 samples,
#: one of the four crosses into new bricks).
MOVES = 4

#: Camera directions (from the cube's centre, in cube spans) of the views.
VIEWS = {"east": (1.7, -0.6, 0.7), "north_high": (-0.5, 1.6, 1.4), "below": (0.9, 1.2, -1.1)}


def salt_slab(n: int, k0: int, k1: int) -> np.ndarray:
    """Layers ``k0..k1`` (z) of the n³ salt-body field, (k1 - k0, n, n) float32: a signed distance
    (in cube fractions, < 0 inside) to a diapir, a vertical stalk widening into a mushroom head,
    gently rippled; a few NaN traces (dead traces) along one edge."""
    c = np.arange(n, dtype=np.float32) / np.float32(n - 1)
    z = c[k0:k1, None, None]
    y = c[None, :, None]
    x = c[None, None, :]
    r = np.sqrt((x - 0.5) ** 2 + (y - 0.48) ** 2)
    stalk = r - (0.09 + 0.05 * z)
    head = np.sqrt(((x - 0.52) / 1.4) ** 2 + ((y - 0.5) / 1.2) ** 2 + ((z - 0.7) / 0.8) ** 2) - 0.22
    v = np.minimum(stalk, head) + 0.012 * np.sin(23 * x + 5 * z) * np.cos(19 * y)
    v = np.where(z < 0.08, np.float32(1.0), v)  # the stalk's root below the cube's base
    v = np.broadcast_to(v, (k1 - k0, n, n)).astype(np.float32)
    v[:, :2, : n // 16] = np.nan
    return v


def write_cube(path: str, n: int) -> None:
    """Writes the n³ salt-body cube as a zarr array at ``path`` (chunks 32³, the lazy volume's
    bricks), one slab of 32 layers at a time (bounded memory)."""
    import zarr

    c = min(32, n)
    z = zarr.open_array(path, mode="w", shape=(n, n, n), chunks=(c, c, c), dtype="f4")
    for k in range(0, n, c):
        z[k:k + c] = salt_slab(n, k, min(n, k + c))


def _cameras(vol: Any) -> list[tuple[str, Any]]:
    import geocull as gc

    lo, hi = vol.bounds
    ctr = tuple((a + b) / 2 for a, b in zip(lo, hi, strict=True))
    span = max(b - a for a, b in zip(lo, hi, strict=True))
    return [(name, gc.Camera.look_at(tuple(ctr[i] + d[i] * span for i in range(3)), ctr))
            for name, d in VIEWS.items()]


def _peak_rss() -> int:
    """Peak resident set size of this process in bytes (Linux: ru_maxrss is in KiB)."""
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(r) * (1 if sys.platform == "darwin" else 1024)


def child(path: str, n: int, cache_mib: int, width: int, height: int, out_dir: str) -> None:
    """The lazy run (in its own process): prints its measurements as one JSON line and writes each
    view's image to ``out_dir/<view>.npy``."""
    import zarr

    import geocull as gc

    vol = gc.Volume(zarr.open_array(path, mode="r"), cache_bytes=cache_mib << 20)
    cube = 4 * n**3
    t = time.perf_counter()
    depth = vol.max_depth()
    build_s, build_read = time.perf_counter() - t, vol.bytes_read
    scene = gc.Scene()
    sid = scene.add_slice(vol, "inline", n // 3)
    moves = []
    for i in range(MOVES):
        before = vol.bytes_read
        t = time.perf_counter()
        scene.set_slice_index(sid, n // 3 + 7 * (i + 1))
        moves.append((time.perf_counter() - t, vol.bytes_read - before))
    cold = [m for m in moves if m[1] > 0]
    warm = [m[0] for m in moves if m[1] == 0]
    r = gc.Renderer(width, height)
    views = []
    for name, cam in _cameras(vol):
        vol.clear_cache()
        gc.iso.clear_cache(r)
        t = time.perf_counter()
        res = r.render_isosurface(vol, 0.0, cam)
        ms = (time.perf_counter() - t) * 1e3
        np.save(os.path.join(out_dir, f"{name}.npy"), res.image)
        views.append(dict(view=name, bytes_read=res.stats["bytes_read"], percent=100.0 * res.stats["bytes_read"] / cube,
                          frame_ms=ms, triangles=res.stats["surface_triangles"],
                          cache_bytes=res.stats["brick_cache_bytes"], occluder_depth=res.stats["occluder_depth"],
                          cull_depth=res.stats["cull_depth"]))
    info = vol.cache_info
    print(json.dumps(dict(peak_rss=_peak_rss(), build_s=build_s, build_read=build_read, max_depth=depth,
                          slice_move_cold_s=max((m[0] for m in cold), default=float("nan")),
                          slice_move_read=max((m[1] for m in cold), default=0),
                          slice_move_warm_s=max(warm, default=float("nan")), slice_moves=len(moves),
                          slice_moves_cold=len(cold), views=views,
                          cache_peak=info[2] if info else 0)), flush=True)


def run(cfg: dict[str, Any]) -> dict[str, Any]:
    """Runs the benchmark; ``cfg``: big_n (samples per axis), cache_mib, width, height, compare
    (render the cube in memory to compare the images)."""
    n, cache_mib = int(cfg["big_n"]), int(cfg["cache_mib"])
    w, h = int(cfg["width"]), int(cfg["height"])
    with tempfile.TemporaryDirectory(prefix="geocull-big-volume-") as tmp:
        path = os.path.join(tmp, "cube.zarr")
        t = time.perf_counter()
        write_cube(path, n)
        write_s = time.perf_counter() - t
        code = (f"from geocull.bench.big_volume import child; child({path!r}, {n}, {cache_mib}, {w}, {h}, "
                f"{tmp!r})")
        p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
        if p.returncode != 0:
            raise RuntimeError(f"big-volume: the lazy run failed:\n{p.stderr[-4000:]}")
        out: dict[str, Any] = json.loads(p.stdout.strip().splitlines()[-1])
        out.update(n=n, cube_bytes=4 * n**3, cache_bytes=cache_mib << 20, write_s=write_s, width=w, height=h)
        if cfg.get("compare", True):
            import zarr

            import geocull as gc

            mem = gc.Volume(np.asarray(zarr.open_array(path, mode="r")))
            scene = gc.Scene()
            sid = scene.add_slice(mem, "inline", n // 3)
            moves = []
            for i in range(MOVES):
                t = time.perf_counter()
                scene.set_slice_index(sid, n // 3 + 7 * (i + 1))
                moves.append(time.perf_counter() - t)
            out["slice_move_mem_s"] = max(moves)
            r = gc.Renderer(w, h)
            d = mem.max_depth() - 3
            for v, (name, cam) in zip(out["views"], _cameras(mem), strict=True):
                want = r.render_isosurface(mem, 0.0, cam, occluder_depth=d, cull_depth=d).image
                v["equal"] = bool(np.array_equal(np.load(os.path.join(tmp, f"{name}.npy")), want))
    return out


def format_table(res: dict[str, Any]) -> str:
    n, gib = res["n"], res["cube_bytes"] / 2**30
    lines = [
        f"big-volume: {n}^3 float32 zarr cube ({gib:.2f} GiB, written in {res['write_s']:.1f} s), brick cache "
        f"{res['cache_bytes'] >> 20} MiB (peak held {res['cache_peak'] / 2**20:.0f} MiB), "
        f"{res['width']}x{res['height']}",
        f"  peak RSS (lazy process)     {res['peak_rss'] / 1e9:8.3f} GB",
        f"  octree streaming pass       {res['build_s']:8.2f} s   read "
        f"{res['build_read'] / res['cube_bytes']:.3f} x the cube",
        f"  slice move, new bricks      {res['slice_move_cold_s']:8.4f} s   read "
        f"{res['slice_move_read'] / 2**20:.2f} MiB ({res['slice_moves_cold']} of {res['slice_moves']} moves, worst)",
        f"  slice move, cached bricks   {res['slice_move_warm_s']:8.4f} s   (worst); any move in memory "
        f"{res.get('slice_move_mem_s', float('nan')):.4f} s (worst)",
        "  view          read (MiB)   % of cube   frame (ms)   triangles   image == in memory",
    ]
    for v in res["views"]:
        eq = {True: "yes", False: "NO"}.get(v.get("equal"), "-")
        lines.append(f"  {v['view']:<12} {v['bytes_read'] / 2**20:11.1f} {v['percent']:11.2f} {v['frame_ms']:12.1f} "
                     f"{v['triangles']:11d}   {eq}")
    return "\n".join(lines)
