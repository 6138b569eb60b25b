"""``python -m geocull bench --scene grid | seismic`` on tiny configurations: the tables' rows are
there, side by side, and what they claim by construction holds (three_pass with slices equals none;
level 0 is its own reference; volumes change little across levels)."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc
from geocull.bench import grid as bench_grid
from geocull.bench import seismic as bench_seismic


def test_bench_grid_tiny():
    pytest.importorskip("pyvista")
    res = bench_grid.run(dict(grid_n=12, grid_nk=6, width=64, height=48, repeats=1, blocks=(4, 4)))
    modes = [(r["view"], r["mode"], r["colour"]) for r in res["rows"]]
    assert modes == [(v, m, c) for v in ("near", "distant")
                     for m, c in [(m, c) for c in ("values", "flat") for m in ("full", "distance", "screen_error")]
                     + [("pyvista", "flat")]]
    full = [r for r in res["rows"] if r["mode"] == "full"]
    assert all(r["differing_pct"] == 0 and r["x_full"] == 1 for r in full)
    assert res["levels"][0]["faces_pct"] == 100 and all(abs(lv["volume_change_pct"]) < 3 for lv in res["levels"])
    assert "volume change" in bench_grid.format_table(res)


def test_bench_seismic_tiny():
    res = bench_seismic.run(dict(size=48, n_faults=2, width=64, height=48, repeats=1, cube=(16, 16, 12), views=2))
    assert len(res["rows"]) == 2
    for r in res["rows"]:
        assert r["same_image"]  # conservative three_pass at threshold 0 with slices and a lens = none
        assert r["lens_tested"] > 0
    assert "lens drawn/tested" in bench_seismic.format_table(res)


def test_amplitude_cube_spans_the_bounds():
    v, o, d = bench_seismic.amplitude_cube((0, 100, 0, 50, -20, 0), (11, 6, 5))
    assert v.shape == (11, 6, 5) and v.dtype == np.float32
    np.testing.assert_allclose(np.array(o) + np.array(d) * (np.array(v.shape) - 1), (100, 50, 0))
    gc.Volume(v, origin=o, spacing=d, order="xyz")
