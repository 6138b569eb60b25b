"""The Reek files (``../shared/data/reek``, Equinor's xtgeo test data) go in with one call each
(issue 37): a rotated IRAP horizon, the EGRID grid coloured by porosity, an RMS well coloured by
its Poro log; no far-apart warning (they share UTM coordinates); the horizon's vertices lie at
xtgeo's node positions at z = -depth; the grid's porosity is xtgeo's on active cells (NaN elsewhere);
the well's stations are xtgeo's at z = -TVDSS.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import geocull as gc

xtgeo = pytest.importorskip("xtgeo")
REEK = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "reek"
pytestmark = pytest.mark.skipif(not REEK.is_dir(), reason="../shared/data/reek not present")


def test_reek_sources_one_call_each():
    top = xtgeo.surface_from_file(REEK / "surfaces" / "topreek_rota.gri")
    grid = xtgeo.grid_from_file(REEK / "grid" / "REEK.EGRID")
    poro = xtgeo.gridproperty_from_file(REEK / "grid" / "reek_sim_poro.grdecl", grid=grid, name="PORO")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # xtgeo's own pandas deprecations
        well = xtgeo.well_from_file(REEK / "wells" / "OP_1.w")
    s = gc.Scene()
    with warnings.catch_warnings():
        warnings.simplefilter("error", gc.GeocullWarning)
        h = s.add_heightfield(top, tiles=(4, 4), name="TopReek")
        g = s.add_grid(grid, values=poro)
        w = s.add_well(well, log="Poro", max_stations=400)
    # horizon: node (i, j) where xtgeo puts it, at z = -depth
    v, _ = s.geometry(h)
    t = np.radians(top.rotation)
    d = v[:, :2] - (top.xori, top.yori)
    fi = (d[:, 0] * np.cos(t) + d[:, 1] * np.sin(t)) / top.xinc
    fj = (-d[:, 0] * np.sin(t) + d[:, 1] * np.cos(t)) / (top.yinc * top.yflip)
    i, j = np.rint(fi).astype(int), np.rint(fj).astype(int)
    assert np.abs(fi - i).max() < 1e-3 and np.abs(fj - j).max() < 1e-3  # every vertex on a node
    depth = top.values[i, j]
    assert not np.ma.getmaskarray(depth).any()  # ... a defined one
    np.testing.assert_allclose(v[:, 2], -np.ma.getdata(depth), atol=1e-3)
    assert len(np.unique(i * top.nrow + j)) > 0.95 * (~np.ma.getmaskarray(top.values)).sum()
    # grid: the porosity of the active cells, (nk, nj, ni), inactive NaN; the grid object as the
    # arrays give it (boundary faces coloured by their cells: a colour range within porosity's)
    values = gc.io.xtgeo_property(poro, grid)
    active = np.asarray(grid.get_actnum().values).transpose(2, 1, 0) != 0
    np.testing.assert_array_equal(values[active], np.ma.getdata(poro.values).transpose(2, 1, 0)[active])
    assert np.isnan(values[~active]).all()
    ref = gc.Scene()
    r = ref.add_grid(**gc.grid.from_xtgeo(grid, poro))
    np.testing.assert_array_equal(ref.geometry(r)[0], s.geometry(g)[0])
    lo_c, hi_c = s.object_info(g)["clim"]
    assert (lo_c, hi_c) == ref.object_info(r)["clim"]
    assert np.nanmin(values) * (1 - 1e-6) <= lo_c < hi_c <= np.nanmax(values) * (1 + 1e-6)  # f32 colour range
    # well: xtgeo's stations at z = -TVDSS, named
    assert s.object_info(w)["name"] == "OP_1"
    df = well.get_dataframe()
    path = gc.io.from_xtgeo_well(well)["path"]
    np.testing.assert_allclose(path, np.c_[df["X_UTME"], df["Y_UTMN"], -df["Z_TVDSS"]])
    lo, hi = s.bounds
    assert -2000.0 < lo[2] < -1600.0 and hi[2] < 20.0
