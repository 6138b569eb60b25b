"""Speed against error: parameter sweeps, tables and plots.

``sweep``        render a scene with ``none``, ``oracle`` and ``three_pass`` (over pixel thresholds,
                 prepass scales, and, from a :class:`~geocull.data.SceneSpec`, tile counts and coarse
                 factors) from a set of cameras, timed side by side; returns a table (list of dicts)
``summarize``    one row per configuration over all views (geometric-mean ratios, mean/max errors)
``plot``         speed (ratio to none) against error (differing pixel fraction), one numbered marker
                 per configuration and a key of the numbers (matplotlib); ``figure`` the same as a
                 matplotlib Figure
``to_markdown``  a table as GitHub markdown;  ``to_frame``  as a pandas DataFrame (if installed)
``timed_rounds`` the side-by-side timing loop (warm-up, then interleaved rounds in rotated order)

Timing: every method of one view is rendered once as a warm-up (this also uploads a new scene and
gives the images used for the errors: renders are deterministic), then ``repeats`` rounds render
each method once, in an order rotated every round so no method always runs first or last. A frame
time is the renderer's ``stats["total_ms"]`` (wall time from the call until the GPU is done,
excluding read-back); a point's time is the minimum over the rounds (the median is kept too).
Ratios divide by ``none``'s (and ``oracle``'s) time of the same view, scene and run.

Errors are against the unculled (``none``) image of the same view: ``differing_pixel_fraction``
(any channel differs), ``psnr``, and ``missing_tiles`` = tiles visible in the unculled image
(``oracle``'s ``tile_pixels > 0``) that the method did not draw.

Method names: ``"three_pass"`` here is the paper's *approximate* mode (``conservative=False``),
while :meth:`geocull.Renderer.render`'s ``culling="three_pass"`` is conservative by default;
``"three_pass_cons"`` is the conservative mode. Every row says which in its ``mode`` column
(:data:`MODES`: "approximate (paper)", "conservative"), and tables and plots name them so.
"""

from __future__ import annotations

import itertools
import math
import statistics
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal, overload

import numpy as np

from .. import _progress
from .._errors import InputError
from .._progress import ProgressLike
from ._report_tables import COLUMNS as COLUMNS  # the table's columns and their kinds (documented here)
from ._report_tables import INT_COLUMNS as INT_COLUMNS
from ._report_tables import PARAM_COLUMNS as PARAM_COLUMNS
from ._report_tables import jsonable, to_frame, to_markdown, write_json

if TYPE_CHECKING:
    from ..camera import Camera
    from ..data import SceneSpec
    from ..renderer import CullingMode, Renderer
    from ..scene import Scene

    #: What ``sweep`` takes as cameras (see there).
    Cameras = (
        Iterable[Camera | Mapping[str, Any] | tuple[str, Camera | Mapping[str, Any]]]
        | Mapping[str, Camera | Mapping[str, Any]]
        | None
    )

__all__ = ["sweep", "summarize", "plot", "figure", "to_markdown", "to_frame", "timed_rounds", "best_frame",
           "write_json", "jsonable", "method_name", "MODES"]

DEFAULT_THRESHOLDS = (0, 10, 50)
DEFAULT_COARSE_FACTORS = (25, 100, 400)
DEFAULT_TILES = ((10, 10),)
DEFAULT_PREPASS_SCALES = (1.0, 0.5, 0.25)

#: The ``mode`` of the sweep's three_pass methods: the paper's approximate culling and the conservative one.
MODES = {"three_pass": "approximate (paper)", "three_pass_cons": "conservative"}


def _mode(method: str) -> str | None:
    """The three_pass mode of a method: the sweep's names (:data:`MODES`) and the benchmark's
    ("three_pass(s=1)" approximate, "three_pass(cons,t=0)" conservative); None for other methods."""
    if method in MODES:
        return MODES[method]
    if method.startswith("three_pass(") and method.endswith(")"):
        return MODES["three_pass_cons" if "cons" in method[11:-1].split(",") else "three_pass"]
    return None


