"""The seismic-scene benchmark (``python -m geocull bench --scene seismic``, issue 14): the
Gullfaks-like horizons and faults with three seismic slices (an inline, a crossline and a time
slice through a synthetic amplitude cube spanning the scene) and one volume lens, as in seed
000's Figure 1. Per view, side by side in one run: the frame time of none and three_pass
(conservative, threshold 0) without and with the slices and the lens, the tiles three_pass culls
with and without the slices (the culling the slices cause; "culled tiles +slices" counts the
horizons' and faults' tiles only), the lens's slices drawn or hidden, and the cost of moving a
slice (``set_slice_index`` and the next frame, none and three_pass) against moving it in PyVista
(cut from the cube, replaced in the plotter, rendered). With ``salt`` (default on), a second
scene, the horizons and faults with the inline and a salt body (an isosurface of a synthetic blob
volume, a diapir through the shallow horizons), per view: the frame time and the isosurface triangles drawn by none,
three_pass and implicit (issue 40; all three at threshold 0). Nothing is asserted.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from .report import best_frame

__all__ = ["run", "format_table", "amplitude_cube", "salt_volume"]


def amplitude_cube(
    bounds: tuple[float, ...], n: tuple[int, int, int], seed: int = 0
) -> tuple[np.ndarray, tuple[float, float, float], tuple[float, float, float]]:
    """A synthetic post-stack amplitude cube (x, y, z) spanning ``bounds`` = (xmin, xmax, ymin, ymax,
    zmin, zmax): layered reflectors (a sine in depth, gently dipping) with noise. Returns
    (values (nx, ny, nz) float32, origin, spacing)."""
    x0, x1, y0, y1, z0, z1 = bounds
    nx, ny, nz = n
    rng = np.random.default_rng(seed)
    x, y, z = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(y0, y1, ny), np.linspace(z0, z1, nz), indexing="ij")
    v = np.sin((z + 0.02 * (x - x0) + 0.01 * (y - y0)) / max((z1 - z0) / 40, 1e-9))
    v = (v + 0.3 * rng.standard_normal(v.shape)).astype(np.float32)
    spacing = ((x1 - x0) / (nx - 1), (y1 - y0) / (ny - 1), (z1 - z0) / (nz - 1))
    return v, (x0, y0, z0), spacing


def salt_volume(bounds: tuple[float, ...], n: tuple[int, int, int]) -> tuple[np.ndarray, tuple, tuple]:
    """A lumpy salt body (values > 0 inside, isovalue 0) in the middle of ``bounds``, clear of the
    volume's border: (values (nx, ny, nz) float32, origin, spacing), as :func:`amplitude_cube`."""
    x0, x1, y0, y1, z0, z1 = bounds
    nx, ny, nz = n
    u, v, w = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny), np.linspace(0, 1, nz), indexing="ij")
    r = np.sqrt((u - 0.5) ** 2 + (v - 0.5) ** 2 + ((w - 0.45) / 1.3) ** 2)
    vals = (0.26 + 0.03 * np.sin(9 * u) * np.cos(7 * v) + 0.02 * np.sin(11 * w) - r).astype(np.float32)
    spacing = ((x1 - x0) / (nx - 1), (y1 - y0) / (ny - 1), (z1 - z0) / (nz - 1))
    return vals, (x0, y0, z0), spacing


