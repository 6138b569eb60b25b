"""``python -m geocull bench --scene field`` on the real Reek field (``../shared/data/reek``), at tiny
size (64x48, the quick run's 4 views, 1 round): the JSON has its rows side by side for every view and
method, and what holds by construction does: every exact mode draws the image of ``none`` bit for
bit and misses no tile the oracle sees; the oracle is its own lower bound; ``none`` is its own
reference. Skipped where the data or xtgeo is missing."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from geocull import bench
from geocull.bench import field as bench_field

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "reek"

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason=f"no real field at {DATA}")


@pytest.fixture(scope="module")
def field_json(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    pytest.importorskip("xtgeo")
    out = tmp_path_factory.mktemp("bench_field") / "field.json"
    assert bench.main(["--scene", "field", "--tiny", "--data", str(DATA), "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_field_bench_json_structure(field_json: dict[str, Any]) -> None:
    s, rows = field_json["summary"], field_json["rows"]
    assert (s["width"], s["height"], s["repeats"]) == (64, 48, 1)
    names = [v["name"] for v in s["views"]]
    assert names == [v[0] for v in bench_field.VIEWS[:4]]
    assert {v["z_scale"] for v in s["views"]} == {1.0, 5.0, 10.0}
    assert min(v["elevation"] for v in s["views"]) <= 10 and max(v["elevation"] for v in s["views"]) >= 60
    assert max(v["azimuth"] for v in s["views"]) - min(v["azimuth"] for v in s["views"]) >= 180
    assert s["kinds"].keys() == {"heightfield", "grid", "well"}
    assert s["kinds"]["heightfield"]["objects"] == 4 and s["kinds"]["well"]["objects"] == 9
    assert sum(k["triangles"] for k in s["kinds"].values()) == s["n_triangles"]
    assert s["clim_z"][0] < s["clim_z"][1] < 0  # z = -depth
    assert sum(w["log"] for w in s["wells"]) == 8  # OP_6 has no Poro log

    methods = [m for m, _ in bench_field.methods()]
    assert {"none", "oracle", "three_pass(cons,t=0)", "temporal(t=0)", "temporal(lod=0.5)"} <= set(methods)
    has_pv = any(r["method"] == "pyvista" for r in rows)
    expected = methods + (["pyvista"] if has_pv else [])
    for v in names:
        assert [r["method"] for r in rows if r["view"] == v] == expected
    for r in rows:
        assert r["median_ms"] > 0 and r["x_none"] > 0 and r["x_oracle"] > 0
        assert (r["x_pyvista"] is not None) == has_pv
        if r["renderer"] == "geocull":
            for k in ("triangles_drawn", "tiles_drawn", "differing_pixel_fraction", "differing_pixel_fraction_tol4",
                      "max_abs_diff", "missing_tiles", "same_image"):
                assert k in r, (r["method"], k)
            if r["kwargs"]["culling"] in ("temporal",) or r["method"].startswith("three_pass(cons"):
                assert "tiles_proven_hidden" in r
    none = [r for r in rows if r["method"] == "none"]
    assert all(r["x_none"] == 1 and r["same_image"] and r["triangles_drawn"] == s["n_triangles"] for r in none)
    for r in (r for r in rows if r["method"] == "oracle"):
        assert r["tiles_drawn"] == r["oracle_tiles"] and r["x_oracle"] == 1
        assert r["tiles_by_kind"].keys() == s["kinds"].keys()
        assert all(drawn == seen for drawn, seen in r["tiles_by_kind"].values())
    pm = s["per_method"]
    assert set(pm) == set(expected)
    assert all(pm[m]["x_none"] is not None and pm[m]["x_oracle"] is not None for m in expected)
    assert [r["mode"] for r in field_json["grid_rows"]] == [m for _ in names for m in s["grid_alone"]]
    assert all(r["differing_pixels"] == 0 for r in field_json["grid_rows"] if r["mode"] == "full")
    assert "summary over 4 view(s)" in bench_field.format_table(field_json)


def test_field_bench_exact_modes_equal_none(field_json: dict[str, Any]) -> None:
    bad = [f"{r['method']} in {r['view']}: {r['differing_pixels']} px differ, {r['missing_tiles']} tiles missed"
           for r in field_json["rows"] if r["renderer"] == "geocull" and r["method"] in bench_field.EXACT
           and not (r["same_image"] and r["missing_tiles"] == 0)]
    assert not bad, "; ".join(bad)
    # With LOD, tiles visible at level 0 may hide behind coarser neighbours (so "missed" tiles say
    # nothing); what culling must not change is the LOD image: the repeated frame (the last one's
    # visible tiles, untested) and the moving one (tested) differ from none alike.
    by = {(r["view"], r["method"]): r for r in field_json["rows"]}
    for (view, method), r in by.items():
        if method.startswith("temporal(lod=") and not method.endswith(",moving)"):
            m = by[(view, method[:-1] + ",moving)")]
            same = ("differing_pixels", "differing_pixel_fraction_tol4", "max_abs_diff")
            assert [r[k] for k in same] == [m[k] for k in same], view
