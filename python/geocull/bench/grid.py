"""The reservoir-grid benchmark (``python -m geocull bench --scene grid``, issue 11): a
:func:`geocull.data.faulted_grid` built into a scene (build time, peak memory), its cell-merging
levels (faces and vertices as a share of level 0 and the volume change per level, Jia et al.'s
Figures 6 and 9), and per view the frame time of each ``grid_lod`` mode against level 0 and
against PyVista/VTK rendering the same grid's surface (``UnstructuredGrid.extract_surface`` of the
cells as hexahedra), with each mode's image error against level 0. Every ratio comes from one run,
side by side (the grid_lod modes of a view and colour interleaved round by round, so that a shared
machine's load falls on all of them alike: each row gives the best frame and the median over the
rounds of its ratio to the same round's level-0 frame); nothing is asserted.
"""

from __future__ import annotations

import resource
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .._convert import surface_of
from .report import best_frame

__all__ = ["run", "format_table", "level_table"]


def _peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _views(bounds: tuple[tuple[float, ...], tuple[float, ...]]) -> dict[str, Any]:
    import geocull as gc

    lo, hi = np.array(bounds[0]), np.array(bounds[1])
    c = (lo + hi) / 2
    ext = float(np.linalg.norm(hi - lo))
    return {
        # Oblique from a corner at about one grid diagonal: near blocks fine, far ones merged.
        "near": gc.Camera.look_at(tuple(c + ext * np.array([0.45, -0.75, 0.45])), tuple(c), fov_y=45),
        # A distant overview (the target's distance-LOD case).
        "distant": gc.Camera.look_at(tuple(c + ext * np.array([1.2, -2.0, 1.2])), tuple(c), fov_y=30),
    }


def level_table(levels: Sequence[Mapping[str, Any]]) -> list[dict[str, float]]:
    """Per level: faces and vertices as % of level 0, volume change in % (the paper's figures)."""
    f0, v0 = levels[0]["faces"] or 1, levels[0]["vertices"] or 1
    return [
        dict(level=h, faces=lv["faces"], faces_pct=100.0 * lv["faces"] / f0, vertices=lv["vertices"],
             vertices_pct=100.0 * lv["vertices"] / v0, volume_change_pct=100.0 * lv["volume_change"])
        for h, lv in enumerate(levels)
    ]


def _interleaved(renders: Mapping[str, Any], repeats: int) -> dict[str, tuple[Any, float, list[float]]]:
    """One warm-up call of each render, then ``repeats`` rounds calling each once in turn: per key
    (the last result, the best ``total_ms``, every round's ``total_ms``)."""
    for f in renders.values():
        f()
    out: dict[str, tuple[Any, float, list[float]]] = {}
    times: dict[str, list[float]] = {k: [] for k in renders}
    for _ in range(max(1, int(repeats))):
        for k, f in renders.items():
            res = f()
            times[k].append(float(res.stats["total_ms"]))
            out[k] = (res, min(times[k]), times[k])
    return out


def _pyvista_surface(g: dict[str, np.ndarray]) -> tuple[Any, float]:
    """The grid's active cells as VTK hexahedra and PyVista's surface of them (timed)."""
    import pyvista as pv

    act = g["active"].reshape(-1)
    corners = g["corners"].reshape(-1, 8, 3)[act]
    order = [4, 5, 7, 6, 0, 1, 3, 2]  # VTK: the bottom face, then the top, counter-clockwise
    # Cells share their coincident corners (as a user's grid does), so faces between neighbours
    # are interior for VTK too.
    pts, inv = np.unique(corners[:, order, :].reshape(-1, 3), axis=0, return_inverse=True)
    n = len(corners)
    cells = np.hstack([np.full((n, 1), 8, np.int64), inv.reshape(n, 8).astype(np.int64)]).ravel()
    ug = pv.UnstructuredGrid(cells, np.full(n, pv.CellType.HEXAHEDRON, np.uint8), pts)
    t = time.perf_counter()
    surf = surface_of(ug).triangulate()
    return surf, (time.perf_counter() - t) * 1e3


