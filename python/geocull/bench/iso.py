"""``python -m geocull bench --scene iso``: isosurfaces, geocull against PyVista, side by side.

For every volume (the Pesco et al. synthetic field, and real volumes shipped inside PyVista's wheel:
``channels``, 251×251×101 facies of a fluvial reservoir model, and ``frog``, 500×470×136 tissue
labels; nothing is downloaded) and every view (``--views``, default 8, orbiting the volume at 1.4
diagonals, elevation ±25°), in one process and one run, after a warm-up frame per method:

- geocull ``none`` (every octree node that may hold surface: the reference image), ``implicit``
  (occlusion map of implicit occluders, only visible nodes extracted) and ``oracle`` (only the
  cells holding a visible point of none's image, read from it untimed: about the least that
  culling whole cells can draw, so implicit's distance to it is what its walk and its extra cells
  cost), each *cold* (``cache=False`` on a renderer of its own whose caches are cleared first:
  every patch extracted and uploaded in the frame) and *warm* (patches cached, and kept on the
  GPU, by the earlier frames of the same view); frame time = ``stats["total_ms"]`` (call → GPU
  done; read-back and one-time setup excluded);
- PyVista: ``contour(method="flying_edges")`` + an off-screen render with MSAA off. Cold = the
  contour's wall time + a render of its mesh in an already set-up plotter; warm = the render alone.

Printed per row: best frame time over ``--repeats`` rounds (rotated order), the ratio to geocull
none of the same temperature and to PyVista of the same temperature, surface faces (and the ratio to
none), nodes visible / straddling, read-backs, and the differing pixel fraction against none (0 for a
conservative method). Targets of issue 15 (Pesco field 128³ at 512²): implicit ≥ 2.5× faster than
none, faces ≤ 0.3× of none, implicit ≤ 0.5× PyVista's time.
"""

from __future__ import annotations

import math
import statistics
import sys
import time
from typing import Any

import numpy as np

from ..renderer import IsoCullingMode

VOLUMES = ("pesco", "channels", "frog")


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def load_volume(name: str, n: int) -> tuple[np.ndarray, tuple[float, float, float], tuple[float, float, float], float]:
    """``(values (nz, ny, nx), origin, spacing, isovalue)`` of a benchmark volume (no download)."""
    if name == "pesco":
        from ..data import pesco_synthetic

        vals, origin, spacing = pesco_synthetic(n)
        return vals, origin, spacing, 0.0
    from pyvista import examples

    if name == "channels":
        d, key, iso = examples.load_channels(), "facies", 0.5  # channel facies (1..4) against background (0)
    elif name == "frog":
        d, key, iso = examples.load_frog_tissues(), "MetaImage", 0.5  # the frog's tissues against air (0)
    else:
        raise SystemExit(f"--iso-volumes: unknown volume {name!r}; known: {', '.join(VOLUMES)}")
    nx, ny, nz = d.dimensions
    a = np.asarray(d[key])
    o = np.array(d.origin, dtype=np.float64)
    if a.size != nx * ny * nz:  # cell data (channels): one sample per cell, at the cell centres
        nx, ny, nz = nx - 1, ny - 1, nz - 1
        o = o + 0.5 * np.array(d.spacing)
    vals = a.reshape(nz, ny, nx).astype(np.float32)
    return vals, tuple(map(float, o)), tuple(map(float, d.spacing)), iso  # type: ignore[return-value]


def views(origin, spacing, shape, n_views: int) -> list[tuple[str, Any]]:
    import geocull as gc

    nz, ny, nx = shape
    lo = np.array(origin, dtype=np.float64)
    hi = lo + np.array(spacing) * (np.array([nx, ny, nz]) - 1)
    c = 0.5 * (lo + hi)
    dist = 1.4 * float(np.linalg.norm(hi - lo))
    out = []
    for k in range(n_views):
        a = 2 * math.pi * k / n_views + 0.3
        e = math.radians(25.0 if k % 2 == 0 else -25.0)
        eye = c + dist * np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
        out.append((f"az{math.degrees(a) % 360:03.0f}_el{math.degrees(e):+03.0f}",
                    gc.Camera.look_at(eye, c, up=(0, 0, 1), fov_y=40.0)))
    return out


class _MeshScene:
    """One mesh in the shape geocull.pyvista's plotter set-up reads a scene."""

    def __init__(self, verts: np.ndarray, faces: np.ndarray) -> None:
        self.v, self.f = verts, faces

    def object_ids(self) -> list[int]:
        return [0]

    def object_info(self, id: int, /) -> dict[str, Any]:
        return {"color": (0.85, 0.72, 0.45), "visible": True}

    def geometry(self, id: int, /) -> tuple[np.ndarray, np.ndarray]:
        return self.v, self.f


