"""The scale benchmark (``python -m geocull bench --scene scale``, issue 41): does a frame's cost follow
what is on screen, or the number of fine triangles?

The Gullfaks-like scene (:func:`geocull.data.gullfaks_like`: 11 horizons, faults) at the same extent
(417 cells of 25 m a side) sampled ever finer: ``sizes`` samples per horizon side, the spacing
``25 m x 417 / (size - 1)`` (418, 835, 1669 samples: 3.9 M, 15.3 M, 61.2 M triangles; ``--quick``: 96
and 191 samples, 0.2 M and 0.8 M triangles), tiles of a fixed size (as many per side as ``10 x (size -
1) / 417``, rounded: the 3.9 M scene's tiles, ~3,500 triangles each), coarse factor 25. Each size is
measured in its own process (``python -m geocull.bench.scale``), so that each gets its own peak RSS:

- ``build``: :meth:`geocull.data.SceneSpec.build` (tiles and levels), seconds;
- ``first image``: from the start of the build to the first frame's image in hand (the build, a new
  renderer, its upload, one ``temporal`` + lod 0.5 px frame of the first view, no history yet);
- per view (``oblique_az045``, ``low_az200``, ``top_down`` of :func:`geocull.data.standard_views`):
  ``none``, ``temporal`` (threshold 0) and ``temporal`` + ``lod="screen_error"`` 0.5 px, one warm-up
  frame each (temporal ones two: their history is then the view), then ``repeats`` rounds in rotated
  order (:func:`geocull.bench.report.timed_rounds`); a method's time is the median of its rounds of
  ``stats["total_ms"]``, a size's the mean of its views';
- the lod frame's image error against ``none``'s (:func:`geocull.compare.image_error`: pixels
  differing at all and by more than 4/255), per view and the largest over the views;
- ``peak RSS``: the process's ``ru_maxrss`` at the end (spec, scene, renderer and driver), and that
  per fine triangle.

The summary gives what issue 41's acceptance asks, each beside its target: the largest size's lod
frame over the smallest's (<= 1.3 x), the largest's first image (<= 10 s), its peak RSS per fine
triangle (<= 40 B), and the lod image error in every view (<= 0.5 % of pixels). Nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from typing import Any

__all__ = ["run", "format_table", "measure", "scale_config", "SIZES", "QUICK_SIZES", "VIEWS", "TARGETS",
           "COLUMNS", "spacing_for", "tiles_for"]

#: Samples per horizon side: 3.9 M, 15.3 M and 61.2 M triangles at the same extent.
SIZES = (418, 835, 1669)
#: ``--quick``: 0.2 M and 0.8 M triangles.
QUICK_SIZES = (96, 191)
#: ``--tiny`` (tests).
TINY_SIZES = (24, 48)
#: The views (:func:`geocull.data.standard_views`), as the quick Gullfaks benchmark's.
VIEWS = ("oblique_az045", "low_az200", "top_down")
BASE_SIZE, BASE_SPACING, BASE_TILES = 418, 25.0, 10
COARSE_FACTOR = 25
LOD_ERROR = 0.5
#: Issue 41's acceptance: lod frame ratio (largest / smallest), first image (s), peak RSS per fine
#: triangle (bytes), lod image error (percent of pixels, every view).
TARGETS = dict(lod_ratio=1.3, first_image_s=10.0, rss_bytes_per_triangle=40.0, lod_diff_pct=0.5)
METHODS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("none", dict(culling="none")),
    ("temporal", dict(culling="temporal", pixel_threshold=0)),
    ("temporal_lod", dict(culling="temporal", pixel_threshold=0, lod="screen_error", max_pixel_error=LOD_ERROR)),
)


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def spacing_for(size: int) -> float:
    """Sample spacing (m) of ``size`` samples per side over the base scene's extent (417 x 25 m)."""
    return BASE_SPACING * (BASE_SIZE - 1) / (int(size) - 1)


def tiles_for(size: int) -> int:
    """Tiles per horizon side at ``size`` samples: the base scene's tile size (41.7 cells)."""
    return max(1, round(BASE_TILES * (int(size) - 1) / (BASE_SIZE - 1)))