def _family(method: str) -> str:
    """The method a plot colours a point by: "three_pass" (approximate), "three_pass_cons", or the
    culling mode before any "(...)" of the benchmark's names."""
    if _mode(method) == MODES["three_pass_cons"]:
        return "three_pass_cons"
    return method.split("(")[0]


def method_name(method: str) -> str:
    """A method as tables and plots show it: ``"three_pass, approximate (paper)"``,
    ``"three_pass, conservative"`` (:data:`MODES`), the benchmark's three_pass names with their
    mode (``"three_pass(s=1), approximate (paper)"``), else the method itself."""
    mode = _mode(method)
    if mode is None:
        return method
    return f"three_pass, {mode}" if method in MODES else f"{method}, {mode}"


# --------------------------------------------------------------------------- helpers


def _tiles_tuple(t) -> tuple[int, int]:
    if isinstance(t, (int, np.integer)):
        return (int(t), int(t))
    a, b = t
    return (int(a), int(b))


def _cameras(cameras, spec, width: int, height: int) -> list[tuple[str, Any]]:
    """Normalise cameras: None (standard views of ``spec``), a dict name -> camera, or a list of
    cameras / look_at kwargs dicts / (name, camera-or-kwargs) pairs."""
    import geocull as gc

    if cameras is None:
        if spec is None:
            raise InputError("cameras: required when sweeping a Scene (no SceneSpec to frame views from)")
        from ..data import standard_views

        cameras = standard_views(spec, aspect=width / height)
    if isinstance(cameras, dict):
        cameras = list(cameras.items())
    out = []
    for i, c in enumerate(cameras):
        name = f"view{i}"
        if isinstance(c, tuple) and len(c) == 2 and isinstance(c[0], str):
            name, c = c
        if isinstance(c, dict):
            c = gc.Camera.look_at(**c)
        if not isinstance(c, gc.Camera):
            raise InputError(f"cameras[{i}]: expected a geocull.Camera, look_at kwargs or (name, camera), got {c!r}")
        out.append((str(name), c))
    if not out:
        raise InputError("cameras: empty")
    return out


def timed_rounds(
    jobs: Sequence[tuple[Any, Callable[[], float]]], repeats: int, warmup: int = 0
) -> dict[Any, list[float]]:
    """Run every ``(key, fn)`` of ``jobs`` once per round, ``repeats`` rounds, rotating the order by
    one each round (``fn`` returns milliseconds). ``warmup`` extra rounds first, not recorded.
    Returns key -> list of times."""
    times: dict[Any, list[float]] = {k: [] for k, _ in jobs}
    n = len(jobs)
    for r in range(warmup + max(1, int(repeats))):
        for i in range(n):
            k, fn = jobs[(i + r) % n]
            t = fn()
            if r >= warmup:
                times[k].append(float(t))
    return times


def best_frame(render: Callable[..., Any], repeats: int) -> tuple[Any, float]:
    """One warm-up call of ``render`` (uploads, pipelines), then ``repeats`` timed ones: (the last
    result, the best ``stats["total_ms"]``, milliseconds)."""
    render()
    out, best = None, float("inf")
    for _ in range(max(1, int(repeats))):
        out = render()
        best = min(best, out.stats["total_ms"])
    return out, best


def _rel(a: float, b: float) -> float | None:
    return None if not b else (a - b) / b


# --------------------------------------------------------------------------- sweep


def _single_point_methods() -> tuple[str, ...]:
    """Culling modes that are one point of a sweep (no parameters): every mode of the core but
    the references (none, oracle, always run) and three_pass (a grid of points)."""
    import geocull as gc

    return tuple(m for m in gc.CULLING_MODES if m not in ("none", "oracle", "three_pass"))


