"""Depth conventions and far-apart objects (issue 37).

What is checked:
- ``z_positive="down"`` on ``add_well`` and ``add_grid`` with arrays draws z = -depth (the same
  triangles as negated input, for grids also for masked corners' data), the default "up" keeps
  today's behaviour; a bad value is an InputError naming ``z_positive``;
- a ``GeocullWarning`` (a UserWarning, ``gc.GeocullWarning``) when an object is added over 1,000 km
  from another (a grid in local coordinates beside a UTM horizon), naming both objects; none for
  neighbours 900 km apart or on ordinary scenes.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import geocull as gc


def box_corners(x0: float, y0: float, z0: float, ni: int = 3, nj: int = 2, nk: int = 2, d: float = 10.0):
    """(nk, nj, ni, 8, 3) corners of a regular box grid, z0 the top, cells d metres, z growing with k."""
    k, j, i = np.meshgrid(np.arange(nk), np.arange(nj), np.arange(ni), indexing="ij")
    c = np.empty((nk, nj, ni, 8, 3))
    for corner in range(8):
        c[..., corner, 0] = x0 + (i + (corner & 1)) * d
        c[..., corner, 1] = y0 + (j + ((corner >> 1) & 1)) * d
        c[..., corner, 2] = z0 + (k + ((corner >> 2) & 1)) * d
    return c


def test_z_positive_on_wells_and_grids():
    path = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 500.0], [30.0, 5.0, 1200.0]])
    s = gc.Scene()
    up = s.add_well(path, radius=2.0)
    down = s.add_well(path, radius=2.0, z_positive="down")
    neg = s.add_well(path * (1, 1, -1), radius=2.0)
    np.testing.assert_array_equal(s.geometry(down)[0], s.geometry(neg)[0])
    assert s.geometry(up)[0][:, 2].max() > 1200.0 and s.geometry(down)[0][:, 2].min() < -1200.0
    depth = box_corners(0.0, 0.0, 1500.0)  # depths: the top layer at 1500 m, the base deeper
    g_down = s.add_grid(depth, z_positive="down", blocks=(2, 2))
    mirrored = depth.copy()
    mirrored[..., 2] *= -1
    g_ref = s.add_grid(mirrored, blocks=(2, 2))
    va, fa = s.geometry(g_down)
    vb, fb = s.geometry(g_ref)
    np.testing.assert_array_equal(va, vb)
    np.testing.assert_array_equal(fa, fb)
    assert va[:, 2].min() == pytest.approx(-1520.0) and va[:, 2].max() == pytest.approx(-1500.0)
    for f in (lambda: s.add_well(path, z_positive="depth"), lambda: s.add_grid(depth, z_positive=1)):
        with pytest.raises(gc.InputError, match="^z_positive"):
            f()


def test_objects_over_1000_km_apart_warn_naming_both():
    assert issubclass(gc.GeocullWarning, UserWarning)
    s = gc.Scene()
    y, x = np.mgrid[0:20, 0:30]
    s.add_heightfield(-1700.0 + np.sin(x / 5.0), origin=(461_000.0, 5_930_000.0), spacing=(25.0, 25.0),
                      name="TopReek")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # neighbours: silence
        s.add_well([[461_100.0, 5_930_100.0, 0.0], [461_200.0, 5_930_200.0, -1800.0]], name="OP_1")
        s.add_mesh([[1_361_000.0, 5_930_000.0, 0.0], [1_361_100.0, 5_930_000.0, 0.0],
                    [1_361_000.0, 5_930_100.0, 0.0]], [[0, 1, 2]], name="900 km east")
    # A grid in local coordinates (MAPAXES not applied): thousands of km from all three; the
    # farthest is named, with the gap between the two boxes.
    gap = np.hypot(np.hypot(1_361_000.0 - 30.0, 5_930_000.0 - 20.0), 0.0 - -1580.0) / 1000
    want = f"object 3 (grid, 'local grid') lies {gap:,.0f} km from object 2 (mesh, '900 km east')"
    assert want.startswith("object 3 (grid, 'local grid') lies 6,084 km")
    with pytest.warns(gc.GeocullWarning) as rec:
        gid = s.add_grid(box_corners(0.0, 0.0, -1600.0), name="local grid")
    assert len(rec) == 1 and str(rec[0].message).startswith(want)
    assert s.object_ids() == [0, 1, 2, gid] and gid == 3  # added all the same
