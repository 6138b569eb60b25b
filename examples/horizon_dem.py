"""Horizon occlusion culling on a real terrain (issue #7).

matplotlib's Jacksboro fault DEM (344 x 403 samples, ~ 80 m spacing, a real 3-arc-second SRTM
raster shipped with matplotlib, no download) is cut into tiles of about 16 x 16 samples and seen
from low, near-horizontal viewpoints: the eye a few tens of metres above the valley floor, looking
along the valley (and across it / back up it). Each view is rendered with

- ``none``        every fine tile (the reference image),
- ``horizon``     CPU horizon culling over a quadtree of the tiles (front to back, one horizon
                  height per image column),
- ``three_pass``  GPU depth prepass of coarse proxies (coarse_factor 25) + exact per-tile pixel
                  counts, pixel threshold 0 and 10, in the paper's approximate mode ("approx") and
                  in the conservative mode ("cons": the tiles the prepass missed are found by a
                  box test against the first image's depth),
- ``oracle``      exactly the tiles with >= 1 visible pixel in the reference (the lower bound),

and the table gives tiles and triangles drawn, culling milliseconds (horizon: CPU traversal;
three_pass: GPU prepass + count passes), total milliseconds (median of ``--repeat`` renders), the
ratio of total time to ``none``, the fraction of pixels differing from ``none`` and the tiles with
visible pixels that were not drawn.

    python examples/horizon_dem.py [--out examples/out/horizon] [--width 640 --height 480]

Writes ``table.md`` and per view ``<view>_none.png``, ``<view>_horizon.png`` and
``<view>_tiles.png`` (top view of the tiles, north up: green = visible and drawn, yellow = drawn by
horizon but hidden, grey = culled, red = visible but culled, white = the eye) to ``--out``, and
prints the table.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

import geocull as gc
from geocull.compare import image_error
from geocull.data import jacksboro_dem

# (row label, culling mode, pixel threshold, conservative)
# (label, culling, pixel threshold, conservative, max_pixel_error of lod="screen_error" or None = lod="full")
METHODS: list[tuple[str, gc.CullingMode, float, bool, float | None]] = [
    ("none", "none", 10, True, None),
    ("horizon", "horizon", 10, True, None),
    ("three_pass approx t=0", "three_pass", 0, False, None),
    ("three_pass approx t=10", "three_pass", 10, False, None),
    ("three_pass cons t=0", "three_pass", 0, True, None),
    ("three_pass cons t=10", "three_pass", 10, True, None),
    ("oracle", "oracle", 10, True, None),
    ("none lod 0.5 px", "none", 10, True, 0.5),
    ("horizon lod 0.5 px", "horizon", 10, True, 0.5),
    ("three_pass cons t=0 lod 0.5 px", "three_pass", 0, True, 0.5),
    ("three_pass cons t=0 lod 1 px", "three_pass", 0, True, 1.0),
]

Pair = tuple[float, float]


def differing_fraction(a: np.ndarray, b: np.ndarray) -> float:
    return float(image_error(a, b)["differing_pixel_fraction"])


def sample(z: np.ndarray, origin: Pair, spacing: Pair, x: float, y: float) -> float:
    """Bilinear height at world (x, y)."""
    fx = np.clip((x - origin[0]) / spacing[0], 0, z.shape[1] - 1.001)
    fy = np.clip((y - origin[1]) / spacing[1], 0, z.shape[0] - 1.001)
    i, j = int(fx), int(fy)
    u, v = fx - i, fy - j
    return float((1 - u) * (1 - v) * z[j, i] + u * (1 - v) * z[j, i + 1]
                 + (1 - u) * v * z[j + 1, i] + u * v * z[j + 1, i + 1])


View = tuple[str, tuple[float, float, float], float, gc.Camera]


def valley_views(z: np.ndarray, origin: Pair, spacing: Pair, n_spots: int = 3, height: float = 30.0,
                 pitch: float = -2.0, reach: float = 6000.0) -> list[View]:
    """Low views looking along valleys: eyes `height` m above low points of the central part of
    the DEM; for each, the azimuth along which the terrain stays lowest over `reach` metres (along
    the valley), the opposite one (back up the valley) and one across it."""
    ny, nx = z.shape
    rng = np.random.default_rng(7)
    j0, j1, i0, i1 = ny // 5, 4 * ny // 5, nx // 5, 4 * nx // 5
    inner = z[j0:j1, i0:i1]
    low = np.argwhere(inner <= np.quantile(inner, 0.05))
    views: list[tuple[str, tuple[float, float, float], float]] = []
    picked: list[tuple[float, float]] = []
    for k in rng.permutation(len(low)):
        j, i = (int(v) for v in low[k] + (j0, i0))
        x, y = origin[0] + i * spacing[0], origin[1] + j * spacing[1]
        if any(math.hypot(x - px, y - py) < 6000.0 for px, py in picked):
            continue
        picked.append((x, y))
        best, best_az = np.inf, 0.0
        for az in np.arange(0.0, 360.0, 7.5):
            a = math.radians(az)
            ts = np.linspace(300.0, reach, 24)
            h = [sample(z, origin, spacing, x + t * math.cos(a), y + t * math.sin(a)) for t in ts]
            if float(np.mean(h)) < best:
                best, best_az = float(np.mean(h)), az
        ez = sample(z, origin, spacing, x, y) + height
        for name, az in (("along", best_az), ("back", best_az + 180.0), ("across", best_az + 90.0)):
            views.append((f"s{len(picked)}_{name}", (x, y, ez), az % 360.0))
        if len(picked) == n_spots:
            break
    out: list[View] = []
    for name, eye, az in views:
        a, p = math.radians(az), math.radians(pitch)
        d = np.array([math.cos(p) * math.cos(a), math.cos(p) * math.sin(a), math.sin(p)])
        target = np.asarray(eye) + 1000.0 * d
        out.append((name, eye, az, gc.Camera.look_at(eye, target, fov_y=50.0)))
    return out


def cull_ms(stats: gc.RenderStats) -> float:
    """Culling time: CPU horizon (cull_ms), or the GPU prepass + pixel count (three_pass)."""
    return float(stats.get("cull_ms", 0.0) or stats.get("prepass_ms", 0.0) + stats.get("count_ms", 0.0))


def tile_map(tiles: tuple[int, int], visible: np.ndarray, drawn: np.ndarray, eye_xy: Pair, origin: Pair,
             spacing: Pair, scale: int = 12) -> np.ndarray:
    """Top view of the tiles (north up): green = visible (oracle) and drawn, yellow = drawn by
    horizon but not visible, grey = culled, red = visible but culled (a bug), white dot = eye."""
    tx, ty = tiles
    rgba = np.zeros((ty, tx, 4), np.uint8)
    rgba[..., 3] = 255
    v, d = visible.reshape(ty, tx), drawn.reshape(ty, tx)
    rgba[v & d, :3] = (40, 170, 60)
    rgba[~v & d, :3] = (230, 200, 40)
    rgba[~v & ~d, :3] = (70, 70, 70)
    rgba[v & ~d, :3] = (230, 30, 30)
    img = np.repeat(np.repeat(rgba[::-1], scale, 0), scale, 1)
    ex = (eye_xy[0] - origin[0]) / spacing[0]
    ey = (eye_xy[1] - origin[1]) / spacing[1]
    nxs, nys = tx * scale, ty * scale
    # tile boundaries are ~uniform: map sample coordinates to the tile grid
    return _dot(img, ex, ey, nxs, nys)


_GRID: dict[str, tuple[int, int]] = {}


def _dot(img: np.ndarray, ex: float, ey: float, nxs: int, nys: int) -> np.ndarray:
    n = _GRID.get("n")
    if n is None:
        return img
    px = int(ex / (n[1] - 1) * nxs)
    py = nys - 1 - int(ey / (n[0] - 1) * nys)
    img[max(0, py - 3):py + 4, max(0, px - 3):px + 4, :3] = 255
    return img


def png(path: Path, image: np.ndarray) -> None:
    import struct
    import zlib

    h, w = image.shape[:2]
    raw = b"".join(b"\x00" + image[r].tobytes() for r in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def main(argv: Sequence[str] | None = None) -> str:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--out", default="examples/out/horizon")
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--tile", type=int, default=16, help="samples per tile side (about)")
    ap.add_argument("--eye-height", type=float, default=30.0, help="metres above the terrain")
    ap.add_argument("--spots", type=int, default=3, help="eye positions (3 views each)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    z, origin, spacing = jacksboro_dem()
    ny, nx = z.shape
    _GRID["n"] = (ny, nx)
    tiles = (max(1, round((nx - 1) / args.tile)), max(1, round((ny - 1) / args.tile)))
    t0 = time.perf_counter()
    scene = gc.Scene()
    scene.add_heightfield(z, origin=origin, spacing=spacing, tiles=tiles, coarse_factor=25,
                          name="jacksboro", color=(0.55, 0.6, 0.4))
    build_s = time.perf_counter() - t0
    r = gc.Renderer(args.width, args.height)
    views = valley_views(z, origin, spacing, n_spots=args.spots, height=args.eye_height)

    lines = [
        f"Jacksboro DEM {ny}x{nx} (spacing {spacing[0]:.1f} x {spacing[1]:.1f} m), {tiles[0]}x{tiles[1]} tiles, "
        f"{scene.n_triangles} triangles, coarse_factor 25, {args.width}x{args.height}, "
        f"eye {args.eye_height:g} m above the terrain, pitch -2 deg, fov 50 deg; scene build {build_s:.2f} s; "
        f"device: {r.adapter_info if hasattr(r, 'adapter_info') else '?'}; times: median of {args.repeat}.",
        "",
        "| view | method | tiles drawn | triangles drawn | cull ms | total ms | time / none "
        "| differing pixels vs none | missed tiles |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    summary: dict[str, list[float]] = {m: [] for m, _, _, _, _ in METHODS}
    for name, eye, az, cam in views:
        res: dict[str, gc.RenderResult[gc.RenderStats]] = {}
        median_total: dict[str, float] = {}
        median_cull: dict[str, float] = {}
        for m, culling, threshold, conservative, err in METHODS:
            lod: gc.LodMode = "full" if err is None else "screen_error"
            kw = dict(culling=culling, pixel_threshold=threshold, conservative=conservative, lod=lod,
                      max_pixel_error=err or 0.5)
            r.render(scene, cam, **kw)  # type: ignore[arg-type]  # warm-up (uploads, pipeline caches)
            runs = [r.render(scene, cam, **kw) for _ in range(args.repeat)]  # type: ignore[arg-type]
            res[m] = runs[-1]
            median_total[m] = statistics.median(x.stats["total_ms"] for x in runs)
            median_cull[m] = statistics.median(cull_ms(x.stats) for x in runs)
        ref, oracle = res["none"], res["oracle"]
        visible = oracle.tile_pixels > 0
        for m, _, _, _, _ in METHODS:
            x = res[m]
            ratio = median_total[m] / median_total["none"]
            summary[m].append(ratio)
            diff = differing_fraction(x.image, ref.image)
            missed = int((visible & ~x.tile_drawn).sum())
            lines.append(
                f"| {name} (az {az:.0f}) | {m} | {int(x.tile_drawn.sum())}/{x.tile_drawn.size} | "
                f"{x.stats['triangles_drawn']} | {median_cull[m]:.2f} | {median_total[m]:.1f} | {ratio:.2f} | "
                f"{diff:.2e} | {missed} |")
        hz = res["horizon"]
        png(out / f"{name}_none.png", ref.image)
        png(out / f"{name}_horizon.png", hz.image)
        png(out / f"{name}_tiles.png", tile_map(tiles, visible, hz.tile_drawn, (eye[0], eye[1]), origin, spacing))
        print(f"{name}: horizon drew {int(hz.tile_drawn.sum())} tiles, oracle {int(visible.sum())}, "
              f"nodes visited {hz.stats['nodes_visited']}, culled {hz.stats['nodes_culled']}", flush=True)
    lines += ["", "Mean time / none over the views: "
              + ", ".join(f"{m} {statistics.mean(v):.2f}" for m, v in summary.items())]
    table = "\n".join(lines)
    (out / "table.md").write_text(table + "\n")
    print(table)
    return table


if __name__ == "__main__":
    main()
