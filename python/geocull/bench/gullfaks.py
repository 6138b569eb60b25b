"""``python -m geocull bench`` (``--scene gullfaks``, the default): geocull's culling methods against
each other and against PyVista on a Gullfaks-like scene; the command line and what it measures are
described in :mod:`geocull.bench`."""

from __future__ import annotations

import math
import os
import platform
import resource
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _progress
from .._progress import ProgressLike

__all__ = ["run", "format_table"]

THRESHOLD = 10
COARSE_FACTOR = 25  # the seeds' setting
COARSE_ALT = 100  # a cheaper prepass: lattice proxies at stride 10
TILES = (10, 10)
QUICK_VIEWS = ("oblique_az045", "low_az200", "top_down")


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _rss_mb() -> float:
    """Peak resident set size of this process so far, MiB (Linux reports KiB)."""
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / 1024.0 if sys.platform != "darwin" else r / 2**20


def _select_views(views, spec_arg) -> list:
    from ..data import standard_views

    all_views = standard_views(*spec_arg)
    if views is None:
        return all_views
    views = str(views).strip()
    if views.isdigit():
        n = int(views)
        if n < 1:
            raise SystemExit("--views: need at least 1")
        return all_views[:n]
    names = [v.strip() for v in views.split(",") if v.strip()]
    byname = dict(all_views)
    bad = [n for n in names if n not in byname]
    if bad:
        raise SystemExit(f"--views: unknown view(s) {bad}; known: {', '.join(byname)}")
    return [(n, byname[n]) for n in names]


def run(cfg: dict[str, Any], progress: ProgressLike = None) -> dict[str, Any]:
    """Run the benchmark described by ``cfg`` (see :func:`geocull.bench.cli.config`); returns summary and rows.
    progress: None (a bar in notebooks, silence in scripts: the command line prints its own
    messages), True, False or ``f(fraction, message)`` over the two scene builds and the views
    (:mod:`geocull._progress`)."""
    with _progress.task(progress, 1, "bench") as task:
        return _run(cfg, task)


def _run(cfg: dict[str, Any], task: _progress.Task) -> dict[str, Any]:
    t_start = time.perf_counter()
    sc = _build_scenes(cfg, task)
    views = _select_views(cfg["views"], (sc.spec, 45.0, 1.0, sc.w / sc.h))
    methods = _methods(cfg)
    acc = _Acc()
    for vi, (vname, kw) in enumerate(views):
        _run_view(cfg, task, sc, acc, methods, vi, views, vname, kw, t_start)
    orbit = _orbit(sc.render, views, cfg)
    return dict(summary=_summary(cfg, sc, acc, views, orbit, t_start), rows=acc.rows)


@dataclass
class _Scenes:
    """The built scenes of a run (two coarse factors, each in its own renderer) and what their
    building measured."""

    w: int
    h: int
    spec: Any
    gen_s: float
    build_s: float
    rss_before: float
    rss_fixed: float
    scene: Any
    renderer: Any
    render: Callable[[Any, dict[str, Any]], Any]


