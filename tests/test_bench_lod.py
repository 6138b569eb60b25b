"""``python -m geocull bench --scene lod`` on a tiny configuration: the tiles read back from
``Scene.to_bytes`` are the scene's (``tile_table``'s counts), geocull's levels keep the fine vertices
(meshoptimizer removes, never moves), fast-simplification reaches about the same counts, and the
distances are exact on a case known by hand. Skipped without fast-simplification or PyVista (the
``bench`` extra)."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

pytest.importorskip("fast_simplification", reason="bench --scene lod's baseline: pip install 'geocull[bench]'")
pytest.importorskip("pyvista", reason="bench --scene lod's distances: pip install 'geocull[bench]'")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

from geocull.bench import cli, lod  # noqa: E402


def test_surface_distance_and_level_error_by_hand():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    d = lod.surface_distance(np.array([[0.5, 0.5, 2.0], [2.0, 0.5, 0.0], [0.25, 0.75, -0.5]]), square, faces)
    np.testing.assert_allclose(d, [2.0, 1.0, 0.5], atol=1e-9)
    lifted = square + [0, 0, 0.25]
    mx, mean = lod.level_error(square, faces, lifted, faces)
    assert mx == pytest.approx(0.25) and mean == pytest.approx(0.25)


def test_scene_tiles_match_the_tile_table():
    scene, build_s, n_fine = lod.build_scene(lod.lod_config("tiny"))
    tiles = lod.scene_tiles(scene)
    table = scene.tile_table()
    assert build_s > 0 and n_fine == scene.n_triangles == sum(len(t["fine"]) for t in tiles)
    assert [len(t["fine"]) for t in tiles] == table["tris_fine"].tolist()
    for t, row in zip(tiles, table, strict=True):
        counts = [len(ix) for _, ix in t["levels"]]
        assert counts == row["level_triangles"][1:len(counts) + 1].tolist() and len(counts) >= 1
        np.testing.assert_allclose([e for e, _ in t["levels"]], row["level_error"][1:len(counts) + 1], rtol=1e-6)
        fine_vertices = set(np.unique(t["fine"]).tolist())
        for _, ix in t["levels"]:
            assert set(np.unique(ix).tolist()) <= fine_vertices  # simplified by removing vertices only
    bounds = scene.bounds
    assert bounds is not None
    (x0, y0, z0), _ = bounds
    heightfield = scene.add_heightfield(np.full((9, 9), z0), origin=(x0, y0), spacing=(1, 1))
    assert all(t["object"] != heightfield for t in lod.scene_tiles(scene))  # lattice levels are not read


def test_bench_lod_tiny_json(tmp_path, capsys):
    out = tmp_path / "lod.json"
    assert cli.main(["--scene", "lod", "--tiny", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "meshoptimizer (geocull)" in text and "fast-simplification, border kept" in text
    res = json.loads(out.read_text())
    s, rows = res["summary"], res["rows"]
    assert s["n_tiles"] >= 3 and s["geocull_add_mesh_s"] > 0 and s["geocull_add_mesh_1thread_s"] > 0
    assert {r["method"] for r in rows} == set(lod.METHODS)
    for r in rows:
        assert r["max_error_m"] >= r["mean_error_m"] >= 0
        if r["method"] == lod.METHODS[0]:
            assert r["triangles"] == r["target_triangles"] and r["max_error_m"] > 0 and r["seconds"] is None
        else:  # fast-simplification lands near the same counts
            assert abs(r["triangles"] / r["target_triangles"] - 1) < 0.25 and r["seconds"] >= 0
