"""geocull.bench.report (sweeps, tables, plots) and ``python -m geocull bench`` on tiny configurations.
Timings are never asserted, only their presence and sign."""

import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

gc = pytest.importorskip("geocull")
pytest.importorskip("geocull._geocull")

from geocull.bench import report  # noqa: E402
from geocull.data import stacked_test_scene, standard_views  # noqa: E402

ROW_KEYS = {
    "tiles", "coarse_factor", "view", "method", "mode", "pixel_threshold", "prepass_scale", "total_ms", "median_ms",
    "ratio_to_none", "ratio_to_oracle", "differing_pixel_fraction", "psnr", "missing_tiles", "triangles_drawn",
    "triangles_fine_total", "tiles_drawn", "tiles_total", "triangle_diff_vs_oracle", "build_s", "times_ms",
}


@pytest.fixture(scope="module")
def spec():
    return stacked_test_scene(n=32, n_horizons=3)


@pytest.fixture(scope="module")
def table(spec):
    views = standard_views(spec)[:2]
    return report.sweep(
        spec, views, thresholds=[0, 10], coarse_factors=[25, 100], tiles=[4, (5, 3)], prepass_scales=[1.0, 0.5],
        width=64, height=64, repeats=2,
    )


def test_sweep_rows_cover_the_grid(table):
    # 2 tiles × 2 coarse factors × 2 views × (none + oracle + 2 thresholds × 2 prepass scales)
    assert len(table) == 2 * 2 * 2 * (2 + 4)
    for r in table:
        assert ROW_KEYS <= set(r), ROW_KEYS - set(r)
        assert r["total_ms"] > 0 and r["ratio_to_none"] > 0 and r["ratio_to_oracle"] > 0
        assert len(r["times_ms"]) == 2 and min(r["times_ms"]) == r["total_ms"]
        assert 0.0 <= r["differing_pixel_fraction"] <= 1.0
        assert 0 <= r["tiles_drawn"] <= r["tiles_total"]
        assert 0 <= r["triangles_drawn"] <= r["triangles_fine_total"]
        assert r["build_s"] > 0
    assert {r["tiles"] for r in table} == {"4x4", "5x3"}
    assert {r["coarse_factor"] for r in table} == {25, 100}
    tp = [r for r in table if r["method"] == "three_pass"]
    assert {(r["pixel_threshold"], r["prepass_scale"]) for r in tp} == {(0, 1), (0, 0.5), (10, 1), (10, 0.5)}
    # "three_pass" here is the paper's approximate mode (Renderer's default is conservative): rows say so.
    assert {r["mode"] for r in tp} == {"approximate (paper)"}
    assert all(r["mode"] is None for r in table if r["method"] != "three_pass")


def test_references_have_no_error(table):
    for r in table:
        if r["method"] == "none":
            assert r["differing_pixel_fraction"] == 0.0
            assert r["missing_tiles"] == 0
            assert r["ratio_to_none"] == 1.0
            assert r["tiles_drawn"] == r["tiles_total"]
            assert r["pixel_threshold"] is None and r["prepass_scale"] is None
        if r["method"] == "oracle":
            assert r["missing_tiles"] == 0
            assert r["differing_pixel_fraction"] == 0.0
            assert r["ratio_to_oracle"] == 1.0
            assert r["triangle_diff_vs_oracle"] == 0.0