@dataclass
class _Acc:
    """What the views loop gathers: the rows, the first view's memory, PyVista's module and setups."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    rss_geocull: float | None = None
    gpu_bytes: int | None = None
    pv_setup_s: list[float] = field(default_factory=list)
    gpv: Any = None
    pv_versions: dict[str, str] = field(default_factory=dict)


def _build_scenes(cfg: dict[str, Any], task: _progress.Task) -> _Scenes:
    """The build stage: the scene's data, a renderer's fixed cost, the two scenes and their renderers."""
    import geocull as gc

    from ..data import gullfaks_like

    w, h = int(cfg["width"]), int(cfg["height"])
    _say(f"bench[{cfg['mode']}]: generating scene {cfg['size']}x{cfg['size']} samples, {cfg['n_faults']} faults")
    t0 = time.perf_counter()
    spec = gullfaks_like(nx=cfg["size"], ny=cfg["size"], n_faults=cfg["n_faults"],
                         fault_triangles=cfg["fault_triangles"])
    gen_s = time.perf_counter() - t0
    rss_before = _rss_mb()  # the process with the scene's numpy data, before any geocull object
    # What geocull costs whatever the scene: a renderer of this size (the driver, lavapipe's JIT
    # pipelines of every method) on a one-tile scene. The growth above it is the scenes' own.
    fixed_renderer, fixed_scene = gc.Renderer(w, h), gc.Scene()
    fixed_scene.add_heightfield(np.zeros((3, 3)))
    fixed_cam = gc.Camera.look_at((0.5, -2.0, 2.0), (1.0, 1.0, 0.0))
    for kind in ("none", "three_pass", "temporal", "oracle"):
        for lod in ("full", "screen_error"):
            fixed_renderer.render(fixed_scene, fixed_cam, culling=kind, lod=lod)
    rss_fixed = _rss_mb()
    task.total = 2 + len(_select_views(cfg["views"], (spec, 45.0, 1.0, w / h)))  # two builds, then the views
    _say(f"bench: building tiles + LOD (tiles {TILES[0]}x{TILES[1]}, coarse factor {COARSE_FACTOR})")
    t0 = time.perf_counter()
    scene = spec.build(tiles=TILES, coarse_factor=COARSE_FACTOR)
    build_s = time.perf_counter() - t0
    task.advance(1, "bench: second scene (coarser proxies)")
    renderer = gc.Renderer(w, h)
    # The same scene with coarser proxies (a cheaper prepass), in its own renderer so that
    # switching scenes never re-uploads geometry inside a timed frame.
    scene_alt = spec.build(tiles=TILES, coarse_factor=COARSE_ALT)
    task.advance(1, "bench: views")
    targets = {COARSE_FACTOR: (scene, renderer), COARSE_ALT: (scene_alt, gc.Renderer(w, h))}
    for _, rr in targets.values():
        rr.pass_triangles = cfg.get("pass_triangles")
    # The renderer that measured the fixed cost is no renderer of the scenes: its targets go now (the
    # device and its pipelines stay, shared by the scenes' renderers).
    del fixed_renderer, fixed_scene

    def render(cam, rk):
        rk = dict(rk)
        sc, rr = targets[rk.pop("coarse_factor", COARSE_FACTOR)]
        return rr.render(sc, cam, **rk)

    return _Scenes(w=w, h=h, spec=spec, gen_s=gen_s, build_s=build_s, rss_before=rss_before, rss_fixed=rss_fixed,
                   scene=scene, renderer=renderer, render=render)


def _methods(cfg: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """(name, render keyword arguments) of geocull's methods, in table order."""
    methods: list[tuple[str, dict[str, Any]]] = [
        ("none", dict(culling="none")),
        ("three_pass(s=1)", dict(culling="three_pass", pixel_threshold=THRESHOLD, prepass_scale=1.0,
                                 conservative=False)),
        ("three_pass(s=0.5)", dict(culling="three_pass", pixel_threshold=THRESHOLD, prepass_scale=0.5,
                                   conservative=False)),
        (f"three_pass(cf={COARSE_ALT},s=0.5)",
         dict(culling="three_pass", pixel_threshold=THRESHOLD, prepass_scale=0.5, coarse_factor=COARSE_ALT,
              conservative=False)),
        ("three_pass(cons,t=0)", dict(culling="three_pass", pixel_threshold=0)),  # default prepass_scale (1/2)
        (f"three_pass(cons,t=0,cf={COARSE_ALT},s=0.5)",
         dict(culling="three_pass", pixel_threshold=0, prepass_scale=0.5, coarse_factor=COARSE_ALT)),
        ("none(lod=0.5)", dict(culling="none", lod="screen_error", max_pixel_error=0.5)),
        *[(f"three_pass(cons,lod={e:g})",
           dict(culling="three_pass", pixel_threshold=0, lod="screen_error", max_pixel_error=e))
          for e in (0.5, 1.0, 2.0)],
        # History = its own last frame of the same view (the rounds repeat each view): the static-
        # camera case; the orbit section below measures a moving camera.
        ("temporal(t=0)", dict(culling="temporal", pixel_threshold=0)),
        ("temporal(lod=0.5)", dict(culling="temporal", pixel_threshold=0, lod="screen_error", max_pixel_error=0.5)),
        ("oracle", dict(culling="oracle")),
    ]
    if cfg["horizon"]:
        methods.append(("horizon", dict(culling="horizon")))
    return methods


