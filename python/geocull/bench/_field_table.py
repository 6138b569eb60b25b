"""The field benchmark's text report (:func:`format_table`): the field, a table per view, the grid
alone and the summary, from the result :func:`geocull.bench.field.run` returns."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["format_table"]


def _f(v: Any, fmt: str) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    return format(v, fmt)


def _pct(v: Any, fmt: str = ".4f") -> str:
    return _f(None if v is None else 100.0 * v, fmt)


def format_table(result: dict[str, Any]) -> str:
    """The benchmark as text: the field, a table per view, the grid alone, and the summary."""
    s = result["summary"]
    lines = [f"geocull bench --scene field ({s['mode']}): {s['data']}, {s['width']}x{s['height']}, "
             f"{len(s['views'])} view(s), median of {s['repeats']} round(s) after a warm-up frame, methods in rotated "
             f"order; {s['adapter']}, {s['cpu_count']} CPU(s)"]
    lines.append(f"field: {s['n_triangles']:,} triangles in {s['n_tiles']:,} tiles (read {s['read_s']:.1f} s, "
                 f"built {s['build_s']:.1f} s); horizons tiles {s['tiles']} coarse factor {s['coarse_factor']}, "
                 f"clim z {s['clim_z'][0]:.1f}..{s['clim_z'][1]:.1f} m; grid {s['files']['grid']} "
                 f"{'x'.join(map(str, s['grid_dims']))} ({s['grid_active']:,} active) blocks {s['grid_blocks']}, "
                 f"porosity {s['files']['poro']}, clim {_f(s['clim_poro'] and s['clim_poro'][0], '.3f')}.."
                 f"{_f(s['clim_poro'] and s['clim_poro'][1], '.3f')}")
    for kind, k in s["kinds"].items():
        lines.append(f"  {kind:<11} {k['objects']:>2} object(s) {k['triangles']:>10,} triangles "
                     f"({100.0 * k['triangles'] / max(s['n_triangles'], 1):4.1f} %) in {k['tiles']:>4} tiles, "
                     f"coarse proxies {k['coarse_triangles']:>10,} triangles")
    lines.append("  wells: " + ", ".join(f"{wl['name']} {wl['stations']} st {wl['triangles']:,} tri"
                                         + ("" if wl["log"] else " (no log)") for wl in s["wells"]))
    hdr = (f"{'method':<26} {'median ms':>9} {'best ms':>8} {'x none':>7} {'x oracle':>8} {'x pv':>6} "
           f"{'triangles':>10} {'tiles':>9} {'hidden':>6} {'diff px %':>9} {'>4/255 %':>8} {'max':>4} {'miss':>4}")
    for v in s["views"]:
        lines += ["", f"view {v['name']}: azimuth {v['azimuth']:g}, elevation {v['elevation']:g}, "
                      f"z_scale {v['z_scale']:g}, zoom {v['zoom']:g}", hdr, "-" * len(hdr)]
        for r in (r for r in result["rows"] if r["view"] == v["name"]):
            geo = r["renderer"] == "geocull"
            tiles = f"{r['tiles_drawn']}/{r['oracle_tiles']}" if geo else "all"
            lines.append(
                f"{r['method']:<26} {r['median_ms']:>9.1f} {r['best_ms']:>8.1f} {r['x_none']:>7.3f} "
                f"{r['x_oracle']:>8.3f} {_f(r['x_pyvista'], '.3f'):>6} {r['triangles_drawn']:>10,} {tiles:>9} "
                f"{_f(r.get('tiles_proven_hidden'), 'd'):>6} {_pct(r.get('differing_pixel_fraction')):>9} "
                f"{_pct(r.get('differing_pixel_fraction_tol4'), '.3f'):>8} {_f(r.get('max_abs_diff'), 'd'):>4} "
                f"{_f(r.get('missing_tiles'), 'd'):>4}"
                + ("" if not geo or not r["exact"] or r["same_image"] else
                   f"  <- exact mode differs: {r['differing_pixels']} px (depth tie {r['diff_depth_equal']}, "
                   f"nearer {r['diff_depth_nearer']}, farther {r['diff_depth_farther']}) e.g. "
                   f"{r['diff_pixels_sample'][:3]}"))
    lines += ["", "the grid alone (its own renderer): grid_lod screen_error against level 0",
              f"{'view':<20} {'mode':<20} {'median ms':>9} {'x full':>7} {'triangles':>10} {'faces':>8} "
              f"{'diff px %':>9} {'>4/255 %':>8} {'max':>4}"]
    for r in result["grid_rows"]:
        lines.append(f"{r['view']:<20} {r['mode']:<20} {r['median_ms']:>9.1f} {r['x_full']:>7.3f} "
                     f"{r['triangles_drawn']:>10,} {r['faces']:>8,} {_pct(r['differing_pixel_fraction']):>9} "
                     f"{_pct(r['differing_pixel_fraction_tol4'], '.3f'):>8} {r['max_abs_diff']:>4}")
    lines += ["", f"summary over {len(s['views'])} view(s): geometric means of the per-view ratios (of medians); "
                  "max over the views of the image errors against none; missed tiles and proven-hidden tiles summed",
              f"{'method':<26} {'exact':>5} {'x none':>7} {'x oracle':>8} {'x pv':>6} {'triangles':>11} "
              f"{'tiles':>7} {'same img':>8} {'diff px %':>9} {'>4/255 %':>8} {'max':>4} {'miss':>4} {'hidden':>6}"]
    n_views = len(s["views"])
    for name, m in s["per_method"].items():
        same = "–" if m["views_same_image"] is None else f"{m['views_same_image']}/{n_views}"
        lines.append(
            f"{name:<26} {('yes' if m['exact'] else ''):>5} {_f(m['x_none'], '.3f'):>7} {_f(m['x_oracle'], '.3f'):>8} "
            f"{_f(m['x_pyvista'], '.3f'):>6} {m['mean_triangles_drawn']:>11,.0f} "
            f"{_f(m['mean_tiles_drawn'], '.1f'):>7} {same:>8} {_pct(m['max_differing_pixel_fraction']):>9} "
            f"{_pct(m['max_differing_pixel_fraction_tol4'], '.3f'):>8} {_f(m['max_abs_diff'], 'd'):>4} "
            f"{_f(m['missing_tiles'], 'd'):>4} {_f(m['tiles_proven_hidden'], 'd'):>6}")
    lines += ["", "tiles drawn per object kind / visible in the oracle's image (mean over the views):"]
    for name, m in s["per_method"].items():
        if m.get("mean_tiles_by_kind"):
            lines.append(f"  {name:<26} " + ", ".join(f"{k} {d:.1f}/{o:.1f}"
                                                      for k, (d, o) in m["mean_tiles_by_kind"].items()))
    lines.append("")
    for gname, m in s["grid_alone"].items():
        lines.append(f"grid alone {gname:<15} x full {_f(m['x_full'], '.3f')}, mean triangles "
                     f"{m['mean_triangles_drawn']:,.0f}, max diff px {_pct(m['max_differing_pixel_fraction'])} % "
                     f"(beyond 4/255 {_pct(m['max_differing_pixel_fraction_tol4'], '.3f')} %)")
    pv = f"PyVista {s['pyvista']}, VTK {s['vtk']} (MSAA off, flat colours); " if "pyvista" in s else ""
    lines.append(f"{pv}wall {s['wall_s']:.0f} s")
    lines.append("columns: tiles = drawn / visible in the oracle's image; hidden = stats tiles_proven_hidden; "
                 "diff px = pixels differing from none; max = largest channel difference; miss = tiles visible in "
                 "the oracle's image but not drawn; x pv = time / PyVista's (MSAA off)")
    return "\n".join(lines)
