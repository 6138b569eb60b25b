"""``python -m geocull bench``'s command line: :func:`parser` (the options), :func:`config` (the run's
configuration from them: the scene, its size and the image size in the full, ``--quick`` and
``--tiny`` modes) and :func:`main`, which runs the ``--scene``'s module (:mod:`geocull.bench`)."""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

from . import gullfaks

__all__ = ["main", "parser", "config"]


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m geocull bench",
        description="Benchmark geocull's culling (none / three_pass / oracle / horizon) against PyVista, side by side.",
    )
    p.add_argument("--quick", action="store_true", help="small scene (120x120 samples, 6 faults), 320x256, 3 views")
    p.add_argument("--tiny", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--json", metavar="PATH", help="write rows and summary as JSON")
    p.add_argument("--plot", metavar="PATH", help="gullfaks: write the speed-against-error plot (x none against "
                   "differing pixels, one marker per method over the views; needs matplotlib)")
    p.add_argument("--width", type=int, help="image width (default 1280; quick 320)")
    p.add_argument("--height", type=int, help="image height (default 1024; quick 256)")
    p.add_argument("--views", help="number of standard views to use (first N), or comma-separated view names")
    p.add_argument("--repeats", type=int, help="timed rounds after the warm-up (default 3; quick 2)")
    p.add_argument("--size", type=int, help="samples per horizon side (default 418; quick 120)")
    p.add_argument("--no-pyvista", action="store_true", help="skip the PyVista rows")
    p.add_argument("--no-horizon", action="store_true", help="skip CPU horizon culling")
    p.add_argument("--pass-triangles", type=int, help="gullfaks: Renderer.pass_triangles of the scenes' renderers "
                   "(at most this many triangles per render pass: less driver memory on CPU drivers; default "
                   "unbounded)")
    p.add_argument("--scene", choices=("gullfaks", "iso", "grid", "seismic", "field", "lod", "scale", "big-volume"),
                   default="gullfaks",
                   help="gullfaks: horizons and faults (default); iso: isosurfaces (geocull.bench.iso); grid: a "
                   "faulted reservoir grid (geocull.bench.grid); seismic: the gullfaks scene with slices and a lens "
                   "(geocull.bench.seismic); field: a real field's horizons, grid and wells (geocull.bench.field); "
                   "lod: the LOD build of mesh tiles, meshoptimizer against fast-simplification (geocull.bench.lod; "
                   "--size: samples per horizon side); scale: the gullfaks scene ever finer, 3.9 M / 15 M / 61 M "
                   "triangles, each in its own process (geocull.bench.scale; --scale-sizes); big-volume: a lazy "
                   "volume larger than memory, a salt body in a zarr cube (geocull.bench.big_volume; --big-n, "
                   "--cache-mib)")
    p.add_argument("--data", help="field: the field's directory (surfaces/*.gri, grid/*.EGRID or *.grdecl + porosity, "
                   "wells/*.w; default ../shared/data/reek beside the checkout)")
    p.add_argument("--scale-sizes", help="scale: comma-separated samples per horizon side (default 418,835,1669; "
                   "quick 96,191)")
    p.add_argument("--grid-n", type=int, help="grid: cells along i and j (default 100; quick 30)")
    p.add_argument("--grid-nk", type=int, help="grid: layers (default 100; quick 20)")
    p.add_argument("--iso-volumes", help="iso: comma-separated volumes of pesco, channels, frog "
                   "(default all; quick: pesco)")
    p.add_argument("--iso-n", type=int, help="iso: samples per axis of the Pesco field (default 128; quick 32)")
    p.add_argument("--big-n", type=int, help="big-volume: samples per axis of the zarr cube (default 1024, 4 GiB; "
                   "quick 128)")
    p.add_argument("--cache-mib", type=int, help="big-volume: the lazy volume's brick cache in MiB (default 512; "
                   "quick 16)")
    p.add_argument("--occluder-depth", type=int, help="iso: octree depth of the occluders (default: geocull's)")
    p.add_argument("--cull-depth", type=int, help="iso: octree depth of the tested nodes (default: geocull's)")
    return p


def config(a: argparse.Namespace) -> dict[str, Any]:
    tiny = a.tiny or os.environ.get("GEOCULL_BENCH_TINY", "") not in ("", "0")
    if tiny:
        mode = "tiny"
        cfg = dict(size=48, n_faults=2, fault_triangles=(50, 200), width=64, height=48, views="1", repeats=1)
    elif a.quick:
        mode = "quick"
        cfg = dict(size=120, n_faults=6, fault_triangles=(2000, 20000), width=320, height=256,
                   views=",".join(gullfaks.QUICK_VIEWS), repeats=2)
    else:
        mode = "full"
        cfg = dict(size=418, n_faults=16, fault_triangles=(2000, 20000), width=1280, height=1024, views=None, repeats=3)
    cfg["mode"] = mode
    for k in ("size", "width", "height", "views", "repeats"):
        v = getattr(a, k)
        if v is not None:
            cfg[k] = v
    cfg["pyvista"] = not a.no_pyvista
    cfg["horizon"] = not a.no_horizon
    cfg["pass_triangles"] = a.pass_triangles
    cfg["scene"] = a.scene
    if a.scene == "iso":
        from .iso import VOLUMES

        small = mode != "full"
        cfg.update(width=a.width or (96 if mode == "tiny" else 128 if small else 512),
                   height=a.height or (96 if mode == "tiny" else 128 if small else 512),
                   iso_views=int(a.views) if a.views and str(a.views).isdigit()
                   else (1 if mode == "tiny" else 2 if small else 8),
                   repeats=a.repeats or (1 if small else 3),
                   iso_n=a.iso_n or (24 if mode == "tiny" else 32 if small else 128),
                   iso_volumes=[v.strip() for v in a.iso_volumes.split(",")] if a.iso_volumes else
                   (["pesco"] if small else list(VOLUMES)),
                   occluder_depth=a.occluder_depth, cull_depth=a.cull_depth)
    elif a.scene == "grid":
        small = mode != "full"
        cfg.update(grid_n=a.grid_n or (12 if mode == "tiny" else 30 if small else 100),
                   grid_nk=a.grid_nk or (6 if mode == "tiny" else 20 if small else 100),
                   blocks=(8, 8) if small else (16, 16))
    elif a.scene == "field":
        from .field import field_config

        cfg.update(field_config(mode, a))
    elif a.scene == "lod":
        from .lod import lod_config

        cfg.update(lod_config(mode))
        if a.size:
            cfg["size"] = a.size
    elif a.scene == "scale":
        from .scale import scale_config

        cfg.update(scale_config(mode, a))
    elif a.scene == "big-volume":
        small = mode != "full"
        cfg.update(big_n=a.big_n or (48 if mode == "tiny" else 128 if small else 1024),
                   cache_mib=a.cache_mib if a.cache_mib is not None else (16 if small else 512),
                   width=a.width or (96 if small else 512), height=a.height or (96 if small else 512))
    elif a.scene == "seismic":
        small = mode != "full"
        cfg.update(cube=(24, 24, 16) if mode == "tiny" else (60, 60, 40) if small else (200, 200, 120),
                   views=1 if mode == "tiny" else 3 if small else 7)
    return cfg


def main(argv: list[str] | None = None) -> int:
    """``python -m geocull bench [options]``: run the benchmark and print its table; returns the exit status."""
    a = parser().parse_args(sys.argv[1:] if argv is None else argv)
    cfg = config(a)
    if cfg["scene"] == "iso":
        from . import iso

        result = iso.run(cfg)
        print(iso.format_table(result), flush=True)
    elif cfg["scene"] in ("grid", "seismic", "field", "lod", "scale", "big-volume"):
        import importlib

        mod = importlib.import_module(f".{cfg['scene'].replace('-', '_')}", __package__)
        result = mod.run(cfg)
        print(mod.format_table(result), flush=True)
    else:
        result = gullfaks.run(cfg)
        print(gullfaks.format_table(result), flush=True)
    if a.plot and cfg["scene"] == "gullfaks":
        from .report import plot

        rows = [r for r in result["rows"] if r.get("differing_pixel_fraction") is not None]
        plot(rows, a.plot, title=f"geocull bench ({cfg['mode']}): speed against error, {cfg['width']}x{cfg['height']}")
        _say(f"bench: wrote {a.plot}")
    if a.json:
        from .report import write_json

        d = os.path.dirname(os.path.abspath(a.json))
        os.makedirs(d, exist_ok=True)
        write_json(result, a.json)
        _say(f"bench: wrote {a.json}")
    return 0