def scale_config(mode: str, a: argparse.Namespace) -> dict[str, Any]:
    """The scale benchmark's part of :func:`geocull.bench.cli.config`: sizes, views (names), repeats and
    faults for ``mode`` (full, quick, tiny), overridden by ``--scale-sizes``, ``--views`` (N: the first N
    standard views, or names) and ``--repeats``. The image size is the common options' (full 1280x1024,
    quick 320x256)."""
    from ..data import standard_views

    sizes = {"full": SIZES, "quick": QUICK_SIZES, "tiny": TINY_SIZES}[mode]
    if getattr(a, "scale_sizes", None):
        try:
            sizes = tuple(int(x) for x in a.scale_sizes.split(",") if x.strip())
        except ValueError:
            sizes = ()
        if not sizes or min(sizes) < 3:
            raise SystemExit(f"--scale-sizes: expected comma-separated sizes >= 3, got {a.scale_sizes!r}")
    known = [n for n, _ in standard_views((0.0, 1.0, 0.0, 1.0, 0.0, 1.0))]
    names = list(VIEWS[:1] if mode == "tiny" else VIEWS)
    if a.views is not None:
        spec = str(a.views).strip()
        names = known[: int(spec)] if spec.isdigit() else [v.strip() for v in spec.split(",") if v.strip()]
        bad = [n for n in names if n not in known]
        if not names or bad:
            raise SystemExit(f"--views: expected N >= 1 or view names of {', '.join(known)}, got {a.views!r}")
    return dict(sizes=sizes, views=names, n_faults={"full": 16, "quick": 6, "tiny": 2}[mode],
                repeats=a.repeats or {"full": 3, "quick": 2, "tiny": 1}[mode])


def _peak_rss_bytes() -> int:
    r = int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    return r if sys.platform == "darwin" else r * 1024


def measure(size: int, cfg: dict[str, Any]) -> dict[str, Any]:
    """One size, in this process: its build, first image, frame times, image errors and peak RSS
    (call it in a fresh process for a peak RSS of its own: :func:`run` does)."""
    import geocull as gc

    from ..compare import image_error
    from ..data import gullfaks_like, standard_views
    from . import report

    w, h = int(cfg["width"]), int(cfg["height"])
    load_start = os.getloadavg()[0]
    t0 = time.perf_counter()
    spec = gullfaks_like(nx=size, ny=size, spacing=spacing_for(size), n_faults=int(cfg["n_faults"]))
    gen_s = time.perf_counter() - t0
    n_tri = int(spec.n_triangles)
    k = tiles_for(size)
    _say(f"bench[scale]: {size}x{size} samples ({spacing_for(size):.2f} m), {n_tri:,} triangles, "
         f"tiles {k}x{k}: building")
    t0 = time.perf_counter()
    scene = spec.build(tiles=(k, k), coarse_factor=COARSE_FACTOR)
    build_s = time.perf_counter() - t0
    byname = dict(standard_views(spec, 45.0, 1.0, w / h))
    views = [(v, gc.Camera.look_at(**byname[v])) for v in cfg["views"]]
    renderer = gc.Renderer(w, h)
    first = renderer.render(scene, views[0][1], **dict(METHODS)["temporal_lod"])
    _ = first.image
    first_image_s = time.perf_counter() - t0
    del first
    _say(f"bench[scale]: {n_tri:,} triangles: built in {build_s:.1f} s, first image at {first_image_s:.1f} s")
    rows: list[dict[str, Any]] = []
    for vname, cam in views:
        ref = renderer.render(scene, cam, **dict(METHODS)["none"])
        renderer.render(scene, cam, **dict(METHODS)["temporal"])
        renderer.render(scene, cam, **dict(METHODS)["temporal_lod"])
        lod = renderer.render(scene, cam, **dict(METHODS)["temporal_lod"])
        err = image_error(lod.image, ref.image)
        err4 = image_error(lod.image, ref.image, threshold=4)
        lod_triangles = int(lod.stats["triangles_drawn"])
        del ref, lod

        def job(rk: dict[str, Any], cam: Any = cam) -> Any:
            return lambda: renderer.render(scene, cam, **rk).stats["total_ms"]

        times = report.timed_rounds([(name, job(rk)) for name, rk in METHODS], int(cfg["repeats"]))
        rows.append(dict(view=vname, **{f"{m}_ms": statistics.median(times[m]) for m, _ in METHODS},
                         lod_diff_pct=100.0 * err["differing_pixel_fraction"],
                         lod_diff4_pct=100.0 * err4["differing_pixel_fraction"],
                         lod_max_diff=int(err["max_abs_diff"]), lod_triangles=lod_triangles))
        _say(f"bench[scale]: {n_tri:,} triangles, view {vname}: " + ", ".join(
            f"{m} {rows[-1][m + '_ms']:.0f} ms" for m, _ in METHODS))
    rss = _peak_rss_bytes()
    return dict(size=int(size), spacing=spacing_for(size), tiles_per_side=k, triangles=n_tri,
                tiles=int(scene.n_tiles), gen_s=gen_s, build_s=build_s, first_image_s=first_image_s,
                **{f"{m}_ms": statistics.fmean(r[f"{m}_ms"] for r in rows) for m, _ in METHODS},
                lod_diff_pct=max(r["lod_diff_pct"] for r in rows),
                lod_diff4_pct=max(r["lod_diff4_pct"] for r in rows),
                peak_rss_bytes=rss, rss_bytes_per_triangle=rss / n_tri, views=rows,
                load_average=(load_start, os.getloadavg()[0]),
                adapter=renderer.adapter_info)


