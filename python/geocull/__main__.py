"""Command line: ``python -m geocull demo`` renders the demo scene; ``python -m geocull bench``
runs the benchmark (see :mod:`geocull.bench`)."""

from __future__ import annotations

import argparse
import sys
import time


def demo(argv: list[str]) -> int:
    """``python -m geocull demo [options]``: render the demo scene to a PNG; returns the exit status."""
    p = argparse.ArgumentParser(prog="python -m geocull demo", description="Render the demo scene to a PNG.")
    p.add_argument("--out", default="demo.png")
    p.add_argument("--width", type=int, default=1280)
    p.add_argument("--height", type=int, default=1024)
    p.add_argument("--size", type=int, default=200, help="samples per horizon side")
    a = p.parse_args(argv)

    import geocull as gc
    from geocull.compare import image_error
    from geocull.data import gullfaks_like, standard_views

    t0 = time.perf_counter()
    spec = gullfaks_like(nx=a.size, ny=a.size)
    scene = spec.build(tiles=(10, 10), coarse_factor=25)
    t_build = time.perf_counter() - t0
    print(f"scene: {len(spec.horizons)} horizons + {len(spec.faults)} faults, {scene.n_triangles:,} triangles, "
          f"{scene.n_tiles} tiles, built in {t_build:.2f} s")
    r = gc.Renderer(a.width, a.height)
    print(f"adapter: {r.adapter_info}")
    name, kw = standard_views(spec, aspect=a.width / a.height)[0]
    cam = gc.Camera.look_at(**kw)
    r.render(scene, cam, culling="none")  # warm-up: upload + pipeline compilation
    ref = r.render(scene, cam, culling="none")
    res = r.render(scene, cam, culling="three_pass", pixel_threshold=10)
    err = image_error(res.image, ref.image)
    for label, x in (("none", ref), ("three_pass", res)):
        s = x.stats
        print(f"{label:>10}: {s['triangles_drawn']:>9,} triangles drawn, {s['tiles_drawn']}/{s['tiles_total']} tiles, "
              f"{s['total_ms']:.1f} ms")
    print(f"view {name}: three_pass differs from none in {err['differing_pixel_fraction'] * 100:.3f} % of pixels")
    res.save_png(a.out)
    print(f"wrote {a.out}")
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