def _import_pyvista(acc: _Acc) -> None:
    """geocull.pyvista and the versions into ``acc`` (imported after geocull's first view so that
    peak_rss_geocull_mb excludes VTK); a message and no PyVista rows where it cannot be imported."""
    try:
        import pyvista
        import vtk

        from .. import pyvista as gpv_mod

        acc.pv_versions.update(pyvista=pyvista.__version__, vtk=vtk.vtkVersion.GetVTKVersion())
        acc.gpv = gpv_mod
    except Exception as e:  # pragma: no cover - environment dependent
        _say(f"bench: PyVista unavailable ({e}); skipping its rows")


def _run_view(cfg: dict[str, Any], task: _progress.Task, sc: _Scenes, acc: _Acc,
              methods: list[tuple[str, dict[str, Any]]], vi: int, views: list, vname: str, kw: Any,
              t_start: float) -> None:
    """One view: warm-up frames and image errors, the first view's memory, timed rounds, its rows."""
    import geocull as gc

    task.update(task.done, f"bench: view {vi + 1}/{len(views)} {vname}")
    cam = gc.Camera.look_at(**kw)
    _say(f"bench: view {vi + 1}/{len(views)} {vname}: warm-up")
    ref, first = _warm_up(sc.render, cam, methods)
    if acc.gpu_bytes is None:
        acc.gpu_bytes = int(sc.renderer.gpu_bytes)
    if acc.rss_geocull is None:
        acc.rss_geocull = _rss_mb()
        if cfg["pyvista"]:
            _import_pyvista(acc)
    jobs, times, pv_out = _timed_view(cfg, sc, acc, methods, cam, vname, ref)
    acc.rows.extend(_view_rows(vname, jobs, times, first, dict(methods), pv_out, ref, sc.scene))
    del first, ref
    _say(f"bench: view {vname}: done ({time.perf_counter() - t_start:.0f} s so far)")
    task.advance(1)


def _warm_up(render: Callable[[Any, dict[str, Any]], Any], cam: Any,
             methods: list[tuple[str, dict[str, Any]]]) -> tuple[Any, dict[str, dict[str, Any]]]:
    """One warm-up frame per method (temporal twice: its history is then this view, the timed
    rounds' case). Only the reference frames (none; the oracle's visible tiles) are kept: every
    other frame is reduced to the numbers its row needs at once, so that the memory measured after
    the first view is geocull's and not a dozen 1280x1024 frames held by this benchmark. Returns
    (none's frame, per method :func:`_warm_summary`)."""
    ref = render(cam, dict(methods)["none"])
    visible = np.asarray(render(cam, dict(methods)["oracle"]).tile_pixels)
    first: dict[str, dict[str, Any]] = {}
    for name, rk in methods:
        res = ref if name == "none" else render(cam, rk)
        if rk["culling"] == "temporal":
            res = render(cam, rk)
        first[name] = _warm_summary(res, ref, visible)
        del res
    return ref, first


def _timed_view(cfg: dict[str, Any], sc: _Scenes, acc: _Acc, methods: list[tuple[str, dict[str, Any]]], cam: Any,
                vname: str, ref: Any) -> tuple[list[tuple[str, Any]], dict[str, list[float]], dict[str, Any]]:
    """The timed rounds of one view: every method, and PyVista (set up and warmed up first) where
    imported. Returns (jobs, their times, PyVista's (image, depth) per row name)."""
    from . import report

    render = sc.render

    def gjob(rk, cam=cam):  # cam bound at definition (B023); the jobs run in this call
        return lambda: render(cam, rk).stats["total_ms"]

    jobs = [(name, gjob(rk)) for name, rk in methods]
    setups = {}
    if acc.gpv is not None:
        for name, msaa in (("pyvista", False), ("pyvista_msaa", True)):
            _say(f"bench: view {vname}: PyVista setup ({'MSAA on' if msaa else 'MSAA off'})")
            t0 = time.perf_counter()
            st = acc.gpv._Setup(sc.scene, cam, sc.w, sc.h, msaa, True, ref.near, ref.far, (0.0, 0.0, 0.0), 1e-4)
            st.render()  # warm-up: context, shaders, geometry upload
            acc.pv_setup_s.append(time.perf_counter() - t0)
            setups[name] = st
            jobs.append((name, st.render))
    try:
        _say(f"bench: view {vname}: {cfg['repeats']} timed round(s) of {len(jobs)} methods")
        times = report.timed_rounds(jobs, cfg["repeats"])
        pv_out = {name: st.read() for name, st in setups.items()}
    finally:
        for st in setups.values():
            st.close()
    return jobs, times, pv_out


