"""Meshes in and out (issue 16): ``Scene.add_mesh`` takes a ``trimesh.Trimesh`` or a ``pyvista.PolyData``
in place of (vertices, faces); ``gc.io.to_trimesh`` / ``gc.io.to_pyvista`` give objects back; the public
helpers ``gc.data.grid_faces`` and ``Scene.bounds``.

What is checked:
- trimesh: a Trimesh goes in with its vertices and faces unchanged, comes out (``to_trimesh``) with
  the same arrays, name / kind / colour, and goes back in identically (round trip);
- PyVista: triangle PolyData as they are; quads and strips triangulated; line and vertex cells
  ignored with a GeocullWarning; an UnstructuredGrid reduced to its surface; ``to_pyvista`` ->
  ``add_mesh`` round-trips geometry, name and colour; faces given with a mesh object is an error;
- neither package is imported by geocull unless such an object is used (a duck-typed stand-in
  works; ``import geocull.io`` imports no optional dependency);
- ``grid_faces`` (two triangles per cell, row-major) on a fault plane, and its argument check;
- ``Scene.bounds``: world, hidden objects included, offsets applied, None for an empty scene.
"""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import geocull as gc


def test_trimesh_in_out_round_trip():
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.creation.icosphere(subdivisions=2, radius=50.0)
    m.apply_translation((456_000.0, 6_780_000.0, -1500.0))
    s = gc.Scene()
    oid = s.add_mesh(m, kind="fault", name="F1", color=(0.9, 0.1, 0.1), tiles=4)
    v, f = s.geometry(oid)
    assert s.n_triangles == len(m.faces)
    # the same triangles (geometry() lists them tile by tile, positions stored as float32 about the
    # scene origin): compare the sorted triangle centres to a millimetre
    def centres(vv, ff):
        c = np.round(np.asarray(vv)[np.asarray(ff)].mean(axis=1), 3)
        return c[np.lexsort(c.T)]

    np.testing.assert_allclose(centres(v, f), centres(m.vertices, m.faces), atol=2e-3)
    out = gc.io.to_trimesh(s, oid)
    assert isinstance(out, trimesh.Trimesh)
    np.testing.assert_array_equal(out.vertices, v)
    np.testing.assert_array_equal(out.faces, f)
    assert out.metadata["name"] == "F1" and out.metadata["kind"] == "fault"
    rgb = s.object_info(oid)["color"]
    assert tuple(out.visual.face_colors[0]) == (*(round(255 * c) for c in rgb), 255)
    back = s.add_mesh(out)
    v2, f2 = s.geometry(back)
    np.testing.assert_array_equal(v2, v)
    np.testing.assert_array_equal(f2, f)
    assert abs(out.area - m.area) < 1e-6 * m.area


