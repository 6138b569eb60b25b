"""``python -m geocull bench --scene scale --quick`` (issue 41's scale benchmark, the CI variant): two sizes
of the Gullfaks-like scene at the same extent, each measured in its own process; the table has its
columns, one row per size, and the acceptance lines with their targets; the JSON has the same numbers."""

from __future__ import annotations

import json

import pytest

from geocull.bench import cli
from geocull.bench import scale as bench_scale


def test_sizes_keep_the_extent_and_the_tile_size():
    for n in (*bench_scale.SIZES, *bench_scale.QUICK_SIZES):
        assert bench_scale.spacing_for(n) * (n - 1) == pytest.approx(417 * 25.0)
    assert [bench_scale.tiles_for(n) for n in bench_scale.SIZES] == [10, 20, 40]


def test_config():
    cfg = cli.config(cli.parser().parse_args(["--scene", "scale", "--quick"]))
    assert cfg["sizes"] == bench_scale.QUICK_SIZES and cfg["views"] == list(bench_scale.VIEWS)
    assert (cfg["width"], cfg["height"]) == (320, 256)
    cfg = cli.config(cli.parser().parse_args(["--scene", "scale", "--scale-sizes", "50,60", "--views", "2"]))
    assert cfg["sizes"] == (50, 60) and cfg["views"] == ["oblique_az045", "oblique_az135"]
    with pytest.raises(SystemExit):
        cli.config(cli.parser().parse_args(["--scene", "scale", "--views", "nowhere"]))


def test_bench_scale_quick(tmp_path, capsys):
    out = tmp_path / "scale.json"
    assert cli.main(["--scene", "scale", "--quick", "--json", str(out)]) == 0
    table = capsys.readouterr().out
    header = next(line for line in table.splitlines() if line.startswith("| scene |"))
    assert [c.strip() for c in header.strip("|").split("|")] == list(bench_scale.COLUMNS)
    rows = [line for line in table.splitlines() if line.startswith("| ") and "triangles |" in line]
    assert len(rows) == 2 and all(len(r.strip("|").split("|")) == len(bench_scale.COLUMNS) for r in rows)
    for what in ("temporal + lod frame", "first image", "peak RSS per fine triangle", "lod image error"):
        assert what in table
    assert "target <= 1.3 x" in table and "target <= 10 s" in table and "target <= 40 B" in table

    res = json.loads(out.read_text())
    sizes = res["rows"]
    assert [r["size"] for r in sizes] == list(bench_scale.QUICK_SIZES)
    small, big = sizes
    assert 150_000 < small["triangles"] < 350_000 and 3 < big["triangles"] / small["triangles"] < 4.5
    for r in sizes:
        assert "error" not in r
        assert [v["view"] for v in r["views"]] == list(bench_scale.VIEWS)
        assert r["tiles"] > 0 and r["build_s"] > 0 and r["first_image_s"] >= r["build_s"]
        assert r["none_ms"] > 0 and r["temporal_ms"] > 0 and r["temporal_lod_ms"] > 0
        assert r["peak_rss_bytes"] > 0 and r["rss_bytes_per_triangle"] == pytest.approx(
            r["peak_rss_bytes"] / r["triangles"])
        assert 0 <= r["lod_diff4_pct"] <= r["lod_diff_pct"] <= 100
    s = res["summary"]
    assert s["lod_ratio"] == pytest.approx(big["temporal_lod_ms"] / small["temporal_lod_ms"])
    assert s["first_image_s"] == big["first_image_s"] and s["targets"] == bench_scale.TARGETS