def _view_rows(vname: str, jobs: list[tuple[str, Any]], times: dict[str, list[float]],
               first: dict[str, dict[str, Any]], by_name: dict[str, dict[str, Any]], pv_out: dict[str, Any],
               ref: Any, scene: Any) -> list[dict[str, Any]]:
    """The rows of one view, one per timed job, in the jobs' order."""
    t_none = min(times["none"])
    t_oracle = min(times["oracle"])
    t_pv = min(times["pyvista"]) if "pyvista" in times else None
    t_pvm = min(times["pyvista_msaa"]) if "pyvista_msaa" in times else None
    rows = []
    for name, _ in jobs:
        t = min(times[name])
        row: dict[str, Any] = dict(
            view=vname,
            method=name,
            total_ms=t,
            median_ms=statistics.median(times[name]),
            ratio_to_none=t / t_none,
            ratio_to_oracle=t / t_oracle,
            ratio_to_pyvista=t / t_pv if t_pv else None,
            ratio_to_pyvista_msaa=t / t_pvm if t_pvm else None,
            times_ms=times[name],
        )
        if name in first:
            row.update(_geocull_columns(first[name], by_name[name]))
        else:
            row.update(_pyvista_columns(name, pv_out[name], ref, scene))
        rows.append(row)
    return rows


def _geocull_columns(warm: dict[str, Any], rk: dict[str, Any]) -> dict[str, Any]:
    """A geocull row's columns beyond the times: its method's options, warm-up stats and image errors."""
    s = warm["stats"]
    return dict(
        renderer="geocull",
        culling=rk["culling"],
        pixel_threshold=rk.get("pixel_threshold"),
        prepass_scale=rk.get("prepass_scale"),
        coarse_factor=rk.get("coarse_factor", COARSE_FACTOR) if rk["culling"] == "three_pass" else None,
        triangles_drawn=int(s["triangles_drawn"]),
        triangles_prepass=int(s.get("triangles_prepass", 0)),
        tiles_drawn=int(s["tiles_drawn"]),
        tiles_total=int(s["tiles_total"]),
        differing_pixel_fraction=warm["differing_pixel_fraction"],
        # beyond a shading tolerance of 4/255: LOD changes the flat shading of facets
        differing_pixel_fraction_tol4=warm["differing_pixel_fraction_tol4"],
        psnr=warm["psnr"],
        missing_tiles=warm["missing_tiles"],
        coverage_agreement=warm["coverage_agreement"],
        depth_median_rel=None,
        depth_p99_rel=None,
        prepass_ms=float(s.get("prepass_ms", 0.0)),
        count_ms=float(s.get("count_ms", 0.0)),
        draw_ms=float(s.get("draw_ms", 0.0)),
        cull_ms=float(s.get("cull_ms", 0.0)),
    )


def _pyvista_columns(name: str, out: Any, ref: Any, scene: Any) -> dict[str, Any]:
    """A PyVista row's columns beyond the times: its depth against none's."""
    from ..compare import coverage_agreement, depth_error

    img, depth = out
    de = depth_error(depth, ref.depth)
    return dict(
        renderer="pyvista",
        culling=None,
        msaa=name == "pyvista_msaa",
        pixel_threshold=None,
        prepass_scale=None,
        triangles_drawn=int(scene.n_triangles),
        tiles_drawn=None,
        tiles_total=None,
        differing_pixel_fraction=None,
        psnr=None,
        missing_tiles=None,
        coverage_agreement=coverage_agreement(depth, ref.depth),
        depth_median_rel=de["median_rel"],
        depth_p99_rel=de["p99_rel"],
        depth_fraction_over_1e3=de["fraction_over_tol"],
    )