def run_volume(name: str, cfg: dict[str, Any]) -> list[dict[str, Any]]:
    import geocull as gc

    from ..compare import image_error
    from . import report

    w, h = int(cfg["width"]), int(cfg["height"])
    vals, origin, spacing, iso = load_volume(name, int(cfg["iso_n"]))
    _say(f"bench[iso]: volume {name} {vals.shape[::-1]} isovalue {iso}")
    vol = gc.Volume(vals, origin=origin, spacing=spacing)
    # Warm frames on one renderer (its caches filled by the first frames of each view), cold ones
    # on another whose caches are cleared before each: a cold frame never empties the warm
    # renderer's caches (renderers share the device and pipelines, not caches).
    r, r_cold = gc.Renderer(w, h), gc.Renderer(w, h)
    od: int | None = cfg.get("occluder_depth")
    cd: int | None = cfg.get("cull_depth")
    pv_mesh = None
    contour_ms = None
    if cfg["pyvista"]:
        try:
            import pyvista as pv

            from .. import pyvista as gpv

            g = pv.ImageData(dimensions=vals.shape[::-1], origin=origin, spacing=spacing)
            g.point_data["f"] = vals.ravel()
            g.contour([iso], scalars="f", method="flying_edges")  # warm-up
            ct: list[float] = []
            for _ in range(max(1, int(cfg["repeats"]))):
                t0 = time.perf_counter()
                pv_mesh = g.contour([iso], scalars="f", method="flying_edges")
                ct.append((time.perf_counter() - t0) * 1e3)
            contour_ms = min(ct)
        except Exception as e:  # pragma: no cover - environment dependent
            _say(f"bench[iso]: PyVista unavailable ({e}); skipping its rows")
            pv_mesh = None
    rows: list[dict[str, Any]] = []
    for vname, cam in views(origin, spacing, vals.shape, int(cfg["iso_views"])):
        def geo(culling: IsoCullingMode, cache: bool, cam=cam):
            def job() -> float:
                if not cache:
                    gc.iso.clear_cache(r_cold)
                rr = r if cache else r_cold
                res = rr.render_isosurface(vol, iso, cam, culling, cache=cache, occluder_depth=od, cull_depth=cd)
                return res.stats["total_ms"]
            return job

        modes: tuple[IsoCullingMode, ...] = ("none", "implicit", "oracle")
        first = {c: r.render_isosurface(vol, iso, cam, c, occluder_depth=od, cull_depth=cd) for c in modes}
        ref = first["none"]
        jobs: list[tuple[str, Any]] = [(f"{c}_{t}", geo(c, t == "warm")) for c in modes for t in ("cold", "warm")]
        st = None
        if pv_mesh is not None:
            faces = np.asarray(pv_mesh.regular_faces)
            st = gpv._Setup(_MeshScene(np.asarray(pv_mesh.points, dtype=np.float64), faces), cam, w, h, False, True,
                            ref.near, ref.far, (0.0, 0.0, 0.0), 1e-4)
            st.render()  # warm-up: context, shaders, upload
            jobs.append(("pyvista_warm", st.render))
        # Cores busy per call: the process's CPU time (all its threads: the host's walk, lavapipe's
        # or llvmpipe's) over the call's wall time; on a CPU adapter the share of the machine a frame
        # takes, which its time alone does not say.
        cores: dict[str, list[float]] = {}

        def busy(key: str, fn: Any, out: dict[str, list[float]] = cores) -> Any:
            def job() -> float:
                c0, t0 = time.process_time(), time.perf_counter()
                ms = fn()
                out.setdefault(key, []).append((time.process_time() - c0) / max(1e-9, time.perf_counter() - t0))
                return ms
            return job

        jobs = [(k, busy(k, fn)) for k, fn in jobs]
        try:
            times = report.timed_rounds(jobs, int(cfg["repeats"]))
        finally:
            if st is not None:
                st.close()
        if contour_ms is not None:
            times["pyvista_cold"] = [contour_ms + t for t in times["pyvista_warm"]]
        best = {k: min(v) for k, v in times.items()}
        for key in times:
            method, temp = key.rsplit("_", 1)
            row: dict[str, Any] = dict(volume=name, view=vname, method=method, temperature=temp, total_ms=best[key],
                                       median_ms=statistics.median(times[key]),
                                       ratio_to_none=best[key] / best[f"none_{temp}"],
                                       # (The oracle's call renders `none` first, untimed: not its frame's.)
                                       cores=(statistics.median(cores[key])
                                              if key in cores and method != "oracle" else None),
                                       ratio_to_pyvista=(best[key] / best[f"pyvista_{temp}"]
                                                         if f"pyvista_{temp}" in best else None))
            if method in first:
                res = first[method]
                s = res.stats
                row.update(faces=int(s["surface_triangles"]), faces_ratio=s["surface_triangles"] /
                           max(1, ref.stats["surface_triangles"]), nodes_visible=int(s["nodes_visible"]),
                           nodes_straddling=int(s["nodes_straddling"]), readbacks=int(s["readbacks"]),
                           setup_ms=float(s["setup_ms"]), walk=str(s["walk"]), walk_rays=int(s["walk_rays"]),
                           walk_steps=int(s["walk_steps"]),
                           differing_pixel_fraction=image_error(res.image, ref.image)["differing_pixel_fraction"])
            else:
                assert pv_mesh is not None
                row.update(faces=int(pv_mesh.n_cells),
                           faces_ratio=pv_mesh.n_cells / max(1, ref.stats["surface_triangles"]), contour_ms=contour_ms)
            rows.append(row)
        _say(f"bench[iso]: {name} view {vname} done")
    return rows