def _child(size: int, cfg: dict[str, Any]) -> dict[str, Any]:
    """:func:`measure` in a fresh Python process (the geocull this one imported), its result as JSON."""
    import geocull

    env = dict(os.environ)
    top = os.path.dirname(os.path.dirname(os.path.abspath(geocull.__file__)))
    env["PYTHONPATH"] = top + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    arg = json.dumps(dict(size=int(size), cfg={k: cfg[k] for k in ("width", "height", "views", "repeats", "n_faults")}))
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "geocull.bench.scale", arg], stdout=subprocess.PIPE, env=env, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        _say(f"bench[scale]: size {size} failed (exit {p.returncode})")
        return dict(size=int(size), error=f"exit {p.returncode}", wall_s=wall)
    out: dict[str, Any] = json.loads(p.stdout.strip().splitlines()[-1])
    out["wall_s"] = wall
    return out


def run(cfg: dict[str, Any]) -> dict[str, Any]:
    """Every size of ``cfg["sizes"]`` in its own process; ``cfg``: sizes, width, height, views (names),
    repeats, n_faults, mode. Returns ``{"summary": {...}, "rows": [one per size]}``."""
    t0 = time.perf_counter()
    rows = [_child(s, cfg) for s in cfg["sizes"]]
    ok = [r for r in rows if "error" not in r]
    summary: dict[str, Any] = dict(mode=cfg.get("mode"), width=cfg["width"], height=cfg["height"],
                                   views=list(cfg["views"]), repeats=cfg["repeats"], n_faults=cfg["n_faults"],
                                   sizes=list(cfg["sizes"]), targets=dict(TARGETS), cpus=os.cpu_count(),
                                   python=platform.python_version(), adapter=ok[0]["adapter"] if ok else None)
    if ok:
        small, big = ok[0], ok[-1]
        summary.update(
            small_triangles=small["triangles"], big_triangles=big["triangles"],
            lod_ratio=big["temporal_lod_ms"] / small["temporal_lod_ms"] if len(ok) > 1 else None,
            triangle_ratio=big["triangles"] / small["triangles"],
            first_image_s=big["first_image_s"], rss_bytes_per_triangle=big["rss_bytes_per_triangle"],
            lod_diff_pct=max(r["lod_diff_pct"] for r in ok), lod_diff4_pct=max(r["lod_diff4_pct"] for r in ok))
    summary["wall_s"] = time.perf_counter() - t0
    return dict(summary=summary, rows=rows)


def _mtri(n: int) -> str:
    return f"{n / 1e6:.2f} M" if n < 1e6 else f"{n / 1e6:.1f} M"


def _check(value: float | None, target: float) -> str:
    return "–" if value is None else ("ok" if value <= target else "MISSED")


#: The main table's columns (header, row key).
COLUMNS = ("scene", "tiles", "build", "first image", "none", "temporal", "temporal + lod 0.5 px", "peak RSS",
           "B/tri", "lod diff px %", "lod >4/255 %")