def _values(x, arg: str) -> list:
    """``x`` (any iterable, generators included) as a list, read exactly once; a str is one value."""
    if isinstance(x, (str, bytes)):
        return [x]
    try:
        return list(x)
    except TypeError:
        raise InputError(f"{arg}: expected a sequence of values, got {type(x).__name__}") from None


def _sweep_scene(
    scene, cams, renderer, thresholds, prepass_scales, repeats, methods, base: dict[str, Any], say
) -> list[dict[str, Any]]:
    from ..compare import image_error

    # configurations: key -> render kwargs
    configs: list[tuple[tuple, dict[str, Any]]] = [(("none",), dict(culling="none"))]
    configs.append((("oracle",), dict(culling="oracle")))
    for m in _single_point_methods():  # horizon, frustum, ... in the core's order
        if m in methods:
            configs.append(((m,), dict(culling=m)))
    # "three_pass" is the paper's approximate mode; "three_pass_cons" the conservative one.
    for name, conservative in (("three_pass", False), ("three_pass_cons", True)):
        if name in methods:
            for thr, ps in itertools.product(thresholds, prepass_scales):
                configs.append(
                    ((name, float(thr), float(ps)),
                     dict(culling="three_pass", pixel_threshold=thr, prepass_scale=ps, conservative=conservative))
                )

    rows: list[dict[str, Any]] = []
    for vname, cam in cams:
        say(f"  view {vname}: warm-up ({len(configs)} configurations)")
        first: dict[tuple, Any] = {}
        for key, kw in configs:  # warm-up; keeps one result per config for errors and counts
            first[key] = renderer.render(scene, cam, **kw)
        ref = first[("none",)]
        oracle = first[("oracle",)]
        visible = np.asarray(oracle.tile_pixels)

        def job(kw, cam=cam):  # cam bound at definition (B023); the jobs run in this iteration
            return lambda: renderer.render(scene, cam, **kw).stats["total_ms"]

        say(f"  view {vname}: {repeats} timed round(s)")
        times = timed_rounds([(key, job(kw)) for key, kw in configs], repeats)
        t_none = min(times[("none",)])
        t_oracle = min(times[("oracle",)])
        tri_oracle = oracle.stats["triangles_drawn"]
        for key, kw in configs:
            res = first[key]
            s = res.stats
            t = min(times[key])
            err = image_error(res.image, ref.image, tile_drawn=res.tile_drawn, reference_tile_pixels=visible)
            # Predicted against measured misses of the approximate mode (an extra, untimed render).
            risk: dict[str, Any] = dict(tiles_at_risk=None, predicted_max_missing_pixels=None, missed_not_at_risk=None)
            if key[0] == "three_pass":
                pred = renderer.render(scene, cam, **kw, predict_errors=True)
                missed = (visible > 0) & ~np.asarray(pred.tile_drawn)
                at_risk = pred.tile_at_risk
                assert at_risk is not None
                risk = dict(tiles_at_risk=int(pred.stats.get("tiles_at_risk", 0)),
                            predicted_max_missing_pixels=int(pred.stats.get("predicted_max_missing_pixels", 0)),
                            missed_not_at_risk=int((missed & ~at_risk).sum()))
            rows.append(
                dict(
                    base,
                    view=vname,
                    method=key[0],
                    mode=MODES.get(key[0]),
                    pixel_threshold=key[1] if len(key) > 1 else None,
                    prepass_scale=key[2] if len(key) > 2 else None,
                    total_ms=t,
                    median_ms=statistics.median(times[key]),
                    ratio_to_none=t / t_none if t_none > 0 else None,
                    ratio_to_oracle=t / t_oracle if t_oracle > 0 else None,
                    differing_pixel_fraction=err["differing_pixel_fraction"],
                    psnr=err["psnr"],
                    missing_tiles=err["missing_tiles"],
                    triangles_drawn=int(s["triangles_drawn"]),
                    triangles_prepass=int(s.get("triangles_prepass", 0)),
                    triangles_fine_total=int(s["triangles_fine_total"]),
                    tiles_drawn=int(s["tiles_drawn"]),
                    tiles_total=int(s["tiles_total"]),
                    triangle_diff_vs_oracle=_rel(s["triangles_drawn"], tri_oracle),
                    prepass_ms=float(s.get("prepass_ms", 0.0)),
                    count_ms=float(s.get("count_ms", 0.0)),
                    draw_ms=float(s.get("draw_ms", 0.0)),
                    times_ms=list(times[key]),
                    **risk,
                )
            )
        say(None)  # one view done
    return rows