def run(cfg: dict[str, Any]) -> dict[str, Any]:
    """Runs the grid benchmark; ``cfg`` keys: grid_n (cells along i and j), grid_nk (layers),
    width, height, repeats, pyvista (bool), blocks ((bi, bj))."""
    import geocull as gc
    from geocull import compare, data

    n, nk = int(cfg.get("grid_n", 100)), int(cfg.get("grid_nk", 100))
    w, h, rep = int(cfg["width"]), int(cfg["height"]), int(cfg.get("repeats", 3))
    g = data.faulted_grid(ni=n, nj=n, nk=nk)
    rss0 = _peak_rss_mib()
    scene = gc.Scene()
    t = time.perf_counter()
    gid = scene.add_grid(g["corners"], active=g["active"], region=g["region"], values=g["values"],
                         blocks=cfg.get("blocks", (8, 8)))
    build_s = time.perf_counter() - t
    rss1 = _peak_rss_mib()
    levels = scene.grid_levels(gid)
    out: dict[str, Any] = dict(
        cells=n * n * nk, active=int(g["active"].sum()), build_s=build_s, peak_rss_mib=rss1,
        build_peak_rss_growth_mib=rss1 - rss0, host_bytes=scene.host_bytes, levels=level_table(levels),
        width=w, height=h, rows=[],
    )
    r = gc.Renderer(w, h)
    surf, pv_extract_ms = (None, None)
    if cfg.get("pyvista", True):
        try:
            surf, pv_extract_ms = _pyvista_surface(g)
        except ImportError:
            surf = None
    out["pyvista_extract_ms"] = pv_extract_ms
    bounds = scene.bounds
    assert bounds is not None
    for view, cam in _views(bounds).items():
        full, _ = best_frame(lambda cam=cam: r.render(scene, cam, grid_lod="full"), 1)
        pv_ms = None
        if surf is not None:
            ref = gc.Scene()
            ref.add_mesh(surf, color=(1, 1, 1))
            pv_ms = gc.pyvista.timed_render(ref, cam, w, h, n=rep, near=full.near, far=full.far)
        # Coloured by the cell property (merged faces take their cells' mean value), then in one flat
        # colour (the geometric error of merging alone).
        for colour in ("values", "flat"):
            if colour == "flat":
                scene.set_color(gid, (0.8, 0.8, 0.8))
            frames = _interleaved({mode: (lambda cam=cam, mode=mode: r.render(scene, cam, grid_lod=mode))
                                   for mode in ("full", "distance", "screen_error")}, rep)
            full, t_full, rounds_full = frames["full"]
            for mode, (res, ms, rounds) in frames.items():
                err = compare.image_error(res.image, full.image)
                faces = sum(v for k, v in res.stats.items() if k.startswith("grid_faces_level"))
                out["rows"].append(dict(
                    view=view, mode=mode, colour=colour, ms=ms, x_full=ms / t_full,
                    x_full_median=float(np.median(np.array(rounds) / np.array(rounds_full))),
                    x_pyvista=(ms / pv_ms) if pv_ms else None, triangles=res.stats["triangles_drawn"], faces=faces,
                    interior_skipped=res.stats.get("grid_interior_triangles_skipped"),
                    differing_pct=100.0 * err["differing_pixel_fraction"],
                    differing_tol4_pct=100.0 * compare.image_error(res.image, full.image, threshold=4)[
                        "differing_pixel_fraction"],
                ))
        scene.set_color_by(gid, "values")
        out["rows"].append(dict(view=view, mode="pyvista", colour="flat", ms=pv_ms,
                                x_full=(pv_ms / t_full) if pv_ms else None, x_full_median=None,
                                x_pyvista=1.0 if pv_ms else None, interior_skipped=None,
                                triangles=surf.n_cells if surf is not None else None, faces=None, differing_pct=None,
                                differing_tol4_pct=None))
    return out


def format_table(res: dict[str, Any]) -> str:
    """The benchmark's printed tables."""
    lines = [
        f"grid: {res['cells']:,} cells ({res['active']:,} active), built in {res['build_s']:.2f} s, "
        f"peak RSS {res['peak_rss_mib']:.0f} MiB (+{res['build_peak_rss_growth_mib']:.0f} MiB during the build), "
        f"host geometry {res['host_bytes'] / 2**20:.0f} MiB; PyVista extract_surface "
        + (f"{res['pyvista_extract_ms']:.0f} ms" if res["pyvista_extract_ms"] is not None else "skipped"),
        "",
        "level | faces     | % of L0 | vertices  | % of L0 | volume change %",
    ]
    for lv in res["levels"]:
        lines.append(f"{lv['level']:5d} | {lv['faces']:9,d} | {lv['faces_pct']:7.1f} | {lv['vertices']:9,d} | "
                     f"{lv['vertices_pct']:7.1f} | {lv['volume_change_pct']:+.3f}")
    lines += ["", f"frames at {res['width']}x{res['height']} (best of repeats, one run):",
              "view     | mode         | colour | ms       | x full | x full (median) | x PyVista | triangles  "
              "| interior left out | faces     | differing % | beyond 4/255 %"]
    for row in res["rows"]:
        def f(v: Any, fmt: str) -> str:
            return "–" if v is None else format(v, fmt)
        lines.append(f"{row['view']:8s} | {row['mode']:12s} | {row['colour']:6s} | {f(row['ms'], '8.1f')} | "
                     f"{f(row['x_full'], '6.3f')} | {f(row.get('x_full_median'), '15.3f')} | "
                     f"{f(row['x_pyvista'], '9.3f')} | {f(row['triangles'], '10,d')} | "
                     f"{f(row.get('interior_skipped'), '17,d')} | "
                     f"{f(row['faces'], '9,d')} | {f(row['differing_pct'], '.3f')} | "
                     f"{f(row['differing_tol4_pct'], '.3f')}")
    return "\n".join(lines)