def _per_method(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Geometric means over views of the ratios, mean/max image errors, per method."""
    per_method: dict[str, dict[str, Any]] = {}
    for name in dict.fromkeys(r["method"] for r in rows):
        rs = [r for r in rows if r["method"] == name]
        dpf = [r["differing_pixel_fraction"] for r in rs if r["differing_pixel_fraction"] is not None]
        dpt = [r["differing_pixel_fraction_tol4"] for r in rs if r.get("differing_pixel_fraction_tol4") is not None]
        per_method[name] = dict(
            mean_differing_pixel_fraction_tol4=(sum(dpt) / len(dpt)) if dpt else None,
            ratio_to_none=_gmean(r["ratio_to_none"] for r in rs),
            ratio_to_oracle=_gmean(r["ratio_to_oracle"] for r in rs),
            ratio_to_pyvista=_gmean(r["ratio_to_pyvista"] for r in rs),
            ratio_to_pyvista_msaa=_gmean(r["ratio_to_pyvista_msaa"] for r in rs),
            mean_differing_pixel_fraction=(sum(dpf) / len(dpf)) if dpf else None,
            max_differing_pixel_fraction=max(dpf) if dpf else None,
            missing_tiles=sum(r["missing_tiles"] for r in rs) if rs[0]["missing_tiles"] is not None else None,
            mean_triangles_drawn=sum(r["triangles_drawn"] for r in rs) / len(rs),
        )
    return per_method


def _summary(cfg: dict[str, Any], sc: _Scenes, acc: _Acc, views: list, orbit: dict[str, Any],
             t_start: float) -> dict[str, Any]:
    """The run's summary: its settings, the scene, memory, the environment, per-method means, the orbit."""
    import geocull as gc

    per_method = _per_method(acc.rows)
    scene, rss_geocull, gpu_bytes = sc.scene, acc.rss_geocull, acc.gpu_bytes
    n_tri = int(scene.n_triangles)
    host = int(scene.host_bytes)
    return dict(
        mode=cfg["mode"],
        width=sc.w,
        height=sc.h,
        repeats=int(cfg["repeats"]),
        views=[v for v, _ in views],
        samples=int(cfg["size"]),
        n_horizons=len(sc.spec.horizons),
        n_faults=len(sc.spec.faults),
        tiles=f"{TILES[0]}x{TILES[1]}",
        coarse_factor=COARSE_FACTOR,
        pixel_threshold=THRESHOLD,
        scene_generate_s=sc.gen_s,
        scene_build_s=sc.build_s,
        n_triangles=n_tri,
        n_tiles=int(scene.n_tiles),
        host_bytes=host,
        gpu_bytes=gpu_bytes,
        bytes_per_triangle=(host + (gpu_bytes or 0)) / n_tri if n_tri else None,
        peak_rss_geocull_mb=rss_geocull,
        rss_before_geocull_mb=sc.rss_before,
        # Both scenes (two coarse factors) and their renderers count: the growth of the peak over
        # the process before geocull, per fine triangle of the two scenes.
        rss_bytes_per_triangle=((rss_geocull - sc.rss_before) * 2**20 / (2 * n_tri))
        if rss_geocull and n_tri else None,
        rss_fixed_mb=sc.rss_fixed - sc.rss_before,
        pass_triangles=cfg.get("pass_triangles"),
        # The same growth above a renderer's fixed cost (driver, JIT pipelines): the scenes' own.
        rss_scene_bytes_per_triangle=((rss_geocull - sc.rss_fixed) * 2**20 / (2 * n_tri))
        if rss_geocull and n_tri else None,
        peak_rss_mb=_rss_mb(),
        pyvista_setup_s_mean=(sum(acc.pv_setup_s) / len(acc.pv_setup_s)) if acc.pv_setup_s else None,
        adapter=sc.renderer.adapter_info,
        cpu_count=os.cpu_count(),
        python=platform.python_version(),
        geocull=gc.__version__,
        **acc.pv_versions,
        wall_s=time.perf_counter() - t_start,
        per_method=per_method,
        orbit=orbit,
    )


ORBIT_METHODS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("none", dict(culling="none")),
    (f"three_pass(cons,t=0,cf={COARSE_ALT},s=0.5)",
     dict(culling="three_pass", pixel_threshold=0, prepass_scale=0.5, coarse_factor=COARSE_ALT)),
    ("temporal(t=0)", dict(culling="temporal", pixel_threshold=0)),
    ("oracle", dict(culling="oracle")),
    ("none(lod=0.5)", dict(culling="none", lod="screen_error", max_pixel_error=0.5)),
    ("temporal(lod=0.5)", dict(culling="temporal", pixel_threshold=0, lod="screen_error", max_pixel_error=0.5)),
)