@overload
def sweep(
    scene_or_spec: SceneSpec | Scene,
    cameras: Cameras = None,
    thresholds: Iterable[float] = DEFAULT_THRESHOLDS,
    coarse_factors: Iterable[float] | None = None,
    tiles: Iterable[int | tuple[int, int]] | None = None,
    prepass_scales: Iterable[float] = DEFAULT_PREPASS_SCALES,
    width: int = 640,
    height: int = 512,
    repeats: int = 3,
    methods: Iterable[CullingMode] = ("none", "oracle", "three_pass"),
    fault_tiles: int | None = None,
    fault_coarse_factor: float = 10,
    renderer: Renderer | None = None,
    progress: ProgressLike = None,
    as_frame: Literal[False] = False,
) -> list[dict[str, Any]]: ...
@overload
def sweep(
    scene_or_spec: SceneSpec | Scene,
    cameras: Cameras = None,
    thresholds: Iterable[float] = DEFAULT_THRESHOLDS,
    coarse_factors: Iterable[float] | None = None,
    tiles: Iterable[int | tuple[int, int]] | None = None,
    prepass_scales: Iterable[float] = DEFAULT_PREPASS_SCALES,
    width: int = 640,
    height: int = 512,
    repeats: int = 3,
    methods: Iterable[CullingMode] = ("none", "oracle", "three_pass"),
    fault_tiles: int | None = None,
    fault_coarse_factor: float = 10,
    renderer: Renderer | None = None,
    progress: ProgressLike = None,
    *,
    as_frame: Literal[True],
) -> Any: ...
def sweep(
    scene_or_spec: SceneSpec | Scene,
    cameras: Cameras = None,
    thresholds: Iterable[float] = DEFAULT_THRESHOLDS,
    coarse_factors: Iterable[float] | None = None,
    tiles: Iterable[int | tuple[int, int]] | None = None,
    prepass_scales: Iterable[float] = DEFAULT_PREPASS_SCALES,
    width: int = 640,
    height: int = 512,
    repeats: int = 3,
    methods: Iterable[CullingMode] = ("none", "oracle", "three_pass"),
    fault_tiles: int | None = None,
    fault_coarse_factor: float = 10,
    renderer: Renderer | None = None,
    progress: ProgressLike = None,
    as_frame: bool = False,
) -> list[dict[str, Any]] | Any:
    """Sweep the culling parameters of a scene and measure speed against error, side by side.

    scene_or_spec: a :class:`geocull.data.SceneSpec` (rebuilt for every tile count × coarse factor)
        or a built :class:`geocull.Scene` (then ``tiles`` and ``coarse_factors`` must be None: a
        built scene cannot change them).
    cameras: None (the spec's :func:`~geocull.data.standard_views`), a list of ``geocull.Camera``,
        ``Camera.look_at`` kwargs dicts or ``(name, camera)`` pairs, or a dict name -> camera.
    thresholds × prepass_scales: the ``three_pass`` points of each scene (full product).
    coarse_factors (default for a spec: 25, 100, 400) × tiles (int n = n × n tiles per horizon, or
        (tx, ty); default for a spec: 10 × 10): one scene build each (faults: ``fault_tiles``,
        ``fault_coarse_factor``).
    methods: names from :data:`geocull.CULLING_MODES` or ``"three_pass_cons"`` (others are an
        InputError); ``none`` and ``oracle`` always run (they are the references); ``"three_pass"``
        is the paper's approximate mode (``conservative=False``; its rows also carry the error
        predictor's ``tiles_at_risk``, ``predicted_max_missing_pixels`` and ``missed_not_at_risk``,
        the missed tiles the predictor called safe, from an extra untimed render);
        ``"three_pass_cons"`` is the conservative mode; add ``"horizon"`` or ``"frustum"`` for the
        CPU cullers; leave out ``"three_pass"`` to time only the references. Every sequence
        argument may be any iterable (a generator too); each is read once.
    repeats: timed rounds after the warm-up round (times are the minimum; ``median_ms`` too).
    renderer: a ``geocull.Renderer`` to reuse (its size wins over width/height).
    progress: None (a bar in notebooks, silence in scripts), True (a bar: tqdm when installed,
        else text on stderr), False, or ``f(fraction, message)``: fractions of the views swept
        (over every scene build), monotone, ending at exactly 1.0 (:mod:`geocull._progress`).

    Returns a list of dicts, one per (scene build, view, method point), with the keys of
    :data:`COLUMNS` (``tiles`` is ``"10x10"``, None for a built scene; ``pixel_threshold`` and
    ``prepass_scale`` are None except for ``three_pass``; ``triangle_diff_vs_oracle`` is
    (drawn − oracle's drawn) / oracle's drawn) plus ``times_ms`` (every timed round). With
    ``as_frame=True`` a pandas DataFrame instead.
    """
    import geocull as gc

    from ..data import SceneSpec

    repeats = max(1, int(repeats))
    # Every iterable argument is read once, here: a generator consumed by a check would otherwise
    # leave nothing for the loops (and silently drop their runs).
    methods = tuple(_values(methods, "methods"))
    valid = (*gc.CULLING_MODES, "three_pass_cons")
    unknown = [m for m in methods if m not in valid]
    if unknown:
        raise InputError(f"methods: unknown method(s) {', '.join(map(repr, unknown))}; valid: {', '.join(valid)}")
    thresholds = _values(thresholds, "thresholds")
    prepass_scales = _values(prepass_scales, "prepass_scales")
    if coarse_factors is not None:
        coarse_factors = _values(coarse_factors, "coarse_factors")
    if tiles is not None:
        tiles = _values(tiles, "tiles")
    is_spec = isinstance(scene_or_spec, SceneSpec)
    spec: SceneSpec | None = None
    if isinstance(scene_or_spec, SceneSpec):
        spec = scene_or_spec
        cfs = list(coarse_factors) if coarse_factors is not None else list(DEFAULT_COARSE_FACTORS)
        tls = [_tiles_tuple(t) for t in tiles] if tiles is not None else list(DEFAULT_TILES)
        if not cfs or not tls:
            raise InputError("coarse_factors, tiles: need at least one value each")
    else:
        if coarse_factors is not None or tiles is not None:
            raise InputError(
                "coarse_factors, tiles: sweeping them rebuilds the scene; pass a geocull.data.SceneSpec, not a Scene"
            )
        if not isinstance(scene_or_spec, gc.Scene):
            raise InputError(
                f"scene_or_spec: expected a SceneSpec or geocull.Scene, got {type(scene_or_spec).__name__}"
            )
    if not thresholds or not prepass_scales:
        raise InputError("thresholds, prepass_scales: need at least one value each")

    if renderer is None:
        renderer = gc.Renderer(int(width), int(height))
    cams = _cameras(cameras, spec, renderer.width, renderer.height)

    n_builds = 1 if not is_spec else len(tls) * len(cfs)
    with _progress.task(progress, n_builds * len(cams), "sweep") as task:
        return _sweep_all(scene_or_spec, spec, cams, renderer, thresholds, prepass_scales, repeats, methods,
                          tls if is_spec else [], cfs if is_spec else [], fault_tiles, fault_coarse_factor,
                          as_frame, task)


