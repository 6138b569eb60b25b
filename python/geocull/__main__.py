"""Command line: ``python -m geocull demo`` renders the demo scene; ``python -m geocull bench``
runs the benchmark (see :mod:`geocull.bench`)."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from typing import Any


def demo(argv: list[str]) -> int:
    """``python -m geocull demo [options]``: the demo scene from one view, rendered without culling,
    with three_pass and by PyVista; prints best-of-N frame times side by side with each image's
    error against the unculled one, and writes three_pass's image to a PNG. Returns the exit status."""
    p = argparse.ArgumentParser(prog="python -m geocull demo",
                                description="none / three_pass / PyVista on one view: best-of-N times and image error.")
    p.add_argument("--out", default="demo.png")
    p.add_argument("--width", type=int, default=1280)
    p.add_argument("--height", type=int, default=1024)
    p.add_argument("--size", type=int, default=200, help="samples per horizon side")
    p.add_argument("--repeats", type=int, default=5, help="timed frames per method (the best is shown)")
    p.add_argument("--no-pyvista", action="store_true", help="skip the PyVista row")
    a = p.parse_args(argv)

    import os

    import geocull as gc
    from geocull.bench.report import timed_rounds
    from geocull.compare import coverage_agreement, depth_error, image_error
    from geocull.data import gullfaks_like, standard_views

    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    n = max(1, a.repeats)
    t0 = time.perf_counter()
    spec = gullfaks_like(nx=a.size, ny=a.size)
    scene = spec.build(tiles=(10, 10), coarse_factor=25)
    t_build = time.perf_counter() - t0
    print(f"scene: {len(spec.horizons)} horizons + {len(spec.faults)} faults, {scene.n_triangles:,} triangles, "
          f"{scene.n_tiles} tiles, built in {t_build:.2f} s")
    r = gc.Renderer(a.width, a.height)
    print(f"adapter: {r.adapter_info}; {a.width}x{a.height}; best of {n} frames after a warm-up")
    name, kw = standard_views(spec, aspect=a.width / a.height)[0]
    cam = gc.Camera.look_at(**kw)
    modes: dict[str, dict[str, Any]] = {"none": dict(culling="none"),
                                        "three_pass": dict(culling="three_pass", pixel_threshold=10)}
    first = {m: r.render(scene, cam, **o) for m, o in modes.items()}  # warm-up: upload, pipelines

    def job(o: dict[str, Any]) -> Callable[[], float]:
        return lambda: float(r.render(scene, cam, **o).stats["total_ms"])

    times = timed_rounds([(m, job(o)) for m, o in modes.items()], n)
    ref = first["none"]
    rows = []
    for m, res in first.items():
        err = image_error(res.image, ref.image)
        de = depth_error(res.depth, ref.depth)
        rows.append((m, min(times[m]), f"{res.stats['triangles_drawn']:,}",
                     f"{err['differing_pixel_fraction'] * res.image.shape[0] * res.image.shape[1]:,.0f} "
                     f"({err['differing_pixel_fraction'] * 100:.3f} %)", de["p99_rel"]))
    if not a.no_pyvista:
        try:
            from geocull import pyvista as gpv

            ms = gpv.timed_render(scene, cam, a.width, a.height, n=n)
            pv = gpv.reference_image(scene, cam, a.width, a.height, near=ref.near, far=ref.far)
            disagree = 1.0 - coverage_agreement(pv["depth"], ref.depth)
            rows.append(("pyvista", ms, f"{scene.n_triangles:,}",
                         f"{disagree * a.width * a.height:,.0f} ({disagree * 100:.3f} %) coverage",
                         depth_error(pv["depth"], ref.depth)["p99_rel"]))
        except Exception as e:  # PyVista/VTK missing or without an off-screen context
            print(f"pyvista: skipped ({type(e).__name__}: {e})")
    t_none = rows[0][1]
    print(f"\nview {name}:")
    print(f"{'method':<11} {'best ms':>9} {'x none':>7} {'triangles drawn':>16}  {'pixels differing from none':<34} "
          f"{'depth error p99':>15}")
    for m, ms, tris, diff, p99 in rows:
        print(f"{m:<11} {ms:>9.1f} {ms / t_none:>7.2f} {tris:>16}  {diff:<34} {p99:>15.2e}")
    print("(three_pass: colour differences; pyvista shades differently, so its coverage and depth are compared; "
          "depth error: 99th percentile of |d - d_none| / d_none)")
    first["three_pass"].save_png(a.out)
    print(f"wrote {a.out} (three_pass)")
    return 0


def bench_distributed(argv: list[str]) -> int:
    """``python -m geocull bench-distributed [options]``: frames/s of geocull.distributed.render_views on
    LocalClusters of 1, 2, ... worker processes, side by side."""
    p = argparse.ArgumentParser(prog="python -m geocull bench-distributed",
                                description="Frames/s of render_views on LocalClusters of 1, 2, ... workers.")
    p.add_argument("--workers", default="1,2", help="comma-separated worker counts (default 1,2)")
    p.add_argument("--views", type=int, default=16)
    p.add_argument("--size", type=int, default=120, help="samples per horizon side")
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=256)
    p.add_argument("--culling", default="three_pass")
    a = p.parse_args(argv)
    from geocull.distributed import benchmark

    rows = benchmark([int(n) for n in a.workers.split(",")], a.views, a.size, a.width, a.height, a.culling)
    print(f"{'workers':>8} {'views':>6} {'seconds':>8} {'frames/s':>9} {'x 1 worker':>11}")
    for r in rows:
        print(f"{r['workers']:>8} {r['views']:>6} {r['seconds']:>8.2f} {r['frames_per_s']:>9.1f} "
              f"{r['ratio_to_1']:>11.2f}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m geocull {demo,bench,bench-distributed} ...``; returns the exit status."""
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: python -m geocull {demo,bench,bench-distributed} [options]  (each takes --help)")
        return 0 if argv else 2
    cmd, rest = argv[0], argv[1:]
    if cmd == "demo":
        return demo(rest)
    if cmd == "bench-distributed":
        return bench_distributed(rest)
    if cmd == "bench":
        from geocull.bench import main as bench_main

        return bench_main(rest)
    print(f"unknown command {cmd!r}; expected demo, bench or bench-distributed", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