def test_threshold_zero_full_prepass_draws_every_visible_tile(table):
    for r in table:
        if r["method"] == "three_pass" and r["pixel_threshold"] == 0 and r["prepass_scale"] == 1.0:
            # the prepass of coarse proxies may hide a fine tile's sliver; the exact-count pass with
            # threshold 0 on full resolution should normally draw every visible tile
            assert r["missing_tiles"] <= max(2, r["tiles_total"] // 20)


def test_sweep_on_built_scene_and_errors(spec):
    scene = spec.build(tiles=(4, 4), coarse_factor=25)
    cam = gc.Camera.look_at(**standard_views(spec)[0][1])
    rows = report.sweep(scene, [cam], thresholds=[10], prepass_scales=[1.0], width=48, height=40, repeats=1,
                        methods=("none", "oracle", "three_pass", "horizon"))
    assert [r["method"] for r in rows] == ["none", "oracle", "horizon", "three_pass"]
    assert all(r["tiles"] is None and r["coarse_factor"] is None and r["view"] == "view0" for r in rows)
    with pytest.raises(ValueError, match="SceneSpec"):
        report.sweep(scene, [cam], coarse_factors=[25])
    with pytest.raises(ValueError, match="cameras"):
        report.sweep(scene, None)


def test_summarize_markdown_json_and_plot(table, tmp_path):
    summ = report.summarize(table)
    assert len(summ) == 2 * 2 * 6
    assert all(s["views"] == 2 for s in summ)
    none = [s for s in summ if s["method"] == "none"]
    assert all(math.isclose(s["ratio_to_none"], 1.0) for s in none)
    md = report.to_markdown(summ)
    assert md.startswith("| tiles |") and md.count("\n") == len(summ) + 2
    # Counts print as whole numbers (summaries hold rounded means), parameters as given.
    header, _, *lines = md.strip().split("\n")
    cols = [c.strip() for c in header.strip("|").split("|")]
    cells = [dict(zip(cols, (c.strip() for c in ln.strip("|").split("|")), strict=True)) for ln in lines]
    for c in ("triangles_drawn", "triangles_prepass", "tiles_drawn", "missing_tiles", "views"):
        assert c in cols and all(re.fullmatch(r"[\d,]+|–", row[c]) for row in cells), (c, [r[c] for r in cells])
    assert {row["pixel_threshold"] for row in cells} == {"–", "0", "10"}
    assert {row["prepass_scale"] for row in cells} == {"–", "1", "0.5"}
    assert {row["mode"] for row in cells} == {"–", "approximate (paper)"}
    assert all(isinstance(s["triangles_drawn"], int) and isinstance(s["tiles_drawn"], int) for s in summ)
    p = tmp_path / "t.json"
    report.write_json(dict(rows=table), str(p))  # psnr inf -> null, strict JSON
    back = json.loads(p.read_text())
    assert len(back["rows"]) == len(table)
    png = tmp_path / "speed_vs_error.png"
    assert report.plot(table, str(png), title="test") == str(png)
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000
    png2 = tmp_path / "per_view.png"
    report.plot(table, str(png2), aggregate=False)
    assert png2.stat().st_size > 1000


def test_timed_rounds_rotates_order():
    calls = []
    jobs = [(k, (lambda k=k: calls.append(k) or 1.0)) for k in "abc"]
    t = report.timed_rounds(jobs, repeats=3, warmup=1)
    assert calls == list("abc" + "bca" + "cab" + "abc")
    assert t == {"a": [1.0] * 3, "b": [1.0] * 3, "c": [1.0] * 3}


BENCH_KEYS = {"view", "method", "total_ms", "ratio_to_none", "triangles_drawn", "differing_pixel_fraction"}


def test_bench_tiny_json(tmp_path):
    pytest.importorskip("pyvista")
    out = tmp_path / "bench.json"
    env = dict(os.environ, GEOCULL_BENCH_TINY="1", VTK_DEFAULT_OPENGL_WINDOW="vtkEGLRenderWindow")
    p = subprocess.run(
        [sys.executable, "-m", "geocull", "bench", "--quick", "--json", str(out)],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    assert "bench:" in p.stderr  # progress goes to stderr
    assert "x none" in p.stdout and "bytes per fine triangle" in p.stdout
    d = json.loads(out.read_text())
    rows, s = d["rows"], d["summary"]
    assert s["mode"] == "tiny" and s["width"] == 64 and s["height"] == 48 and len(s["views"]) == 1
    for k in ("scene_build_s", "n_triangles", "host_bytes", "gpu_bytes", "bytes_per_triangle", "peak_rss_mb",
              "adapter", "per_method"):
        assert k in s, k
    assert s["n_triangles"] > 0 and s["bytes_per_triangle"] > 0 and s["peak_rss_mb"] > 0
    methods = [r["method"] for r in rows]
    assert methods == ["none", "three_pass(s=1)", "three_pass(s=0.5)", "three_pass(cf=100,s=0.5)",
                       "three_pass(cons,t=0)", "three_pass(cons,t=0,cf=100,s=0.5)", "none(lod=0.5)",
                       "three_pass(cons,lod=0.5)", "three_pass(cons,lod=1)", "three_pass(cons,lod=2)",
                       "temporal(t=0)", "temporal(lod=0.5)", "oracle", "horizon", "pyvista", "pyvista_msaa"]
    for r in rows:
        assert BENCH_KEYS <= set(r), BENCH_KEYS - set(r)
        assert r["total_ms"] > 0 and r["ratio_to_none"] > 0 and r["triangles_drawn"] > 0
        if r["method"].startswith("pyvista"):
            assert r["differing_pixel_fraction"] is None
            assert 0.9 <= r["coverage_agreement"] <= 1.0
            assert r["triangles_drawn"] == s["n_triangles"]
        else:
            assert 0.0 <= r["differing_pixel_fraction"] <= 1.0
    none = rows[0]
    assert none["ratio_to_none"] == 1.0 and none["differing_pixel_fraction"] == 0.0
    oracle = rows[methods.index("oracle")]
    assert oracle["missing_tiles"] == 0 and oracle["differing_pixel_fraction"] == 0.0
    for m in ("three_pass(cons,t=0)", "three_pass(cons,t=0,cf=100,s=0.5)", "temporal(t=0)"):  # nothing lost
        assert rows[methods.index(m)]["missing_tiles"] == 0, m
        assert rows[methods.index(m)]["differing_pixel_fraction"] == 0.0, m
    orbit = s["orbit"]
    assert set(orbit["methods"]) == {"none", "three_pass(cons,t=0,cf=100,s=0.5)", "temporal(t=0)", "oracle",
                                     "none(lod=0.5)", "temporal(lod=0.5)"}
    assert orbit["temporal_frames_differing"] == 0


def test_bench_views_by_name_without_pyvista(tmp_path):
    out = tmp_path / "b.json"
    env = dict(os.environ, GEOCULL_BENCH_TINY="1")
    p = subprocess.run(
        [sys.executable, "-m", "geocull", "bench", "--views", "top_down,low_az200", "--no-pyvista", "--no-horizon",
         "--json", str(out)],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    d = json.loads(out.read_text())
    assert d["summary"]["views"] == ["top_down", "low_az200"]
    assert {r["method"] for r in d["rows"]} == {"none", "three_pass(s=1)", "three_pass(s=0.5)",
                                                "three_pass(cf=100,s=0.5)", "three_pass(cons,t=0)",
                                                "three_pass(cons,t=0,cf=100,s=0.5)", "none(lod=0.5)",
                                                "three_pass(cons,lod=0.5)", "three_pass(cons,lod=1)",
                                                "three_pass(cons,lod=2)", "temporal(t=0)", "temporal(lod=0.5)",
                                                "oracle"}
    assert np.isclose(d["summary"]["per_method"]["none"]["ratio_to_none"], 1.0)


def test_sweep_materialises_generators_once(spec):
    scene = spec.build(tiles=(4, 4), coarse_factor=25)
    cam = gc.Camera.look_at(**standard_views(spec)[0][1])
    kw = dict(width=32, height=32, repeats=1)
    rows = report.sweep(scene, (c for c in [cam]), thresholds=(t for t in [0, 10]),
                        prepass_scales=(s for s in [1.0]), methods=(m for m in ["none", "three_pass"]), **kw)
    tp = [(r["pixel_threshold"], r["prepass_scale"]) for r in rows if r["method"] == "three_pass"]
    assert tp == [(0, 1.0), (10, 1.0)]
    with pytest.raises(gc.InputError, match="thresholds"):
        report.sweep(scene, [cam], thresholds=(t for t in []), **kw)


def test_sweep_unknown_method_is_an_error_listing_the_valid_ones(spec):
    scene = spec.build(tiles=(4, 4), coarse_factor=25)
    cam = gc.Camera.look_at(**standard_views(spec)[0][1])
    with pytest.raises(gc.InputError, match=r"^methods:.*'three_pas'.*three_pass") as e:
        report.sweep(scene, [cam], methods=("none", "three_pas"), width=32, height=32, repeats=1)
    for m in gc.CULLING_MODES:
        assert m in str(e.value)
    # frustum is a culling mode, so the sweep runs it like horizon
    rows = report.sweep(scene, [cam], methods=["frustum"], width=32, height=32, repeats=1)
    assert [r["method"] for r in rows] == ["none", "oracle", "frustum"]


def test_plot_numbers_points_without_overlaps_and_names_both_three_pass_modes(spec):
    pytest.importorskip("matplotlib")
    scene = spec.build(tiles=(4, 4), coarse_factor=25)
    cams = [gc.Camera.look_at(**v) for _, v in standard_views(spec)[:2]]
    rows = report.sweep(scene, cams, thresholds=[0, 10, 50], prepass_scales=[1.0, 0.5], width=32, height=32,
                        repeats=1, methods=("three_pass", "three_pass_cons", "horizon"))
    assert {r["mode"] for r in rows} == {None, "approximate (paper)", "conservative"}
    assert report.method_name("three_pass") == "three_pass, approximate (paper)"
    assert report.method_name("three_pass_cons") == "three_pass, conservative"
    # the benchmark's names (python -m geocull bench --plot): "cons" marks its conservative runs
    assert report.method_name("three_pass(s=0.5)") == "three_pass(s=0.5), approximate (paper)"
    assert report.method_name("three_pass(cons,t=0)") == "three_pass(cons,t=0), conservative"
    assert report.method_name("temporal(t=0)") == "temporal(t=0)" and report.method_name("none") == "none"
    for aggregate, n in ((True, 3 + 2 * 6), (False, 2 * (3 + 2 * 6))):
        fig = report.figure(rows, aggregate=aggregate)
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        ax = fig.axes[0]
        numbers = [a for a in ax.get_children() if a.get_gid() == "point_label"]
        assert sorted(int(a.get_text()) for a in numbers) == list(range(1, n + 1))
        boxes = [a.get_window_extent(renderer) for a in numbers]
        for i, b in enumerate(boxes):  # no number covers another
            assert not any(b.overlaps(o) for o in boxes[i + 1:]), numbers[i].get_text()
        ticks = [t.get_window_extent(renderer) for t in ax.get_xticklabels() if t.get_text()]
        assert len(ticks) >= 2 and not any(a.overlaps(b) for i, a in enumerate(ticks) for b in ticks[i + 1:])
        key = "\n".join(t.get_text() for t in fig.texts if t.get_gid() == "key")
        assert "three_pass, approximate (paper) t10 s0.5" in key and "three_pass, conservative t0 s1" in key
        assert len(re.findall(r"^ *\d+  ", key, flags=re.M)) == n
        whole = fig.bbox
        for t in fig.texts:  # the key is not cut off at the figure's edge
            e = t.get_window_extent(renderer)
            assert whole.x0 <= e.x0 and e.x1 <= whole.x1 and whole.y0 <= e.y0 and e.y1 <= whole.y1
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert "three_pass, approximate (paper)" in legend and "three_pass, conservative" in legend


def test_to_frame_keeps_counts_integer(table):
    pytest.importorskip("pandas")
    df = report.to_frame(report.summarize(table))
    for c in ("triangles_drawn", "tiles_drawn", "missing_tiles", "views"):
        assert str(df[c].dtype) == "Int64", (c, df[c].dtype)
    assert list(df["mode"].dropna().unique()) == ["approximate (paper)"]