def _sweep_all(scene_or_spec, spec, cams, renderer, thresholds, prepass_scales, repeats, methods, tls, cfs,
               fault_tiles, fault_coarse_factor, as_frame: bool, task: _progress.Task) -> Any:
    def say(msg: str | None) -> None:  # a message, or None when a view is done
        if msg is None:
            task.advance(1)
        else:
            task.update(task.done, msg.strip())

    rows: list[dict[str, Any]] = []
    if spec is None:
        say(f"sweep: built scene, {len(cams)} view(s)")
        rows += _sweep_scene(
            scene_or_spec, cams, renderer, thresholds, prepass_scales, repeats, methods,
            dict(tiles=None, coarse_factor=None, build_s=None), say,
        )
    elif spec is not None:
        for tl, cf in itertools.product(tls, cfs):
            say(f"sweep: building scene tiles={tl[0]}x{tl[1]} coarse_factor={cf}")
            t0 = time.perf_counter()
            scene = spec.build(tiles=tl, coarse_factor=cf, fault_tiles=fault_tiles,
                               fault_coarse_factor=fault_coarse_factor)
            build_s = time.perf_counter() - t0
            base = dict(tiles=f"{tl[0]}x{tl[1]}", coarse_factor=cf, build_s=build_s)
            rows += _sweep_scene(scene, cams, renderer, thresholds, prepass_scales, repeats, methods, base, say)
            del scene
    return to_frame(rows) if as_frame else rows