def format_table(result: dict[str, Any]) -> str:
    s, rows = result["summary"], result["rows"]
    views = ", ".join(s["views"])
    lines = [f"geocull bench --scene scale ({s['mode']}): Gullfaks-like scene, 11 horizons + {s['n_faults']} faults "
             f"over 10,425 m, ever finer: {', '.join(str(n) for n in s['sizes'])} samples a side; "
             f"{s['width']}x{s['height']}, {len(s['views'])} view(s) ({views}), median of {s['repeats']} round(s) "
             f"after a warm-up, each size in its own process; {s['adapter']}; {s['cpus']} CPU(s)", ""]
    lines.append("| " + " | ".join(COLUMNS) + " |")
    lines.append("|" + "|".join("---" for _ in COLUMNS) + "|")
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['size']} samples | failed: {r['error']} |" + " |" * (len(COLUMNS) - 2))
            continue
        lines.append(
            f"| {_mtri(r['triangles'])} triangles | {r['tiles']:,} | {r['build_s']:.1f} s | {r['first_image_s']:.1f} s "
            f"| {r['none_ms']:,.0f} ms | {r['temporal_ms']:,.0f} ms | {r['temporal_lod_ms']:,.0f} ms "
            f"| {r['peak_rss_bytes'] / 2**30:.2f} GiB | {r['rss_bytes_per_triangle']:.0f} "
            f"| {r['lod_diff_pct']:.3f} | {r['lod_diff4_pct']:.3f} |")
    if "big_triangles" in s:
        t, big, small = TARGETS, _mtri(s["big_triangles"]), _mtri(s["small_triangles"])
        ratio = s["lod_ratio"]
        checks = [
            (f"temporal + lod frame, {big} / {small}", "–" if ratio is None else f"{ratio:.2f} x",
             f"<= {t['lod_ratio']} x", _check(ratio, t["lod_ratio"])),
            (f"first image, {big}", f"{s['first_image_s']:.1f} s", f"<= {t['first_image_s']:.0f} s",
             _check(s["first_image_s"], t["first_image_s"])),
            (f"peak RSS per fine triangle, {big}", f"{s['rss_bytes_per_triangle']:.0f} B",
             f"<= {t['rss_bytes_per_triangle']:.0f} B",
             _check(s["rss_bytes_per_triangle"], t["rss_bytes_per_triangle"])),
            ("lod image error, worst view", f"{s['lod_diff_pct']:.3f} % px", f"<= {t['lod_diff_pct']} % px",
             _check(s["lod_diff_pct"], t["lod_diff_pct"])),
        ]
        lines += ["", f"acceptance (issue 41), the largest scene against the smallest ({s['triangle_ratio']:.1f} x the "
                  "triangles):"]
        lines += [f"  {label:<44} {value:>12}   target {target:<12} {check}" for label, value, target, check in checks]
    lines += ["", "per view (ms: median of the rounds; lod diff: pixels of the temporal + lod frame differing from "
              "none's, at all / beyond 4/255):"]
    for r in rows:
        for v in r.get("views", []):
            lines.append(f"  {_mtri(r['triangles']):>7} {v['view']:<14} none {v['none_ms']:9,.1f}  temporal "
                         f"{v['temporal_ms']:8,.1f}  lod {v['temporal_lod_ms']:7,.1f}  lod triangles "
                         f"{v['lod_triangles']:>10,}  diff {v['lod_diff_pct']:.3f} % / {v['lod_diff4_pct']:.3f} %")
    lines.append(f"columns: build = tiles + levels (SceneSpec.build); first image = build start -> first temporal + "
                 f"lod frame's image (new renderer, upload, no history); frame times = geocull stats total_ms (call -> "
                 f"GPU done), mean over the views; peak RSS = ru_maxrss of the size's process (spec, scene, renderer, "
                 f"driver); B/tri = peak RSS per fine triangle; lod diff = largest over the views. Wall "
                 f"{s['wall_s']:.0f} s.")
    loads = [f"{_mtri(r['triangles'])} {r['load_average'][0]:.1f} -> {r['load_average'][1]:.1f}"
             for r in rows if "load_average" in r]
    if loads:
        lines.append(f"load average (1 min) at each size's start -> end, {s['cpus']} CPU(s): " + ", ".join(loads)
                     + " (above the CPU count, other processes shared the machine: slower frames)")
    return "\n".join(lines)


def _main() -> None:
    a = json.loads(sys.argv[1])
    print(json.dumps(measure(int(a["size"]), a["cfg"])), flush=True)


if __name__ == "__main__":
    _main()
