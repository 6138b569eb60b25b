"""The real-field benchmark (``python -m geocull bench --scene field [--data DIR]``, issue 36): a field
as a user's files give it, built with the public API only, and every culling mode, level of detail,
the oracle and PyVista side by side on views geoscientists use (vertical exaggeration 1, 5 and 10).

The field (default ``../shared/data/reek`` beside the checkout: Equinor's public Reek field; any
directory laid out the same way, see :func:`find_files`):

- every ``surfaces/*.gri`` horizon (``xtgeo.surface_from_file`` -> :func:`geocull.io.from_xtgeo_surface`,
  depth positive down -> z = -depth, rotation and undefined nodes as they come), coloured by z with
  one colour range shared by all horizons (their joint min/max), tiles 10 x 10, coarse factor 25;
- the corner-point grid (``grid/*.EGRID``, else a ``grid/*.grdecl`` holding the geometry) coloured by
  porosity (a ``grid/*poro*`` property file, else PORO of an INIT file beside the EGRID) through
  :func:`geocull.grid.from_xtgeo`, blocks of 8 x 8 columns;
- every ``wells/*.w`` well (``xtgeo.well_from_file``: the path X_UTME, Y_UTMN, z = -Z_TVDSS) as
  ``scene.add_well`` (radius 10 m, 8 sides: the defaults), coloured by its ``Poro`` log where it has
  one (NaN where undefined), over the porosity range shared with the grid; wells without the log
  are drawn in their palette colour.

Views (:data:`VIEWS`): :meth:`geocull.Camera.fit` to the reservoir (horizons and grid; the wells'
shallow parts leave the image) from azimuths all round, elevations 10-90 degrees, ``z_scale`` 1, 5
and 10, two of them zoomed in. Methods (:func:`methods`): ``none`` (the reference), three_pass
conservative (threshold 0) and the paper's approximate mode (threshold 10, prepass scale 1),
``temporal`` (threshold 0, on its own renderer; its history is its last frame, the same view), ``horizon``,
``frustum``, ``oracle`` (the lower bound), ``implicit`` (threshold 0: three_pass with the isosurfaces'
enclosed occluders; a field without isosurfaces has none), any other mode of :data:`geocull.CULLING_MODES` with its
defaults, ``temporal`` + ``lod="screen_error"`` 0.5 px, the same with ``grid_lod="screen_error"``
too, ``temporal`` and ``temporal`` + lod with a moving camera (``,moving``: every frame alternates
between the view and the view turned by :data:`NUDGE_DEGREES` of azimuth, so that no frame repeats
the last one, as in an orbit; the plain rows repeat the view, which temporal draws at the oracle's
cost), and PyVista/VTK with MSAA off (:mod:`geocull.pyvista`, the same camera and clip range, flat colours).

Timing as in :mod:`geocull.bench`: one warm-up frame per method (the first temporal one two, so
that temporal's history is the view), whose image is compared with ``none``'s (differing pixels, beyond 4/255, largest
difference, missed tiles: tiles visible in the oracle's image that the mode did not draw), then
``repeats`` rounds calling every method once in rotated order (:func:`geocull.bench.report.timed_rounds`:
a shared machine's load falls on all alike); a method's time is the median of its rounds of
``stats["total_ms"]`` (call -> GPU done; PyVista: ``Render`` + ``WaitForCompletion``), ratios are of
medians of the same view, and the summary gives their geometric means over the views. The grid is
also rendered alone (its own renderer) at ``grid_lod="screen_error"`` against level 0 per view.
Nothing is asserted: the tests check what holds by construction.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ._field_table import format_table

__all__ = ["run", "format_table", "find_files", "build_field", "field_config", "default_data_dir", "methods",
           "views", "VIEWS", "EXACT"]

THRESHOLD = 10
TILES = (10, 10)
COARSE_FACTOR = 25
GRID_BLOCKS = (8, 8)
WELL_LOG = "Poro"
LOD_ERROR = 0.5
#: The moving-camera rows alternate between each view and the view turned by this (degrees).
NUDGE_DEGREES = 0.25

#: (name, azimuth, elevation, z_scale, zoom) of the views, in this order; ``--quick`` takes the first 4.
VIEWS: tuple[tuple[str, float, float, float, float], ...] = (
    ("az030_el30_z5", 30.0, 30.0, 5.0, 1.0),
    ("az120_el10_z10", 120.0, 10.0, 10.0, 1.0),
    ("az210_el60_z1", 210.0, 60.0, 1.0, 1.0),
    ("az300_el90_z5", 300.0, 90.0, 5.0, 1.0),
    ("az075_el20_z10_x2", 75.0, 20.0, 10.0, 2.0),
    ("az165_el45_z5_x2", 165.0, 45.0, 5.0, 2.0),
    ("az255_el15_z1", 255.0, 15.0, 1.0, 1.0),
    ("az345_el75_z10", 345.0, 75.0, 10.0, 1.0),
)

#: Methods whose image must equal ``none``'s bit for bit (the renderer's contract).
EXACT = ("none", "three_pass(cons,t=0)", "temporal(t=0)", "temporal(t=0,moving)", "horizon", "frustum", "oracle",
         "implicit(t=0)")


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def default_data_dir() -> Path:
    """``../shared/data/reek`` beside the checkout (the repository root is two levels above this
    package's directory), else relative to the working directory."""
    repo = Path(__file__).resolve().parents[2]
    for base in (repo.parent, Path.cwd().parent, Path.cwd()):
        d = base / "shared" / "data" / "reek"
        if d.is_dir():
            return d
    return repo.parent / "shared" / "data" / "reek"


def methods() -> list[tuple[str, dict[str, Any]]]:
    """(name, ``Renderer.render`` keyword arguments) of every geocull method, in table order: only
    culling modes the core has (:data:`geocull.CULLING_MODES`), and every mode it has."""
    import geocull as gc

    lod = dict(lod="screen_error", max_pixel_error=LOD_ERROR)
    glod = dict(grid_lod="screen_error", max_pixel_error=LOD_ERROR)
    out: list[tuple[str, dict[str, Any]]] = [
        ("none", dict(culling="none")),
        ("three_pass(cons,t=0)", dict(culling="three_pass", pixel_threshold=0)),
        (f"three_pass(approx,t={THRESHOLD})",
         dict(culling="three_pass", pixel_threshold=THRESHOLD, conservative=False, prepass_scale=1.0)),
        ("temporal(t=0)", dict(culling="temporal", pixel_threshold=0)),
        ("horizon", dict(culling="horizon")),
        ("frustum", dict(culling="frustum")),
        ("oracle", dict(culling="oracle")),
        ("implicit(t=0)", dict(culling="implicit", pixel_threshold=0)),
    ]
    known = {rk["culling"] for _, rk in out}
    out += [(m, dict(culling=m)) for m in gc.CULLING_MODES if m not in known]
    out += [
        (f"temporal(lod={LOD_ERROR:g})", dict(culling="temporal", pixel_threshold=0, **lod)),
        (f"temporal(lod+grid_lod={LOD_ERROR:g})", dict(culling="temporal", pixel_threshold=0, **(lod | glod))),
        ("temporal(t=0,moving)", dict(culling="temporal", pixel_threshold=0)),
        (f"temporal(lod={LOD_ERROR:g},moving)", dict(culling="temporal", pixel_threshold=0, **lod)),
    ]
    return [(n, rk) for n, rk in out if rk["culling"] in gc.CULLING_MODES]


# ------------------------------------------------------------------------------------------ the field


def find_files(data: str | os.PathLike[str]) -> dict[str, Any]:
    """The field's files under ``data``: ``surfaces`` (``surfaces/*.gri``), ``grid`` (``grid/*.EGRID``,
    else the ``grid/*.grdecl`` files: the first that xtgeo reads as a grid is used), ``poro`` (a
    ``grid/*poro*`` property file, .grdecl / .roff, or None: then PORO of an ``.INIT`` file with the
    EGRID's stem), ``wells`` (``wells/*.w``). Raises FileNotFoundError naming what is missing."""
    d = Path(data)
    if not d.is_dir():
        raise FileNotFoundError(f"--data: {d} is not a directory (expected surfaces/, grid/, wells/)")

    def ls(sub: str, *patterns: str) -> list[Path]:
        found: set[Path] = set()
        for p in patterns:
            found.update(x for x in (d / sub).glob(p) if x.is_file())
        return sorted(found)

    surfaces = ls("surfaces", "*.gri")
    egrid = ls("grid", "*.EGRID", "*.egrid")
    poro = [p for p in ls("grid", "*.grdecl", "*.GRDECL", "*.roff") if "poro" in p.name.lower()]
    grdecl = [p for p in ls("grid", "*.grdecl", "*.GRDECL") if p not in poro]
    wells = ls("wells", "*.w")
    missing = [what for what, got in (("surfaces/*.gri", surfaces), ("grid/*.EGRID or *.grdecl", egrid + grdecl),
                                      ("wells/*.w", wells)) if not got]
    if missing:
        raise FileNotFoundError(f"--data: {d} has no {', '.join(missing)}")
    return dict(surfaces=surfaces, grid=egrid[:1] or grdecl, poro=poro[0] if poro else None, wells=wells)


def _read_grid(files: dict[str, Any]) -> tuple[Any, Any, str]:
    """(xtgeo Grid, porosity GridProperty, the grid file's name)."""
    import xtgeo

    grid, used, errors = None, None, []
    for path in files["grid"]:
        try:
            fmt = "egrid" if path.suffix.lower() == ".egrid" else "grdecl"
            grid, used = xtgeo.grid_from_file(str(path), fformat=fmt), path
            break
        except Exception as e:  # a property file or another grdecl: try the next
            errors.append(f"{path.name}: {e}")
    if grid is None:
        raise FileNotFoundError(f"grid: no file xtgeo reads as a grid ({'; '.join(errors)})")
    assert used is not None
    poro_path = files["poro"]
    if poro_path is not None:
        fmt = "roff" if poro_path.suffix.lower() == ".roff" else "grdecl"
        kw = dict(name="PORO") if fmt == "grdecl" else {}
        prop = xtgeo.gridproperty_from_file(str(poro_path), fformat=fmt, grid=grid, **kw)
    else:
        init = [p for p in used.parent.glob(used.stem + ".*") if p.suffix.lower() == ".init"]
        if not init:
            raise FileNotFoundError(f"grid: no *poro* property file and no INIT file beside {used.name}")
        prop = xtgeo.gridproperty_from_file(str(init[0]), fformat="init", name="PORO", grid=grid)
    return grid, prop, used.name


def _well_arrays(path: Path) -> tuple[np.ndarray, np.ndarray | None, str]:
    """(stations (n, 3) with z = -Z_TVDSS, the Poro log (n,) with NaN where undefined or None, name)."""
    import warnings

    import xtgeo

    from ..io import XTGEO_UNDEF_LIMIT

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pandas' deprecation warnings inside xtgeo
        well = xtgeo.well_from_file(str(path))
        df = well.get_dataframe()
    xyz = np.column_stack([np.asarray(df[c], dtype=np.float64) for c in ("X_UTME", "Y_UTMN", "Z_TVDSS")])
    keep = np.isfinite(xyz).all(axis=1) & (np.abs(xyz) < XTGEO_UNDEF_LIMIT).all(axis=1)
    xyz = xyz[keep]
    xyz[:, 2] *= -1.0
    log = None
    if WELL_LOG in df.columns:
        log = np.asarray(df[WELL_LOG], dtype=np.float64)[keep]
        log[~np.isfinite(log) | (np.abs(log) >= XTGEO_UNDEF_LIMIT)] = np.nan
        if not np.isfinite(log).any():
            log = None
    name = str(getattr(well, "name", None) or path.stem)
    return xyz, log, name


def build_field(data: str | os.PathLike[str]) -> dict[str, Any]:
    """The field of ``data`` (:func:`find_files`) as a :class:`geocull.Scene` and what the benchmark
    needs of it: ``scene``, ``grid_scene`` (the grid alone), ``reservoir_bounds`` (horizons and grid),
    ``kinds`` (per object kind: objects, fine and coarse triangles, tiles), ``wells`` (name, stations,
    triangles, log), ``tile_kind`` (each tile's object kind, in tile order), ``files``, ``clim_z``,
    ``clim_poro``, ``read_s`` and ``build_s``."""
    import warnings

    import xtgeo

    import geocull as gc

    files = find_files(data)
    t0 = time.perf_counter()
    surfs = [xtgeo.surface_from_file(str(p)) for p in files["surfaces"]]
    hf: list[dict[str, Any]] = []
    for surf, p in zip(surfs, files["surfaces"], strict=True):
        kw: dict[str, Any] = dict(gc.io.from_xtgeo_surface(surf))
        kw.pop("name", None)  # older versions named the surface in the dictionary
        hf.append(dict(kw, name=p.stem))
    hf.sort(key=lambda kw: -float(np.ma.mean(kw["z"])))  # top first
    zs = [kw["z"] for kw in hf if np.ma.count(kw["z"])]
    clim_z = (float(min(np.ma.min(z) for z in zs)), float(max(np.ma.max(z) for z in zs)))
    grid, prop, grid_file = _read_grid(files)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = gc.grid.from_xtgeo(grid, prop)
    wells = [_well_arrays(p) for p in files["wells"]]
    poro = [g["values"][np.isfinite(g["values"])]] if g["values"] is not None else []
    poro += [log[np.isfinite(log)] for _, log, _ in wells if log is not None]
    vals = np.concatenate(poro) if poro else np.zeros(0)
    clim_poro = (float(vals.min()), float(vals.max())) if vals.size else None
    read_s = time.perf_counter() - t0

    t0 = time.perf_counter()
    scene = gc.Scene()
    for kw in hf:
        scene.add_heightfield(**kw, tiles=TILES, coarse_factor=COARSE_FACTOR, color_by="z", clim=clim_z,
                              progress=False)

    def add_grid(sc: Any) -> int:
        return sc.add_grid(g["corners"], active=g["active"], values=g["values"], clim=clim_poro, blocks=GRID_BLOCKS,
                           name=Path(grid_file).stem, progress=False)

    gid = add_grid(scene)
    reservoir_bounds = scene.bounds
    well_info = []
    for xyz, log, name in wells:
        wid = scene.add_well(xyz, name=name, values=log, clim=clim_poro if log is not None else None)
        info = scene.object_info(wid)
        well_info.append(dict(name=name, stations=len(xyz), triangles=int(info["n_triangles"]),
                              tiles=int(info["n_tiles"]), log=log is not None,
                              log_stations=int(np.isfinite(log).sum()) if log is not None else 0))
    build_s = time.perf_counter() - t0
    grid_scene = gc.Scene()
    add_grid(grid_scene)

    table = scene.tile_table()
    kinds: dict[str, dict[str, int]] = {}
    tile_kind = np.empty(len(table), dtype=object)
    for oid in scene.object_ids():
        info = scene.object_info(oid)
        k = kinds.setdefault(str(info["kind"]), dict(objects=0, triangles=0, coarse_triangles=0, tiles=0))
        rows = table[table["object"] == oid]
        tile_kind[table["object"] == oid] = str(info["kind"])
        k["objects"] += 1
        k["triangles"] += int(info["n_triangles"])
        k["coarse_triangles"] += int(rows["tris_coarse"].sum())
        k["tiles"] += len(rows)
    return dict(scene=scene, grid_scene=grid_scene, grid_id=gid, reservoir_bounds=reservoir_bounds, kinds=kinds,
                tile_kind=tile_kind,
                wells=well_info, clim_z=clim_z, clim_poro=clim_poro, read_s=read_s, build_s=build_s,
                files=dict(surfaces=[p.name for p in files["surfaces"]], grid=grid_file,
                           poro=files["poro"].name if files["poro"] is not None else "INIT:PORO",
                           wells=[p.name for p in files["wells"]]),
                grid_dims=tuple(int(v) for v in grid.dimensions), grid_active=int(np.count_nonzero(g["active"])))


def views(bounds: Any, width: int, height: int, names: Any = None) -> list[tuple[str, Any, dict[str, float]]]:
    """(name, camera, its angles) of :data:`VIEWS` (all, the first ``names`` if an int, or those
    named in a comma-separated string), each :meth:`geocull.Camera.fit` to ``bounds``."""
    import geocull as gc

    chosen = list(VIEWS)
    if names is not None:
        s = str(names).strip()
        if s.isdigit():
            if int(s) < 1:
                raise SystemExit("--views: need at least 1")
            chosen = list(VIEWS[: int(s)])
        else:
            byname = {v[0]: v for v in VIEWS}
            want = [n.strip() for n in s.split(",") if n.strip()]
            bad = [n for n in want if n not in byname]
            if bad:
                raise SystemExit(f"--views: unknown view(s) {bad}; known: {', '.join(byname)}")
            chosen = [byname[n] for n in want]
    out = []
    for name, az, el, zs, zoom in chosen:
        cam = gc.Camera.fit(bounds, azimuth=az, elevation=el, aspect=width / height, z_scale=zs)
        if zoom != 1.0:
            cam = cam.zoomed(zoom)
        out.append((name, cam, dict(azimuth=az, elevation=el, z_scale=zs, zoom=zoom)))
    return out


class _Frozen:
    """A scene's objects read once (what :mod:`geocull.pyvista` reads of a scene), so that PyVista's
    per-view setup does not copy the geometry out of the scene again."""

    def __init__(self, scene: Any) -> None:
        self._ids = list(scene.object_ids())
        self._info = {i: dict(scene.object_info(i)) for i in self._ids}
        self._geo = {i: scene.geometry(i) for i in self._ids}

    def object_ids(self) -> list[int]:
        return list(self._ids)

    def object_info(self, id: int, /) -> dict[str, Any]:
        return self._info[id]

    def geometry(self, id: int, /) -> tuple[np.ndarray, np.ndarray]:
        return self._geo[id]


# -------------------------------------------------------------------------------------------- the run


def field_config(mode: str, a: argparse.Namespace) -> dict[str, Any]:
    """The field benchmark's part of :func:`geocull.bench.cli.config`: image size, views, repeats and the
    data directory for ``mode`` (full, quick, tiny), overridden by the command line's options."""
    size = {"full": (1280, 1024), "quick": (320, 256), "tiny": (64, 48)}[mode]
    return dict(width=a.width or size[0], height=a.height or size[1],
                views=a.views if a.views is not None else (None if mode == "full" else "4"),
                repeats=a.repeats or {"full": 5, "quick": 2, "tiny": 1}[mode],
                data=str(a.data) if getattr(a, "data", None) else str(default_data_dir()))


def _diff_summary(res: Any, ref: Any, visible: np.ndarray) -> dict[str, Any]:
    """Image error of ``res`` against ``none``'s frame ``ref`` (and the oracle's visible tiles)."""
    from ..compare import image_error

    e0 = image_error(res.image, ref.image, tile_drawn=res.tile_drawn, reference_tile_pixels=visible)
    e4 = image_error(res.image, ref.image, threshold=4)
    diff = np.any(res.image != ref.image, axis=2)
    n = int(np.count_nonzero(diff))
    out: dict[str, Any] = dict(
        differing_pixels=n, differing_pixel_fraction=e0["differing_pixel_fraction"],
        differing_pixel_fraction_tol4=e4["differing_pixel_fraction"], max_abs_diff=e0["max_abs_diff"],
        missing_tiles=e0["missing_tiles"], same_image=bool(np.array_equal(res.image, ref.image)),
    )
    if n:
        # Where they differ: a few pixels (row, column) and whether the two frames' depths tie there
        # (coincident surfaces: drawing order decides) or one frame lacks a surface the other has.
        ys, xs = np.nonzero(diff)
        d_res, d_ref = res.depth[diff], ref.depth[diff]
        out.update(
            diff_pixels_sample=[[int(y), int(x)] for y, x in zip(ys[:8], xs[:8], strict=True)],
            diff_depth_equal=int(np.count_nonzero(d_res == d_ref)),
            diff_depth_nearer=int(np.count_nonzero(d_res < d_ref)),
            diff_depth_farther=int(np.count_nonzero(d_res > d_ref)),
        )
    return out


STAT_KEYS = ("triangles_drawn", "triangles_prepass", "tiles_drawn", "tiles_total", "tiles_proven_hidden",
             "tiles_box_tested", "tiles_slab_tested", "triangles_slab_test", "triangles_slab_gates", "tiles_reused",
             "tiles_drawn_first", "tiles_drawn_second", "lod_max_error_px",
             "grid_interior_triangles_skipped", *(f"triangles_level{i}" for i in range(6)),
             *(f"grid_faces_level{i}" for i in range(6)))


def run(cfg: dict[str, Any]) -> dict[str, Any]:
    """Runs the field benchmark; ``cfg`` keys: data (directory), width, height, views (None = all,
    a count or names), repeats, pyvista (bool), mode (a label). Returns ``dict(summary=..., rows=...,
    grid_rows=...)``."""
    import geocull as gc

    t_start = time.perf_counter()
    w, h, rep = int(cfg["width"]), int(cfg["height"]), max(1, int(cfg.get("repeats", 3)))
    data = cfg.get("data") or str(default_data_dir())
    _say(f"bench[field/{cfg.get('mode', 'full')}]: reading and building the field from {data}")
    fld = build_field(data)
    scene = fld["scene"]
    _say(f"bench: field read in {fld['read_s']:.1f} s, built in {fld['build_s']:.1f} s: "
         f"{scene.n_triangles:,} triangles in {scene.n_tiles} tiles")
    vs = views(fld["reservoir_bounds"], w, h, cfg.get("views"))
    renderer, r_grid = gc.Renderer(w, h), gc.Renderer(w, h)
    meths = methods()
    ctx = _Run(fld=fld, renderer=renderer, r_grid=r_grid, meths=meths, by_name=dict(meths), w=w, h=h, rep=rep,
               t_start=t_start)
    if cfg.get("pyvista", True):
        _import_pyvista(ctx)
    for vi, (vname, cam, angles) in enumerate(vs):
        _say(f"bench: view {vi + 1}/{len(vs)} {vname}: warm-up and image errors")
        _run_view(ctx, vname, cam, angles)
    return dict(summary=_summary(cfg, ctx, data, vs), rows=ctx.rows, grid_rows=ctx.grid_rows)


@dataclasses.dataclass
class _Run:
    """A run's field, renderers, methods and settings, PyVista where imported, and the rows gathered."""

    fld: dict[str, Any]
    renderer: Any
    r_grid: Any  # the grid alone, in its own renderer
    meths: list[tuple[str, dict[str, Any]]]
    by_name: dict[str, dict[str, Any]]
    w: int
    h: int
    rep: int
    t_start: float
    gpv: Any = None
    frozen: Any = None
    # Each temporal row's own renderer (its history: one per renderer), made on first use.
    own: dict[str, Any] = dataclasses.field(default_factory=dict)

    def renderer_for(self, name: str, rk: dict[str, Any]) -> Any:
        """The renderer that draws method ``name``: its own for a temporal row (whose history
        is then its own last frame, as a viewer's), else the shared one."""
        if rk.get("culling") != "temporal":
            return self.renderer
        if name not in self.own:
            import geocull as gc

            self.own[name] = gc.Renderer(self.w, self.h)
        return self.own[name]
    pv_version: dict[str, str] = dataclasses.field(default_factory=dict)
    rows: list[dict[str, Any]] = dataclasses.field(default_factory=list)
    pv_setup_s: list[float] = dataclasses.field(default_factory=list)
    grid_rows: list[dict[str, Any]] = dataclasses.field(default_factory=list)


def _import_pyvista(ctx: _Run) -> None:
    """geocull.pyvista, the scene read once for it and the versions into ``ctx``; a message and no
    PyVista rows where it cannot be imported."""
    try:
        import pyvista
        import vtk

        from .. import pyvista as gpv_mod

        ctx.gpv = gpv_mod
        ctx.frozen = _Frozen(ctx.fld["scene"])
        ctx.pv_version = dict(pyvista=pyvista.__version__, vtk=vtk.vtkVersion.GetVTKVersion())
    except Exception as e:  # pragma: no cover - environment dependent
        _say(f"bench: PyVista unavailable ({e}); skipping its rows")


def _run_view(ctx: _Run, vname: str, cam: Any, angles: dict[str, float]) -> None:
    """One view: warm-up frames and image errors, timed rounds, its rows; then the grid alone."""
    import geocull as gc

    turned = gc.Camera.fit(ctx.fld["reservoir_bounds"], azimuth=angles["azimuth"] + NUDGE_DEGREES,
                           elevation=angles["elevation"], aspect=ctx.w / ctx.h, z_scale=angles["z_scale"])
    if angles["zoom"] != 1.0:
        turned = turned.zoomed(angles["zoom"])
    ref, oracle_tiles, first = _warm_up(ctx, cam, turned)
    jobs, times, pv_err = _timed_view(ctx, cam, turned, vname, ref)
    ctx.rows.extend(_view_rows(ctx, vname, angles, jobs, times, first, pv_err, oracle_tiles))
    del ref
    ctx.grid_rows.extend(_grid_alone(ctx, cam, vname))
    _say(f"bench: view {vname}: done ({time.perf_counter() - ctx.t_start:.0f} s so far)")


def _warm_up(ctx: _Run, cam: Any, turned: Any) -> tuple[Any, int, dict[str, dict[str, Any]]]:
    """One warm-up frame per method (a temporal one two, on its own renderer: its history is then
    this view; a moving one's after a frame of the view ``turned``), each reduced at once to its
    stats, tiles drawn per object kind and image errors against none's. Returns (none's frame,
    tiles visible in the oracle's image, per method those numbers)."""
    renderer, scene, kinds, field = ctx.renderer, ctx.fld["scene"], ctx.fld["tile_kind"], ctx.fld
    ref = renderer.render(scene, cam, culling="none")
    oracle = renderer.render(scene, cam, culling="oracle")
    visible = np.asarray(oracle.tile_pixels)
    oracle_tiles = int(np.count_nonzero(visible))
    first: dict[str, dict[str, Any]] = {}
    for name, rk in ctx.meths:
        r = ctx.renderer_for(name, rk)
        if name == "none" or rk == dict(culling="oracle"):
            res = ref if name == "none" else oracle
        elif name.endswith(",moving)"):
            r.render(scene, turned, **rk)
            res = r.render(scene, cam, **rk)
        else:
            res = r.render(scene, cam, **rk)
            if rk["culling"] == "temporal":  # its history is now this view: the view repeated
                res = r.render(scene, cam, **rk)
        s: dict[str, Any] = dict(res.stats)
        # tiles drawn per object kind, against the oracle's (visible in the unculled image)
        by_kind = {k: [int(np.count_nonzero(res.tile_drawn & (kinds == k))),
                       int(np.count_nonzero((visible > 0) & (kinds == k)))] for k in field["kinds"]}
        first[name] = dict(stats={k: s[k] for k in STAT_KEYS if k in s}, tiles_by_kind=by_kind,
                           **_diff_summary(res, ref, visible))
        del res
    del oracle
    return ref, oracle_tiles, first


def _timed_view(ctx: _Run, cam: Any, turned: Any, vname: str,
                ref: Any) -> tuple[list[tuple[str, Any]], dict[str, list[float]], dict[str, Any]]:
    """The timed rounds of one view: every method (a moving one alternating between ``cam`` and
    ``turned``), and PyVista (set up and warmed up first) where imported. Returns (jobs, their times,
    PyVista's depth errors against none's)."""
    from . import report

    scene, w, h, rep = ctx.fld["scene"], ctx.w, ctx.h, ctx.rep
    near, far = ref.near, ref.far

    def job(name: str, rk: dict[str, Any]) -> Any:
        r = ctx.renderer_for(name, rk)
        if not name.endswith(",moving)"):
            return lambda: r.render(scene, cam, **rk).stats["total_ms"]
        cams = [turned, cam]

        def frame() -> float:
            cams.reverse()
            return float(r.render(scene, cams[0], **rk).stats["total_ms"])
        return frame

    jobs: list[tuple[str, Any]] = [(name, job(name, rk)) for name, rk in ctx.meths]
    setup = None
    pv_err: dict[str, Any] = {}
    if ctx.gpv is not None:
        t0 = time.perf_counter()
        setup = ctx.gpv._Setup(ctx.frozen, cam, w, h, False, True, near, far, (0.0, 0.0, 0.0), 1e-4)
        setup.render()  # warm-up: context, shaders, geometry upload
        ctx.pv_setup_s.append(time.perf_counter() - t0)
        jobs.append(("pyvista", setup.render))
    try:
        _say(f"bench: view {vname}: {rep} timed round(s) of {len(jobs)} methods")
        times = report.timed_rounds(jobs, rep)
        if setup is not None:
            from ..compare import coverage_agreement, depth_error

            pv_img, pv_depth = setup.read()
            del pv_img
            pv_err = dict(coverage_agreement=coverage_agreement(pv_depth, ref.depth),
                          depth_median_rel=depth_error(pv_depth, ref.depth)["median_rel"])
    finally:
        if setup is not None:
            setup.close()
    return jobs, times, pv_err


def _view_rows(ctx: _Run, vname: str, angles: dict[str, float], jobs: list[tuple[str, Any]],
               times: dict[str, list[float]], first: dict[str, dict[str, Any]], pv_err: dict[str, Any],
               oracle_tiles: int) -> list[dict[str, Any]]:
    """The rows of one view, one per timed job, in the jobs' order."""
    med = {k: statistics.median(v) for k, v in times.items()}
    t_none, t_oracle, t_pv = med["none"], med["oracle"], med.get("pyvista")
    rows = []
    for name, _ in jobs:
        row: dict[str, Any] = dict(view=vname, **angles, method=name, median_ms=med[name],
                                   best_ms=min(times[name]), times_ms=times[name], x_none=med[name] / t_none,
                                   x_oracle=med[name] / t_oracle,
                                   x_pyvista=med[name] / t_pv if t_pv else None, oracle_tiles=oracle_tiles)
        if name in first:
            f = first[name]
            row.update(renderer="geocull", kwargs=ctx.by_name[name], exact=name in EXACT, **f["stats"],
                       **{k: v for k, v in f.items() if k != "stats"})
        else:
            row.update(renderer="pyvista", kwargs=dict(msaa=False), exact=False,
                       triangles_drawn=int(ctx.fld["scene"].n_triangles), **pv_err)
        rows.append(row)
    return rows


def _grid_alone(ctx: _Run, cam: Any, vname: str) -> list[dict[str, Any]]:
    """The grid alone in one view: its screen-error levels against level 0 (image errors, timed rounds)."""
    from . import report

    r_grid, field, rep = ctx.r_grid, ctx.fld, ctx.rep
    gmodes: dict[str, dict[str, Any]] = {"full": dict(grid_lod="full"),
              f"screen_error({LOD_ERROR:g})": dict(grid_lod="screen_error", max_pixel_error=LOD_ERROR)}
    gref = r_grid.render(field["grid_scene"], cam, **gmodes["full"])
    gfirst: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {}
    for gname, gk in gmodes.items():
        res = r_grid.render(field["grid_scene"], cam, **gk)
        gfirst[gname] = (dict(res.stats), _diff_summary(res, gref, np.asarray(gref.tile_pixels)))

    def gjob(gk: dict[str, Any], cam: Any = cam) -> Any:
        return lambda: r_grid.render(field["grid_scene"], cam, **gk).stats["total_ms"]

    gt = report.timed_rounds([(n, gjob(gk)) for n, gk in gmodes.items()], rep)
    gmed = {k: statistics.median(v) for k, v in gt.items()}
    grid_rows = []
    for gname, (st, err) in gfirst.items():
        grid_rows.append(dict(view=vname, mode=gname, median_ms=gmed[gname], x_full=gmed[gname] / gmed["full"],
                              triangles_drawn=int(st["triangles_drawn"]),
                              faces=sum(int(v) for k, v in st.items() if k.startswith("grid_faces_level")),
                              **{k: int(v) for k, v in st.items() if k.startswith("grid_faces_level")},
                              **err))
    return grid_rows


def _per_method(rows: list[dict[str, Any]], kinds: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Per method over the views: geometric means of the ratios, max image errors, summed tiles."""
    per_method: dict[str, dict[str, Any]] = {}
    for name in dict.fromkeys(r["method"] for r in rows):
        rs = [r for r in rows if r["method"] == name]
        geo = rs[0]["renderer"] == "geocull"
        per_method[name] = dict(
            exact=rs[0]["exact"],
            x_none=_gmean(r["x_none"] for r in rs),
            x_oracle=_gmean(r["x_oracle"] for r in rs),
            x_pyvista=_gmean(r["x_pyvista"] for r in rs),
            median_ms_gmean=_gmean(r["median_ms"] for r in rs),
            mean_triangles_drawn=sum(r["triangles_drawn"] for r in rs) / len(rs),
            mean_tiles_drawn=sum(r["tiles_drawn"] for r in rs) / len(rs) if geo else None,
            max_differing_pixel_fraction=max(r["differing_pixel_fraction"] for r in rs) if geo else None,
            max_differing_pixel_fraction_tol4=max(r["differing_pixel_fraction_tol4"] for r in rs) if geo else None,
            max_abs_diff=max(r["max_abs_diff"] for r in rs) if geo else None,
            missing_tiles=sum(r["missing_tiles"] for r in rs) if geo else None,
            views_same_image=sum(bool(r["same_image"]) for r in rs) if geo else None,
            tiles_proven_hidden=(sum(r["tiles_proven_hidden"] for r in rs)
                                 if geo and all("tiles_proven_hidden" in r for r in rs) else None),
            mean_tiles_by_kind=({k: [sum(r["tiles_by_kind"][k][i] for r in rs) / len(rs) for i in (0, 1)]
                                 for k in kinds} if geo else None),
        )
    return per_method


def _grid_summary(grid_rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per grid mode over the views: the geometric mean of x full, mean triangles, max image errors."""
    grid_summary: dict[str, dict[str, Any]] = {}
    for gname in dict.fromkeys(r["mode"] for r in grid_rows):
        rs = [r for r in grid_rows if r["mode"] == gname]
        grid_summary[gname] = dict(x_full=_gmean(r["x_full"] for r in rs),
                                   mean_triangles_drawn=sum(r["triangles_drawn"] for r in rs) / len(rs),
                                   max_differing_pixel_fraction=max(r["differing_pixel_fraction"] for r in rs),
                                   max_differing_pixel_fraction_tol4=max(r["differing_pixel_fraction_tol4"]
                                                                         for r in rs))
    return grid_summary


def _summary(cfg: dict[str, Any], ctx: _Run, data: str, vs: list[tuple[str, Any, dict[str, float]]]) -> dict[str, Any]:
    """The run's summary: the field, the settings, the environment, per-method and grid-alone means."""
    import geocull as gc

    field, scene = ctx.fld, ctx.fld["scene"]
    per_method = _per_method(ctx.rows, field["kinds"])
    grid_summary = _grid_summary(ctx.grid_rows)
    return dict(
        scene="field", mode=cfg.get("mode", "full"), data=str(data), files=field["files"], width=ctx.w,
        height=ctx.h, repeats=ctx.rep, views=[dict(name=n, **a) for n, _, a in vs], n_triangles=int(scene.n_triangles),
        n_tiles=int(scene.n_tiles), kinds=field["kinds"], wells=field["wells"], grid_dims=field["grid_dims"],
        grid_active=field["grid_active"], clim_z=field["clim_z"], clim_poro=field["clim_poro"],
        tiles=f"{TILES[0]}x{TILES[1]}", coarse_factor=COARSE_FACTOR, grid_blocks=f"{GRID_BLOCKS[0]}x{GRID_BLOCKS[1]}",
        read_s=field["read_s"], build_s=field["build_s"], culling_modes=list(gc.CULLING_MODES),
        adapter=ctx.renderer.adapter_info, cpu_count=os.cpu_count(), geocull=gc.__version__, **ctx.pv_version,
        pyvista_setup_s=ctx.pv_setup_s, per_method=per_method, grid_alone=grid_summary,
        wall_s=time.perf_counter() - ctx.t_start,
    )


def _gmean(xs: Any) -> float | None:
    v = [float(x) for x in xs if x is not None and x > 0]
    return math.exp(sum(math.log(x) for x in v) / len(v)) if v else None