# --------------------------------------------------------------------------- tables


def _config_key(r: dict[str, Any]) -> tuple:
    return (r.get("tiles"), r.get("coarse_factor"), r["method"], r.get("pixel_threshold"), r.get("prepass_scale"))


def _gmean(xs: Iterable[float | None]) -> float | None:
    vals = [float(x) for x in xs if x is not None and x > 0]
    return math.exp(sum(math.log(x) for x in vals) / len(vals)) if vals else None


def _mean(xs):
    xs = [float(x) for x in xs if x is not None]
    return sum(xs) / len(xs) if xs else None


def summarize(table: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per configuration (tiles, coarse factor, method, threshold, prepass scale) over all
    views: geometric means of ``ratio_to_none``/``ratio_to_oracle``, mean and max of
    ``differing_pixel_fraction``, total ``missing_tiles``, mean ``triangles_drawn``,
    ``triangles_prepass``, ``tiles_drawn`` (rounded to whole numbers) and ``triangle_diff_vs_oracle``,
    mean ``total_ms``, ``views`` (how many) and the ``mode`` of three_pass methods."""
    groups: dict[tuple, list[dict[str, Any]]] = {}
    for r in table:
        groups.setdefault(_config_key(r), []).append(r)
    out = []
    for key, rs in groups.items():
        dpf = [r["differing_pixel_fraction"] for r in rs if r.get("differing_pixel_fraction") is not None]
        miss = [r["missing_tiles"] for r in rs if r.get("missing_tiles") is not None]
        out.append(
            dict(
                tiles=key[0],
                coarse_factor=key[1],
                method=key[2],
                mode=MODES.get(key[2]),
                pixel_threshold=key[3],
                prepass_scale=key[4],
                views=len(rs),
                total_ms=_mean(r["total_ms"] for r in rs),
                ratio_to_none=_gmean(r.get("ratio_to_none") for r in rs),
                ratio_to_oracle=_gmean(r.get("ratio_to_oracle") for r in rs),
                differing_pixel_fraction=_mean(dpf),
                max_differing_pixel_fraction=max(dpf) if dpf else None,
                missing_tiles=sum(miss) if miss else None,
                tiles_at_risk=_total(r.get("tiles_at_risk") for r in rs),
                missed_not_at_risk=_total(r.get("missed_not_at_risk") for r in rs),
                triangles_drawn=_round(_mean(r["triangles_drawn"] for r in rs)),
                triangles_prepass=_round(_mean(r.get("triangles_prepass") for r in rs)),
                triangle_diff_vs_oracle=_mean(r.get("triangle_diff_vs_oracle") for r in rs),
                tiles_drawn=_round(_mean(r["tiles_drawn"] for r in rs)),
                build_s=rs[0].get("build_s"),
            )
        )
    return out


def _round(x: float | None) -> int | None:
    return None if x is None else int(round(x))


def _total(values: Iterable[Any]) -> int | None:
    """Sum of the values that are not None (None when all are)."""
    v = [x for x in values if x is not None]
    return int(sum(v)) if v else None


def point_label(r: dict[str, Any]) -> str:
    """A short label of a row's configuration, e.g. ``three_pass, approximate (paper) t10 s0.5 c25
    10x10`` (:func:`method_name`)."""
    parts = [method_name(str(r["method"]))]
    if r.get("pixel_threshold") is not None:
        parts.append(f"t{r['pixel_threshold']:g}")
    if r.get("prepass_scale") is not None:
        parts.append(f"s{r['prepass_scale']:g}")
    if r.get("coarse_factor") is not None:
        parts.append(f"c{r['coarse_factor']:g}")
    if r.get("tiles") is not None:
        parts.append(str(r["tiles"]))
    return " ".join(parts)


# --------------------------------------------------------------------------- plot


def plot(table: Sequence[dict[str, Any]], path: str, title: str | None = None, aggregate: bool = True) -> str:
    """Plot speed (ratio of frame time to ``none``; lower is faster) against error (differing pixel
    fraction vs the unculled image) to ``path`` (PNG, SVG, ... by extension): :func:`figure`, saved.
    Returns ``path``."""
    figure(table, title=title, aggregate=aggregate).savefig(path)
    return path


#: Offsets (points) tried for a point's number, nearest first: around the marker, then farther out.
_LABEL_OFFSETS = [(dx * k, dy * k) for k in (1, 2, 3, 4, 6)
                  for dx, dy in ((6, 4), (6, -12), (-14, 4), (-14, -12), (-4, 9), (-4, -17), (10, -4), (-20, -4))]
_COLORS = {"none": "black", "oracle": "tab:green", "three_pass": "tab:blue", "three_pass_cons": "tab:purple",
           "horizon": "tab:orange", "frustum": "tab:brown", "temporal": "tab:cyan"}
_MARKERS = {"none": "s", "oracle": "*", "three_pass": "o", "three_pass_cons": "D", "horizon": "^", "frustum": "v",
            "temporal": "P"}


def figure(table: Sequence[dict[str, Any]], title: str | None = None, aggregate: bool = True) -> Any:
    """The speed-against-error plot as a matplotlib ``Figure`` (made without pyplot; matplotlib is
    imported here). One marker per point, coloured and shaped by method (the legend names the
    three_pass modes: "approximate (paper)", "conservative"), numbered; each number sits at the
    first place around its marker where it covers no other number and no marker, and a key
    beside the plot (its width measured, so nothing is cut) gives each number's configuration
    (:func:`point_label`; columns of at most 40 lines). With ``aggregate`` (default) a point is a
    configuration over all views (see :func:`summarize`), else every row is a point (its key entry
    names its view). The numbers carry the gid "point_label", the key's texts "key"."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.layout_engine import ConstrainedLayoutEngine
    from matplotlib.lines import Line2D

    rows = summarize(table) if aggregate else list(table)
    rows = [r for r in rows if r.get("ratio_to_none") is not None and r.get("differing_pixel_fraction") is not None]
    keys = [point_label(r) if aggregate else f"{point_label(r)} [{r['view']}]" for r in rows]
    per_col = 40
    plot_w, height = 8.0, max(6.0, 0.9 + 0.16 * min(len(keys), per_col))
    layout = ConstrainedLayoutEngine()
    fig = Figure(figsize=(plot_w, height), dpi=110, layout=layout)
    canvas = FigureCanvasAgg(fig)
    # The key: columns of numbered configurations, measured to size the figure.
    texts = []
    for c in range(max(1, -(-len(keys) // per_col))):
        chunk = keys[c * per_col:(c + 1) * per_col]
        lines = [f"{c * per_col + i + 1:>3}  {k}" for i, k in enumerate(chunk)]
        if c == 0:
            lines = ["t: pixel threshold, s: prepass scale,", "c: coarse factor, then tiles", "", *lines]
        texts.append(fig.text(0, 0.98, "\n".join(lines), va="top", ha="left", fontsize=7, family="monospace",
                              gid="key", in_layout=False))
    renderer = canvas.get_renderer()
    widths = [t.get_window_extent(renderer).width / fig.dpi + 0.25 for t in texts]  # inches, with a gap
    total = plot_w + sum(widths) + 0.1
    fig.set_figwidth(total)
    x = plot_w
    for t, w in zip(texts, widths, strict=True):
        t.set_x((x + 0.1) / total)
        x += w
    layout.set(rect=(0.0, 0.0, plot_w / total, 1.0))  # the plot on the left only

    ax = fig.add_subplot()
    for r in rows:
        m = _family(str(r["method"]))
        ax.scatter(r["differing_pixel_fraction"], r["ratio_to_none"], c=_COLORS.get(m, "tab:gray"),
                   marker=_MARKERS.get(m, "X"), s=60 if m != "oracle" else 140, zorder=3,
                   edgecolors="white", linewidths=0.5)
    pos = [r["differing_pixel_fraction"] for r in rows if r["differing_pixel_fraction"] > 0]
    ax.set_xscale("symlog", linthresh=max(min(pos) / 2, 1e-6) if pos else 1e-5)
    ax.set_xlim(left=0)
    ax.axhline(1.0, color="gray", lw=0.8, ls="--")
    ax.set_xlabel("error: differing pixel fraction vs unculled image (symlog)")
    ax.set_ylabel("frame time / unculled frame time (lower = faster)")
    ax.set_title(title or "geocull: speed against error")
    ax.grid(True, alpha=0.3)
    ax.tick_params(axis="x", labelrotation=30)  # symlog ticks crowd near the linear threshold
    for lab in ax.get_xticklabels():
        lab.set_horizontalalignment("right")
    handles = [Line2D([], [], ls="", marker=_MARKERS[m], color=_COLORS[m], label=method_name(m))
               for m in _COLORS if any(_family(str(r["method"])) == m for r in rows)]
    if handles:
        ax.legend(handles=handles, loc="best", fontsize=8)
    _number_points(fig, ax, [(r["differing_pixel_fraction"], r["ratio_to_none"]) for r in rows])
    return fig


def _number_points(fig: Any, ax: Any, points: list[tuple[float, float]]) -> None:
    """Number each point (1, 2, ...) at the first offset of :data:`_LABEL_OFFSETS` where its number
    covers no number placed before and no marker (the last offset tried when none is free)."""
    from matplotlib.transforms import Bbox

    fig.draw_without_rendering()  # the layout, then the data transform, are final from here
    renderer = fig.canvas.get_renderer()
    r = 5.0 * fig.dpi / 72.0  # a marker's half size, pixels
    markers = [Bbox.from_extents(px - r, py - r, px + r, py + r) for px, py in ax.transData.transform(points)]
    placed: list[Any] = []
    for i, (x, y) in enumerate(points):
        ann = ax.annotate(str(i + 1), (x, y), textcoords="offset points", xytext=_LABEL_OFFSETS[0], fontsize=7,
                          zorder=4, gid="point_label", annotation_clip=False, in_layout=False)
        for off in _LABEL_OFFSETS:
            ann.set_position(off)
            box = ann.get_window_extent(renderer)
            if not any(box.overlaps(b) for b in placed) and not any(box.overlaps(m) for m in markers):
                break
        placed.append(ann.get_window_extent(renderer))