def test_pyvista_polydata_in_out():
    pv = pytest.importorskip("pyvista")
    s = gc.Scene()
    sphere = pv.Sphere(radius=10.0, center=(100.0, 200.0, -50.0))
    oid = s.add_mesh(sphere)
    assert s.n_triangles == sphere.n_cells
    v, f = s.geometry(oid)
    want = np.asarray(sphere.points, np.float64)[sphere.regular_faces].reshape(-1, 3)
    np.testing.assert_allclose(np.sort(v[f].reshape(-1, 3), axis=0), np.sort(want, axis=0), atol=1e-9)
    plane = pv.Plane(i_resolution=4, j_resolution=3)  # 12 quads
    assert s.object_info(s.add_mesh(plane))["n_triangles"] == 24
    strip = pv.PolyData(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 2, 0.0]]), strips=[5, 0, 1, 2, 3, 4])
    assert s.object_info(s.add_mesh(strip))["n_triangles"] == 3
    mixed = pv.PolyData(sphere.points, faces=sphere.faces, lines=[2, 0, 1])
    with pytest.warns(gc.GeocullWarning, match="1 line and 0 vertex cells are ignored"):
        lid = s.add_mesh(mixed)
    assert s.object_info(lid)["n_triangles"] == sphere.n_cells
    ug = pv.Cube().cast_to_unstructured_grid()
    assert s.object_info(s.add_mesh(ug))["n_triangles"] == 12
    # out and back: geometry, name and colour
    s.set_color(oid, (0.2, 0.4, 0.6))
    pd = gc.io.to_pyvista(s, oid)
    assert isinstance(pd, pv.PolyData) and str(pd.field_data["kind"][0]) == "mesh"
    again = s.add_mesh(pd)
    np.testing.assert_array_equal(s.geometry(again)[0], s.geometry(oid)[0])
    np.testing.assert_array_equal(s.geometry(again)[1], s.geometry(oid)[1])
    info = s.object_info(again)
    assert info["name"] == s.object_info(oid)["name"]
    np.testing.assert_allclose(info["color"], (0.2, 0.4, 0.6), atol=1e-6)
    with pytest.raises(gc.InputError, match="^faces: must be omitted when vertices is a PolyData"):
        s.add_mesh(pd, np.zeros((1, 3), int))
    with pytest.raises(gc.InputError, match="^faces: required with a vertex array"):
        s.add_mesh(np.zeros((3, 3)))


def test_duck_typing_imports_nothing():
    class Faces:  # anything with vertices and faces, as trimesh.Trimesh
        vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
        faces = np.array([[0, 1, 2]])

    s = gc.Scene()
    assert s.object_info(s.add_mesh(Faces()))["n_triangles"] == 1
    code = ("import sys, numpy as np, geocull as gc, geocull.io; s = gc.Scene(); "
            "s.add_mesh(np.eye(3), [[0, 1, 2]]); s.add_heightfield(np.zeros((2, 2))); "
            "bad = [m for m in ('trimesh', 'pyvista', 'vtk', 'xtgeo', 'segyio', 'xarray') if m in sys.modules]; "
            "print(bad); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_grid_faces_for_fault_planes():
    nu, nv = 5, 4  # a fault plane sampled as (nv, nu, 3) points
    u, w = np.meshgrid(np.linspace(0, 400, nu), np.linspace(0, -300, nv))
    pts = np.stack([u, 0.2 * w, w], axis=-1)
    f = gc.data.grid_faces(nu, nv)
    assert f.shape == (2 * (nu - 1) * (nv - 1), 3) and f.dtype == np.int64
    np.testing.assert_array_equal(f[:2], [[0, 1, 6], [0, 6, 5]])
    s = gc.Scene()
    oid = s.add_mesh(pts.reshape(-1, 3), f, kind="fault")
    assert s.object_info(oid)["kind"] == "fault" and s.n_triangles == len(f)
    with pytest.raises(gc.InputError, match="at least 2 x 2"):
        gc.data.grid_faces(1, 5)


def test_scene_bounds():
    s = gc.Scene()
    assert s.bounds is None
    s.add_heightfield(np.full((2, 2), np.nan))
    assert s.bounds is None  # only holes: no triangle
    a = s.add_heightfield(np.array([[1.0, 2.0], [3.0, 4.0]]), origin=(450_000.0, 6_780_000.0), spacing=(10, 20))
    assert s.bounds == ((450_000.0, 6_780_000.0, 1.0), (450_010.0, 6_780_020.0, 4.0))
    m = s.add_mesh(np.array([[0.0, 0, -5], [1, 0, -5], [0, 1, 9]]) + (450_000.0, 6_780_000.0, 0), [[0, 1, 2]])
    s.set_visible(m, False)
    s.translate(a, (0.0, 0.0, 100.0))
    lo, hi = s.bounds
    assert lo == pytest.approx((450_000.0, 6_780_000.0, -5.0)) and hi == pytest.approx((450_010.0, 6_780_020.0, 104.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s.remove(m)
    assert s.bounds[0][2] == pytest.approx(101.0)
