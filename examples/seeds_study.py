"""Reproduce the seeds' findings (Plate et al.) on a Gullfaks-like scene with geocull.bench.report.sweep.

Three one-factor sweeps around the seeds' recommended setting (10×10 tiles per horizon, pixel
threshold 10, coarse factor 25, full-resolution prepass), each timed side by side against the
unculled render and the oracle, with errors against the unculled image:

1. tiles per horizon 5², 7², 10², 15², 20²                (threshold 10, coarse 25, prepass 1)
2. pixel threshold 0, 10, 50 × prepass scale 1, 0.5, 0.25  (10×10 tiles, coarse 25)
3. coarse factor 25, 100, 400 × threshold 0, 10             (10×10 tiles, prepass 1)

Writes to --out (default examples/out/seeds): ``<sweep>.json`` (all rows), ``<sweep>.md`` (per
configuration over the views), ``<sweep>.png`` (speed against error), ``findings.md`` (which of the
seeds' findings hold here, with the numbers) and ``study.json`` (everything). ``--quick`` is a
smoke test (small scene, small image, 2 views, 1 repeat); its verdicts mean little.

Usage:  python examples/seeds_study.py [--quick] [--out DIR] [--size N] [--width W --height H]
                                        [--views N|names] [--repeats R]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from typing import Any

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import geocull as gc  # noqa: E402
from geocull.bench import report  # noqa: E402
from geocull.data import gullfaks_like, standard_views  # noqa: E402

TILES = [5, 7, 10, 15, 20]
THRESHOLDS = [0, 10, 50]
COARSE = [25, 100, 400]
PREPASS = [1.0, 0.5, 0.25]
FULL_VIEWS = ("oblique_az045", "oblique_az225", "steep_az045", "low_az200")
QUICK_VIEWS = ("oblique_az045", "low_az200")


def say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def sweep_progress(fraction: float, msg: str) -> None:
    """report.sweep's progress callback: its messages, with the fraction of views done."""
    say(f"{fraction * 100:5.1f} % {msg}")


Row = dict[str, Any]


def pick(summary: Sequence[Row], **kw: Any) -> list[Row]:
    """The summary rows matching every keyword (three_pass unless method is given)."""
    kw.setdefault("method", "three_pass")
    return [r for r in summary if all(r.get(k) == v for k, v in kw.items())]


def one(summary: Sequence[Row], **kw: Any) -> Row:
    rs = pick(summary, **kw)
    if len(rs) != 1:
        raise LookupError(f"{kw}: {len(rs)} rows")
    return rs[0]


def pct(x: float | None) -> str:
    return "–" if x is None else f"{100 * x:.3f} %"