def _orbit(render, views, cfg: dict[str, Any]) -> dict[str, Any]:
    """A moving camera: from each of the first views, ``orbit_frames`` frames turning the azimuth by
    ``orbit_step`` degrees each (a user dragging the view), every method over the whole sequence,
    the methods interleaved over two rounds. temporal's history is the previous frame of the
    sequence (its first frame follows one untimed frame of the view itself). Returns per method the
    best round's mean frame time, its ratios to none and oracle, and the frames whose temporal
    image differs from none's at the same level of detail."""
    import geocull as gc

    frames, step = int(cfg.get("orbit_frames", 8)), float(cfg.get("orbit_step", 2.0))
    n_views = 1 if cfg["mode"] != "full" else 4
    seqs = []
    for _, kw in views[:n_views]:
        cam = gc.Camera.look_at(**kw)
        seqs.append([cam.rotated(k * step, 0.0) for k in range(frames + 1)])
    best: dict[str, float] = {name: math.inf for name, _ in ORBIT_METHODS}
    differing = 0
    for rnd in range(2):
        for name, rk in ORBIT_METHODS:
            total = 0.0
            for seq in seqs:
                render(seq[0], rk)  # the frame before the drag (temporal's history)
                for cam in seq[1:]:
                    res = render(cam, rk)
                    total += res.stats["total_ms"]
                    if rnd == 0 and rk["culling"] == "temporal":
                        same_lod = {k: v for k, v in rk.items() if k != "pixel_threshold"}
                        ref = render(cam, same_lod | dict(culling="none"))
                        differing += int(not np.array_equal(res.image, ref.image))
            best[name] = min(best[name], total / (frames * len(seqs)))
    t_none, t_oracle = best["none"], best["oracle"]
    return dict(
        views=n_views,
        frames=frames,
        step_deg=step,
        methods={name: dict(mean_ms=t, ratio_to_none=t / t_none, ratio_to_oracle=t / t_oracle)
                 for name, t in best.items()},
        temporal_frames_differing=differing,
    )


def _warm_summary(res: Any, ref: Any, visible: np.ndarray) -> dict[str, Any]:
    """What a benchmark row needs of a warm-up frame ``res``, against the unculled frame ``ref``
    and the oracle's visible pixels per tile: its stats and image errors (the frame is not kept)."""
    from ..compare import coverage_agreement, image_error

    err = image_error(res.image, ref.image, tile_drawn=res.tile_drawn, reference_tile_pixels=visible)
    return dict(
        stats=dict(res.stats),
        differing_pixel_fraction=err["differing_pixel_fraction"],
        differing_pixel_fraction_tol4=image_error(res.image, ref.image, threshold=4)["differing_pixel_fraction"],
        psnr=err["psnr"],
        missing_tiles=err["missing_tiles"],
        coverage_agreement=coverage_agreement(res.depth, ref.depth),
    )


def _gmean(xs) -> float | None:
    xs = [float(x) for x in xs if x is not None and x > 0]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else None


def _f(v, fmt: str, none: str = "–") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return none
    return format(v, fmt)