def salt_rows(spec: Any, vol: Any, n: tuple[int, int, int], views: list, cfg: dict[str, Any]) -> list[dict[str, Any]]:
    """Per view, none / three_pass / implicit (threshold 0) on the horizons and faults with the
    inline of ``vol`` and a salt isosurface: best frame ms, isosurface triangles drawn, and whether
    implicit's image is none's."""
    import geocull as gc

    w, h, rep = int(cfg["width"]), int(cfg["height"]), int(cfg.get("repeats", 3))
    scene = spec.build(tiles=(10, 10), coarse_factor=25)
    scene.add_slice(vol, "inline", n[0] // 3)
    c = cfg.get("salt_cube", (64, 64, 48))
    # A diapir: the body's lower half among the horizons, its top above the shallowest.
    x0, x1, y0, y1, z0, z1 = spec.bounds
    dz = z1 - z0
    shape = (int(c[0]), int(c[1]), int(c[2]))
    vals, origin, spacing = salt_volume((x0, x1, y0, y1, z0 + 0.4 * dz, z1 + 0.8 * dz), shape)
    salt = scene.add_isosurface(gc.Volume(vals, origin=origin, spacing=spacing, order="xyz"), 0.0, tiles=64)
    on_salt = scene.tile_table()["object"] == salt
    tris = scene.tile_table()["tris_fine"]
    r = gc.Renderer(w, h)
    rows = []
    for name, cam in views:
        row: dict[str, Any] = dict(view=name)
        imgs = {}
        for mode in ("none", "three_pass", "implicit"):
            res, ms = best_frame(lambda cam=cam, mode=mode: r.render(scene, cam, culling=mode, pixel_threshold=0), rep)
            row[f"{mode}_ms"] = ms
            row[f"{mode}_iso_tris"] = int(tris[res.tile_drawn & on_salt].sum())
            imgs[mode] = res.image
            if mode == "implicit":
                row["boxes"] = int(res.stats.get("implicit_occluder_boxes", 0))
        row["same_image"] = bool(np.array_equal(imgs["implicit"], imgs["none"]))
        rows.append(row)
    return rows


def run(cfg: dict[str, Any]) -> dict[str, Any]:
    """Runs the benchmark; ``cfg``: size (horizon samples per side), n_faults, width, height,
    repeats, cube ((nx, ny, nz) samples of the amplitude cube), views (count)."""
    import geocull as gc
    from geocull.data import gullfaks_like, standard_views

    w, h, rep = int(cfg["width"]), int(cfg["height"]), int(cfg.get("repeats", 3))
    spec = gullfaks_like(nx=int(cfg["size"]), ny=int(cfg["size"]), n_faults=int(cfg.get("n_faults", 12)))
    plain = spec.build(tiles=(10, 10), coarse_factor=25)
    scene = spec.build(tiles=(10, 10), coarse_factor=25)
    c = cfg.get("cube", (120, 120, 80))
    n = (int(c[0]), int(c[1]), int(c[2]))
    vals, origin, spacing = amplitude_cube(spec.bounds, n)
    vol = gc.Volume(vals, origin=origin, spacing=spacing, order="xyz")
    t = time.perf_counter()
    ids = [scene.add_slice(vol, "inline", n[0] // 3), scene.add_slice(vol, "crossline", 2 * n[1] // 3),
           scene.add_slice(vol, "sample", n[2] // 4)]
    slices_s = time.perf_counter() - t
    # Near the top of the cube, over the shallowest horizon in most views.
    lens_box = ((n[0] // 2, n[0] // 2 + n[0] // 6), (n[1] // 4, n[1] // 4 + n[1] // 6), (3 * n[2] // 4, n[2] - 1))
    scene.add_lens(vol, lens_box, cmap="plasma", opacity=0.25)
    views = [(name, gc.Camera.look_at(**kw)) for name, kw in standard_views(spec)][: int(cfg.get("views", 7))]
    r_plain, r_scene = gc.Renderer(w, h), gc.Renderer(w, h)
    _, frame_ms = best_frame(lambda: r_scene.render(scene, views[0][1], culling="none"), 1)
    # Moving the inline: set_slice_index, then the next frame (which writes the moved slice's
    # geometry), best of 3 moves to indices not seen before, for none and three_pass.
    move: dict[str, list[float]] = {"move": [], "none": [], "three_pass": []}
    step = iter(range(1, 7))
    for culling in ("none", "three_pass"):
        r_scene.render(scene, views[0][1], culling=culling, pixel_threshold=0)
        for _ in range(3):
            t = time.perf_counter()
            scene.set_slice_index(ids[0], n[0] // 3 + next(step))
            move["move"].append((time.perf_counter() - t) * 1e3)
            t = time.perf_counter()
            r_scene.render(scene, views[0][1], culling=culling, pixel_threshold=0)
            move[culling].append((time.perf_counter() - t) * 1e3)
    out: dict[str, Any] = dict(width=w, height=h, triangles=plain.n_triangles,
                               slice_triangles=scene.n_triangles - plain.n_triangles, slices_build_s=slices_s,
                               move_ms=min(move["move"]), move_frame_ms=min(move["none"]),
                               move_frame_tp_ms=min(move["three_pass"]), frame_ms=frame_ms,
                               pyvista_move_ms=(pyvista_move(scene, vol, vals, origin, spacing, n, views[0][1], w, h)
                                                if cfg.get("pyvista", True) else None),
                               rows=[])
    # The horizons' and faults' tiles (the slices' and the lens's are counted apart).
    base_tiles = np.isin(scene.tile_table()["object"], plain.object_ids())
    for name, cam in views:
        base_none, t_none = best_frame(lambda cam=cam: r_plain.render(plain, cam, culling="none"), rep)
        base_tp, t_tp = best_frame(
            lambda cam=cam: r_plain.render(plain, cam, culling="three_pass", pixel_threshold=0), rep)
        with_none, t_wnone = best_frame(lambda cam=cam: r_scene.render(scene, cam, culling="none"), rep)
        with_tp, t_wtp = best_frame(
            lambda cam=cam: r_scene.render(scene, cam, culling="three_pass", pixel_threshold=0), rep)
        st = with_tp.stats
        out["rows"].append(dict(
            view=name, none_ms=t_none, tp_ms=t_tp, none_slices_ms=t_wnone, tp_slices_ms=t_wtp,
            tiles_culled=int(base_tp.stats["tiles_total"] - base_tp.stats["tiles_drawn"]),
            tiles_culled_slices=int((~with_tp.tile_drawn & base_tiles).sum()),
            slice_tiles_drawn=int((with_tp.tile_drawn & ~base_tiles).sum()),
            tris_tp=int(base_tp.stats["triangles_drawn"]), tris_tp_slices=int(st["triangles_drawn"]),
            lens_drawn=int(st.get("lens_slices_drawn", 0)), lens_tested=int(st.get("lens_slices_tested", 0)),
            lens_hidden=int(st.get("lenses_hidden", 0)),
            same_image=bool(np.array_equal(with_tp.image, with_none.image)),
        ))
    return out


def pyvista_move(scene, vol, vals, origin, spacing, n, cam, w: int, h: int) -> float | None:
    """What moving the inline costs a PyVista user on the same scene and view (MSAA off): the
    moved slice cut from the cube (``ImageData.slice``), put in place of the last one
    (``add_mesh(..., name=)``, coloured by amplitude) and the frame rendered; best of 3 moves, ms.
    None without PyVista."""
    try:
        import pyvista as pv

        from .. import pyvista as gpv
    except ImportError:
        return None
    st = gpv._Setup(scene, cam, w, h, False, True, None, None, (0.0, 0.0, 0.0), 1e-4)
    grid = pv.ImageData(dimensions=n, spacing=spacing, origin=tuple(np.subtract(origin, st.origin)))
    grid.point_data["amplitude"] = np.asarray(vals).ravel(order="F")  # x fastest, as VTK stores points
    st.render()
    times = []
    try:
        for k in range(1, 4):
            t = time.perf_counter()
            x = grid.origin[0] + (n[0] // 3 + k) * spacing[0]
            sl = grid.slice(normal="x", origin=(x, grid.center[1], grid.center[2]))
            st.plotter.add_mesh(sl, scalars="amplitude", cmap="seismic", name="inline", show_scalar_bar=False)
            st.render()
            times.append((time.perf_counter() - t) * 1e3)
    finally:
        st.close()
    return min(times[1:])  # the first move adds the actor; the others replace it


def format_table(res: dict[str, Any]) -> str:
    """The printed table."""
    lines = [
        f"seismic scene: {res['triangles']:,} horizon + fault triangles, three slices + a lens add "
        f"{res['slice_triangles']:,} triangles ({res['slices_build_s']:.2f} s to build the slices); moving a slice "
        f"{res['move_ms']:.0f} ms, the next frame none {res['move_frame_ms']:.0f} ms (against {res['frame_ms']:.0f} "
        f"without a move), three_pass {res['move_frame_tp_ms']:.0f} ms; PyVista (slice, add_mesh, render): "
        + (f"{res['pyvista_move_ms']:.0f} ms" if res.get("pyvista_move_ms") else "not run")
        + f"; {res['width']}x{res['height']}",
        "view            | none ms | +slices | three_pass | +slices | culled tiles | +slices | triangles tp | +slices "
        "| slice tiles drawn | lens drawn/tested | tp = none",
    ]
    for r in res["rows"]:
        lines.append(
            f"{r['view'][:15]:15s} | {r['none_ms']:7.1f} | {r['none_slices_ms']:7.1f} | {r['tp_ms']:10.1f} | "
            f"{r['tp_slices_ms']:7.1f} | {r['tiles_culled']:12d} | {r['tiles_culled_slices']:7d} | "
            f"{r['tris_tp']:12,d} | {r['tris_tp_slices']:7,d} | {r['slice_tiles_drawn']:17d} | "
            f"{r['lens_drawn']:>8d}/{r['lens_tested']:<8d} | "
            f"{r['same_image']}")
    if res.get("salt_rows"):
        lines.append("with a salt isosurface (horizons, faults, the inline; threshold 0): ms and isosurface "
                     "triangles drawn")
        lines.append("view            | none ms | three_pass | implicit | iso tris none | three_pass | implicit "
                     "| boxes | implicit = none")
        for r in res["salt_rows"]:
            lines.append(
                f"{r['view'][:15]:15s} | {r['none_ms']:7.1f} | {r['three_pass_ms']:10.1f} | {r['implicit_ms']:8.1f} | "
                f"{r['none_iso_tris']:13,d} | {r['three_pass_iso_tris']:10,d} | {r['implicit_iso_tris']:8,d} | "
                f"{r['boxes']:5d} | {r['same_image']}")
    return "\n".join(lines)