def run(cfg: dict[str, Any]) -> dict[str, Any]:
    """All volumes of ``cfg["iso_volumes"]``; returns ``{"summary": ..., "rows": [...]}``."""
    import geocull as gc

    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    for name in cfg["iso_volumes"]:
        rows.extend(run_volume(name, cfg))
    per: dict[str, dict[str, Any]] = {}
    for r in rows:
        k = f"{r['volume']}/{r['method']}_{r['temperature']}"
        per.setdefault(k, {"rows": []})["rows"].append(r)
    for m in per.values():
        rs = m.pop("rows")
        m.update(mean_ms=sum(x["total_ms"] for x in rs) / len(rs),
                 **{k: _gmean(x[k] for x in rs) for k in ("ratio_to_none", "ratio_to_pyvista", "faces_ratio", "cores")},
                 max_differing_pixel_fraction=max((x.get("differing_pixel_fraction") or 0.0) for x in rs),
                 walk_steps_per_ray=(sum(x["walk_steps"] for x in rs) / sum(x["walk_rays"] for x in rs)
                                     if all(x.get("walk_rays") for x in rs) else None))
    return dict(summary=dict(mode=cfg["mode"], width=cfg["width"], height=cfg["height"], repeats=cfg["repeats"],
                             views=cfg["iso_views"], n=cfg["iso_n"], adapter=gc.Renderer(8, 8).adapter_info,
                             wall_s=time.perf_counter() - t0, per_method=per), rows=rows)


def _gmean(xs) -> float | None:
    xs = [float(x) for x in xs if x is not None and x > 0]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else None


def _f(v, fmt: str) -> str:
    return "–" if v is None else format(v, fmt)


def format_table(result: dict[str, Any]) -> str:
    s = result["summary"]
    lines = [f"geocull bench --scene iso ({s['mode']}): {s['width']}x{s['height']}, {s['views']} view(s) per volume, "
             f"best of {s['repeats']} round(s) after a warm-up; {s['adapter']}", ""]
    hdr = (f"{'volume':<9} {'view':<12} {'method':<9} {'temp':<5} {'ms':>8} {'cores':>5} {'x none':>7} {'x pv':>6} "
           f"{'faces':>10} {'x none':>6} {'nodes':>13} {'rb':>3} {'diff px %':>9}")
    lines += [hdr, "-" * len(hdr)]
    for r in result["rows"]:
        nodes = f"{r['nodes_visible']}/{r['nodes_straddling']}" if "nodes_visible" in r else "–"
        dpf = r.get("differing_pixel_fraction")
        lines.append(f"{r['volume']:<9} {r['view']:<12} {r['method']:<9} {r['temperature']:<5} {r['total_ms']:>8.1f} "
                     f"{_f(r['cores'], '.2f'):>5} "
                     f"{r['ratio_to_none']:>7.3f} {_f(r['ratio_to_pyvista'], '.3f'):>6} {r['faces']:>10,} "
                     f"{r['faces_ratio']:>6.3f} {nodes:>13} {_f(r.get('readbacks'), 'd'):>3} "
                     f"{_f(None if dpf is None else 100 * dpf, '.4f'):>9}")
    lines += ["", "per volume and method, geometric mean over views "
              "(mean ms; ratios of frame times, same view, same run):"]
    for k, m in s["per_method"].items():
        lines.append(f"  {k:<24} mean {m['mean_ms']:>8.1f} ms  cores {_f(m['cores'], '.2f')}  "
                     f"x none {_f(m['ratio_to_none'], '.3f')}  "
                     f"x pyvista {_f(m['ratio_to_pyvista'], '.3f')}  faces x none {_f(m['faces_ratio'], '.3f')}  "
                     f"max diff px {100 * m['max_differing_pixel_fraction']:.4f} %"
                     + (f"  walk {m['walk_steps_per_ray']:.1f} steps/ray" if m["walk_steps_per_ray"] else ""))
    walks = "/".join(sorted({str(r["walk"]) for r in result["rows"] if r.get("walk") not in (None, "none")}))
    lines.append("columns: ms = frame time (geocull stats total_ms; PyVista: contour (cold only) + Render + "
                 "WaitForCompletion, MSAA off); cores = the process's CPU time over the wall time of the call (all "
                 "threads; median over rounds; not measured for the oracle, whose call renders none first, nor for "
                 "PyVista cold); cold = no patch cache / contour in the frame; warm = patches cached / mesh already "
                 "extracted; rb = read-backs inside the frame; diff px = pixels differing from geocull none; "
                 f"implicit's walk ran on the {walks or 'none'} (steps/ray: the host walk's cells entered and brick "
                 f"jumps per ray entering the box). Wall {s['wall_s']:.0f} s.")
    return "\n".join(lines)