def format_table(result: dict[str, Any]) -> str:
    """The benchmark as plain text: one table (all views), per-method means, and the summary."""
    s = result["summary"]
    rows = result["rows"]
    lines = []
    lines.append(
        f"geocull bench ({s['mode']}): {s['n_horizons']} horizons {s['samples']}x{s['samples']} + "
        f"{s['n_faults']} faults, "
        f"{s['width']}x{s['height']}, {len(s['views'])} view(s), best of {s['repeats']} round(s) after a warm-up; "
        f"three_pass: threshold {s['pixel_threshold']}, coarse factor {s['coarse_factor']}, tiles {s['tiles']}"
    )
    lines.append("")
    hdr = (f"{'view':<14} {'method':<24} {'ms':>9} {'x none':>7} {'x oracle':>8} {'x pv':>6} {'x pv_msaa':>9} "
           f"{'triangles':>11} {'tiles':>11} {'diff px %':>9} {'missing':>7} {'cov agree':>9} {'depth err':>9}")
    lines.append(hdr)
    lines.append("-" * len(hdr))
    last_view = None
    for r in rows:
        if last_view is not None and r["view"] != last_view:
            lines.append("")
        last_view = r["view"]
        tiles = f"{r['tiles_drawn']}/{r['tiles_total']}" if r.get("tiles_drawn") is not None else "all"
        dpf = r.get("differing_pixel_fraction")
        lines.append(
            f"{r['view']:<14} {r['method']:<24} {r['total_ms']:>9.1f} {r['ratio_to_none']:>7.3f} "
            f"{r['ratio_to_oracle']:>8.3f} {_f(r.get('ratio_to_pyvista'), '.3f'):>6} "
            f"{_f(r.get('ratio_to_pyvista_msaa'), '.3f'):>9} {r['triangles_drawn']:>11,} {tiles:>11} "
            f"{_f(None if dpf is None else 100 * dpf, '.4f'):>9} {_f(r.get('missing_tiles'), 'd'):>7} "
            f"{_f(r.get('coverage_agreement'), '.4f'):>9} {_f(r.get('depth_median_rel'), '.1e'):>9}"
        )
    lines.append("")
    lines.append("geometric mean over views (ratios), mean/max differing pixels, total missing tiles:")
    for name, m in s["per_method"].items():
        dp = m["mean_differing_pixel_fraction"]
        mx = m["max_differing_pixel_fraction"]
        dt = m.get("mean_differing_pixel_fraction_tol4")
        lines.append(
            f"  {name:<24} x none {_f(m['ratio_to_none'], '.3f')}  x oracle {_f(m['ratio_to_oracle'], '.3f')}  "
            f"x pyvista {_f(m['ratio_to_pyvista'], '.3f')}  x pyvista_msaa {_f(m['ratio_to_pyvista_msaa'], '.3f')}  "
            f"diff px {_f(None if dp is None else 100 * dp, '.4f')} % "
            f"(max {_f(None if mx is None else 100 * mx, '.4f')} %)  "
            f"beyond 4/255 {_f(None if dt is None else 100 * dt, '.4f')} %  "
            f"missing tiles {_f(m['missing_tiles'], 'd')}"
        )
    o = s.get("orbit")
    if o:
        lines.append("")
        lines.append(f"moving camera: {o['views']} view(s) x {o['frames']} frames, azimuth +{o['step_deg']:g} deg per "
                     f"frame; mean frame time (best of 2 rounds); temporal frames differing from none: "
                     f"{o['temporal_frames_differing']}")
        for name, m in o["methods"].items():
            lines.append(f"  {name:<32} {m['mean_ms']:>8.1f} ms  x none {m['ratio_to_none']:.3f}  "
                         f"x oracle {m['ratio_to_oracle']:.3f}")
    lines.append("")
    bpt = s["bytes_per_triangle"]
    lines.append(f"scene: {s['n_triangles']:,} triangles in {s['n_tiles']:,} tiles; "
                 f"generated in {s['scene_generate_s']:.2f} s, "
                 f"tiles + LOD built in {s['scene_build_s']:.2f} s (target < 2 s on 2 cores for the full scene)")
    lines.append(f"memory: host {s['host_bytes'] / 2**20:.1f} MiB + GPU {(s['gpu_bytes'] or 0) / 2**20:.1f} MiB = "
                 f"{_f(bpt, '.1f')} bytes per fine triangle (target <= 40); "
                 f"peak RSS {s['peak_rss_geocull_mb']:.0f} MiB "
                 f"after geocull's first view, {s['peak_rss_mb']:.0f} MiB at the end (PyVista included); "
                 f"attributable to geocull (peak growth over {s['rss_before_geocull_mb']:.0f} MiB before its first "
                 f"object, two scenes and their renderers): {_f(s.get('rss_bytes_per_triangle'), '.0f')} bytes per "
                 f"fine triangle (target <= 60), of which a renderer's fixed cost (driver, JIT pipelines, "
                 f"one-tile scene) is {_f(s.get('rss_fixed_mb'), '.0f')} MiB and the scenes' own "
                 f"{_f(s.get('rss_scene_bytes_per_triangle'), '.0f')} bytes per fine triangle; "
                 f"Renderer.pass_triangles {s.get('pass_triangles') or 'unbounded'}")
    pv = f"; PyVista {s['pyvista']}, VTK {s['vtk']}" if "pyvista" in s else ""
    lines.append(f"adapter: {s['adapter']}{pv}; {s['cpu_count']} CPU(s); wall {s['wall_s']:.0f} s")
    lines.append("columns: ms = best frame time (geocull stats total_ms: call -> GPU done; PyVista: Render + "
                 "WaitForCompletion); x = ratio of frame times, same view, same run; diff px = differing pixels vs "
                 "geocull none; missing = tiles visible unculled but not drawn; "
                 "cov agree = coverage agreement vs none; "
                 "depth err = median relative depth difference vs none (PyVista)")
    return "\n".join(lines)