def findings(s_tiles: Sequence[Row], s_thr: Sequence[Row], s_coarse: Sequence[Row],
             quick: bool) -> tuple[str, list[Row]]:
    """Judge the seeds' findings against the summaries; returns markdown and a list of verdicts."""
    out: list[str] = []
    verdicts: list[Row] = []

    # 1. tiles: 10x10 fastest
    rows = sorted(pick(s_tiles), key=lambda r: int(str(r["tiles"]).split("x")[0]))
    best = min(rows, key=lambda r: r["ratio_to_none"])
    ten = next(r for r in rows if r["tiles"] == "10x10")
    close = ten["ratio_to_none"] <= best["ratio_to_none"] * 1.05
    holds = best["tiles"] == "10x10" or close
    out.append("### 1. Tiles per horizon: seeds say 10×10 is best\n")
    out.append("| tiles | × none | × oracle | tiles drawn | triangles drawn | Δ triangles vs oracle | diff px "
               "| missing tiles |")
    out.append("|---|---|---|---|---|---|---|---|")
    for r in rows:
        out.append(f"| {r['tiles']} | {r['ratio_to_none']:.3f} | {r['ratio_to_oracle']:.3f} | {r['tiles_drawn']:.0f} | "
                   f"{r['triangles_drawn']:,.0f} | {pct(r['triangle_diff_vs_oracle'])} | "
                   f"{pct(r['differing_pixel_fraction'])} | {r['missing_tiles']} |")
    v = ("HOLDS" if best["tiles"] == "10x10" else "HOLDS (within 5 % of the best)" if close else "DOES NOT HOLD")
    out.append(f"\n**{v}**: fastest three_pass at {best['tiles']} tiles ({best['ratio_to_none']:.3f} × none); "
               f"10×10 gives {ten['ratio_to_none']:.3f} × none.\n")
    verdicts.append(dict(finding="10x10 tiles best", holds=holds, best_tiles=best["tiles"],
                         ratio_best=best["ratio_to_none"], ratio_10x10=ten["ratio_to_none"]))

    # 2. threshold 10 ~ no visible error
    out.append("### 2. Pixel threshold: seeds say threshold 10 gives (almost) no visible error\n")
    out.append("| threshold | prepass scale | × none | × oracle | diff px (mean) | diff px (max view) | missing tiles "
               "| Δ triangles vs oracle |")
    out.append("|---|---|---|---|---|---|---|---|")
    for r in sorted(pick(s_thr), key=lambda r: (r["pixel_threshold"], -r["prepass_scale"])):
        out.append(f"| {r['pixel_threshold']:g} | {r['prepass_scale']:g} | {r['ratio_to_none']:.3f} | "
                   f"{r['ratio_to_oracle']:.3f} | {pct(r['differing_pixel_fraction'])} | "
                   f"{pct(r['max_differing_pixel_fraction'])} | {r['missing_tiles']} | "
                   f"{pct(r['triangle_diff_vs_oracle'])} |")
    t10 = one(s_thr, pixel_threshold=10.0, prepass_scale=1.0)
    t0 = one(s_thr, pixel_threshold=0.0, prepass_scale=1.0)
    ok = t10["differing_pixel_fraction"] <= 1e-3 and t10["max_differing_pixel_fraction"] <= 5e-3
    out.append(f"\n**{'HOLDS' if ok else 'DOES NOT HOLD'}** "
               f"(criterion: mean differing pixels ≤ 0.1 %, worst view ≤ 0.5 %): "
               f"threshold 10 differs from the unculled image in {pct(t10['differing_pixel_fraction'])} of pixels on "
               f"average (worst view {pct(t10['max_differing_pixel_fraction'])}, {t10['missing_tiles']} missing tiles "
               f"over all views) at {t10['ratio_to_none']:.3f} × none; threshold 0: "
               f"{pct(t0['differing_pixel_fraction'])}, {t0['missing_tiles']} missing tiles, "
               f"{t0['ratio_to_none']:.3f} × none.\n")
    verdicts.append(dict(finding="threshold 10 ~ no visible error", holds=ok,
                         dpf_mean=t10["differing_pixel_fraction"], dpf_max=t10["max_differing_pixel_fraction"],
                         missing_tiles=t10["missing_tiles"], ratio=t10["ratio_to_none"]))

    # 3. coarse factor: 25-100 ~1 % triangle difference, 400 breaks
    out.append("### 3. Coarse factor: seeds say 25–100 changes drawn triangles by ≈ 1 %, 400 breaks\n")
    out.append("| coarse factor | threshold | × none | prepass triangles | triangles drawn | Δ triangles vs coarse 25 "
               "| Δ triangles vs oracle | diff px | missing tiles |")
    out.append("|---|---|---|---|---|---|---|---|---|")
    base = {thr: one(s_coarse, coarse_factor=25, pixel_threshold=float(thr), prepass_scale=1.0) for thr in (0, 10)}
    for r in sorted(pick(s_coarse), key=lambda r: (r["pixel_threshold"], r["coarse_factor"])):
        b = base[int(r["pixel_threshold"])]
        d25 = (r["triangles_drawn"] - b["triangles_drawn"]) / b["triangles_drawn"]
        r["triangle_diff_vs_c25"] = d25
        out.append(f"| {r['coarse_factor']:g} | {r['pixel_threshold']:g} | {r['ratio_to_none']:.3f} | "
                   f"{r.get('triangles_prepass', 0) or 0:,.0f} | {r['triangles_drawn']:,.0f} | {pct(d25)} | "
                   f"{pct(r['triangle_diff_vs_oracle'])} | {pct(r['differing_pixel_fraction'])} | "
                   f"{r['missing_tiles']} |")
    c = {cf: one(s_coarse, coarse_factor=cf, pixel_threshold=0.0, prepass_scale=1.0) for cf in COARSE}
    d100 = abs(c[100]["triangles_drawn"] - c[25]["triangles_drawn"]) / c[25]["triangles_drawn"]
    d400 = abs(c[400]["triangles_drawn"] - c[25]["triangles_drawn"]) / c[25]["triangles_drawn"]
    small = d100 <= 0.02
    breaks = (d400 > 0.05 or c[400]["differing_pixel_fraction"] > max(10 * c[25]["differing_pixel_fraction"], 1e-3)
              or c[400]["missing_tiles"] > max(5 * c[25]["missing_tiles"], 5))
    out.append(f"\n**25–100 ≈ 1 %: {'HOLDS' if small else 'DOES NOT HOLD'}** (criterion ≤ 2 %): at threshold 0 the "
               f"triangles drawn with coarse factor 100 differ by {pct(d100)} from coarse factor 25 "
               f"({pct(c[100]['triangle_diff_vs_oracle'])} vs oracle).\n")
    out.append(f"**400 breaks: {'HOLDS' if breaks else 'DOES NOT HOLD'}** (criterion: > 5 % triangle difference, or "
               f"differing pixels ≥ 10× coarse 25's and > 0.1 %, or missing tiles ≥ 5× and > 5): coarse factor 400 "
               f"draws {pct(d400)} {'more' if c[400]['triangles_drawn'] >= c[25]['triangles_drawn'] else 'fewer'} "
               f"triangles than 25, differs in {pct(c[400]['differing_pixel_fraction'])} of pixels "
               f"({c[400]['missing_tiles']} missing tiles; coarse 25: {pct(c[25]['differing_pixel_fraction'])}, "
               f"{c[25]['missing_tiles']}).\n")
    verdicts.append(dict(finding="coarse 25-100 ~1% triangle difference", holds=small, diff_100_vs_25=d100))
    verdicts.append(dict(finding="coarse 400 breaks", holds=breaks, diff_400_vs_25=d400,
                         dpf_400=c[400]["differing_pixel_fraction"], missing_400=c[400]["missing_tiles"]))

    # prepass scale (no seed finding; reported)
    out.append("### 4. Prepass scale (no seed finding; for the record)\n")
    for ps in PREPASS:
        r = one(s_thr, pixel_threshold=10.0, prepass_scale=ps)
        out.append(f"- threshold 10, prepass scale {ps:g}: {r['ratio_to_none']:.3f} × none, "
                   f"{pct(r['differing_pixel_fraction'])} differing pixels, {r['missing_tiles']} missing tiles")
    out.append("")
    if quick:
        out.insert(0, "> **Quick (smoke-test) run**: small scene and image, few views and repeats; the verdicts "
                      "below are not meaningful. Run without `--quick` for the real study.\n")
    return "\n".join(out), verdicts


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="smoke test: small scene, small image, 2 views, 1 repeat")
    p.add_argument("--out", default=os.path.join("examples", "out", "seeds"))
    p.add_argument("--size", type=int, help="samples per horizon side (default 418 = full Gullfaks-like; quick 100)")
    p.add_argument("--width", type=int)
    p.add_argument("--height", type=int)
    p.add_argument("--views", help="number of standard views, or comma-separated names")
    p.add_argument("--repeats", type=int)
    a = p.parse_args(argv)

    q = a.quick
    size = a.size or (100 if q else 418)
    w, h = a.width or (240 if q else 1280), a.height or (192 if q else 1024)
    repeats = a.repeats or (1 if q else 3)
    os.makedirs(a.out, exist_ok=True)

    t_start = time.perf_counter()
    spec = gullfaks_like(nx=size, ny=size, n_faults=6 if q else 16)
    all_views = standard_views(spec, aspect=w / h)
    names = [n for n, _ in all_views]
    if a.views is None:
        sel = list(QUICK_VIEWS if q else FULL_VIEWS)
    elif a.views.isdigit():
        sel = names[: int(a.views)]
    else:
        sel = [v.strip() for v in a.views.split(",") if v.strip()]
    views = [(n, kw) for n, kw in all_views if n in sel]
    renderer = gc.Renderer(w, h)
    say(f"seeds study: {size}x{size} samples, {w}x{h}, views {', '.join(n for n, _ in views)}, {repeats} repeat(s); "
        f"adapter {renderer.adapter_info}")

    sweeps: dict[str, list[Row]] = {}
    say("sweep 1/3: tiles")
    sweeps["tiles"] = report.sweep(spec, views, thresholds=[10], coarse_factors=[25], tiles=TILES, prepass_scales=[1.0],
                                   renderer=renderer, repeats=repeats, progress=sweep_progress)
    say("sweep 2/3: threshold x prepass scale")
    sweeps["threshold_prepass"] = report.sweep(spec, views, thresholds=THRESHOLDS, coarse_factors=[25], tiles=[10],
                                               prepass_scales=PREPASS, renderer=renderer, repeats=repeats,
                                               progress=sweep_progress)
    say("sweep 3/3: coarse factor")
    sweeps["coarse"] = report.sweep(spec, views, thresholds=[0, 10], coarse_factors=COARSE, tiles=[10],
                                    prepass_scales=[1.0], renderer=renderer, repeats=repeats, progress=sweep_progress)

    summaries: dict[str, list[Row]] = {}
    for name, rows in sweeps.items():
        summ = report.summarize(rows)
        summaries[name] = summ
        report.write_json(dict(rows=rows, summary=summ), os.path.join(a.out, f"{name}.json"))
        with open(os.path.join(a.out, f"{name}.md"), "w") as f:
            f.write(f"# Sweep: {name}\n\nPer configuration over {len(views)} view(s); ratios are geometric means.\n\n")
            f.write(report.to_markdown(summ))
            f.write("\n## Per view\n\n")
            f.write(report.to_markdown(rows))
        report.plot(rows, os.path.join(a.out, f"{name}.png"), title=f"seeds study: {name} ({w}x{h}, {size}² samples)")

    text, verdicts = findings(summaries["tiles"], summaries["threshold_prepass"], summaries["coarse"], q)
    b = sweeps["tiles"][0]
    header = (f"# Seeds study (Plate et al.) on geocull\n\nScene: gullfaks_like({size}×{size} samples, "
              f"{len(spec.horizons)} horizons, {len(spec.faults)} faults), {b['triangles_fine_total']:,} triangles; "
              f"image {w}×{h}; views {', '.join(n for n, _ in views)}; best of {repeats} timed round(s) after a "
              f"warm-up, all methods interleaved; adapter {renderer.adapter_info}. Errors are against the unculled "
              f"image of the same view (differing pixels: any channel differs; missing tiles: visible in the unculled "
              f"image but not drawn, summed over views). Wall time {time.perf_counter() - t_start:.0f} s.\n\n")
    md = header + text
    with open(os.path.join(a.out, "findings.md"), "w") as f:
        f.write(md)
    report.write_json(dict(config=dict(size=size, width=w, height=h, views=[n for n, _ in views], repeats=repeats,
                                       quick=q, adapter=renderer.adapter_info),
                           verdicts=verdicts, summaries=summaries), os.path.join(a.out, "study.json"))
    print(md)
    print("\nSummary:")
    for v in verdicts:
        print(f"  {'holds' if v['holds'] else 'DOES NOT hold'}: {v['finding']}")
    print(f"\nwrote {a.out}/{{tiles,threshold_prepass,coarse}}.{{json,md,png}}, findings.md, study.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
