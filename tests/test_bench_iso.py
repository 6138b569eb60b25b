"""``python -m geocull bench --scene iso`` on a tiny configuration: rows side by side, implicit == none."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest


def test_bench_iso_tiny_json(tmp_path):
    pytest.importorskip("pyvista")
    out = tmp_path / "bench_iso.json"
    env = dict(os.environ, GEOCULL_BENCH_TINY="1", VTK_DEFAULT_OPENGL_WINDOW="vtkEGLRenderWindow")
    p = subprocess.run(
        [sys.executable, "-m", "geocull", "bench", "--scene", "iso", "--quick", "--json", str(out)],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    assert "bench[iso]" in p.stderr and "x none" in p.stdout
    d = json.loads(out.read_text())
    rows, s = d["rows"], d["summary"]
    assert s["mode"] == "tiny" and s["views"] == 1 and s["n"] == 24
    keys = [(r["method"], r["temperature"]) for r in rows]
    assert sorted(keys) == sorted((m, t) for m in ("none", "implicit", "oracle", "pyvista") for t in ("cold", "warm"))
    for r in rows:
        assert r["total_ms"] > 0 and r["ratio_to_none"] > 0 and r["faces"] > 0
        # cores busy: the process's CPU time over the call's wall time, at most the machine's cores
        if r["method"] == "oracle" or (r["method"], r["temperature"]) == ("pyvista", "cold"):
            assert r["cores"] is None
        else:
            assert 0.0 < r["cores"] <= (os.cpu_count() or 1) + 0.5, r
        if r["method"] in ("implicit", "oracle"):
            assert r["differing_pixel_fraction"] == 0.0  # conservative
            assert r["faces"] <= rows[keys.index(("none", r["temperature"]))]["faces"]
        if r["method"] == "oracle":  # the fewest cells a conservative culling of cells can draw
            assert r["faces"] <= rows[keys.index(("implicit", r["temperature"]))]["faces"]
            assert r["walk"] == "none" and r["readbacks"] == 0
        if r["method"] == "implicit":
            # the compute walk reads its marks back; the host's walk (on a CPU adapter) needs none
            assert r["walk"] in ("gpu", "cpu") and r["readbacks"] == (1 if r["walk"] == "gpu" else 0)
            # the host's walk counts its rays and steps (the GPU's does not)
            assert (r["walk_steps"] >= r["walk_rays"] > 0) if r["walk"] == "cpu" else r["walk_steps"] == 0
        if r["method"] == "pyvista":  # VTK flying edges: the same surface within 2 %
            assert abs(r["faces_ratio"] - 1.0) < 0.02
    assert s["per_method"]["pesco/none_cold"]["ratio_to_none"] == 1.0
