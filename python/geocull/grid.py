"""Reservoir corner-point grids in: the Eclipse pillar layout (GRDECL COORD / ZCORN / ACTNUM) and
xtgeo ``Grid`` objects, as the arrays geocull's reservoir grids take.

``from_grdecl``  COORD, ZCORN (, ACTNUM, MAPAXES) -> ``dict(corners=..., active=...)``
``mapaxes_transform``  MAPAXES -> (origin, x axis, y axis) of the local -> world map
``from_xtgeo``   an xtgeo Grid (, a property) -> ``dict(corners=..., active=..., values=...)``, the
                 keyword arguments of ``Scene.add_grid`` (as :func:`geocull.io.from_xtgeo_grid`)

Conventions (the same everywhere in geocull):

- ``corners`` has shape (nk, nj, ni, 8, 3), float64 world (x, y, z); corner c of a cell has i-bit
  ``c & 1``, j-bit ``(c >> 1) & 1``, k-bit ``(c >> 2) & 1`` (k-bit 0 = the cell's top), so c = 0..3
  is the top face at (i, j), (i+1, j), (i, j+1), (i+1, j+1) and c = 4..7 the base in the same
  order; k = 0 is the top layer. Eclipse and xtgeo's nx, ny, nz are ni, nj, nk.
- **z up**: Eclipse depths grow downwards, so with ``z_positive="down"`` (the default) a depth d
  becomes z = -d; pass ``z_positive="up"`` for files that hold elevations.
- ``active`` has shape (nk, nj, ni), bool (ACTNUM != 0); ``values`` (nk, nj, ni) float64 with
  inactive / masked cells NaN.
- **MAPAXES** (Eclipse): 6 numbers X1 Y1 X2 Y2 X3 Y3, a point on the local y axis, the origin, a
  point on the local x axis, in world (map) coordinates. A local (x, y) lies at
  ``origin + x * ex + y * ey`` with ex, ey the *unit* vectors from the origin towards the two points
  (no scaling: the points' distances from the origin do not matter; axes need not be perpendicular,
  and a y axis clockwise of the x axis mirrors the grid), as Eclipse, resdata and xtgeo apply it.
  Without MAPAXES the COORD values are world coordinates already.

Only numpy is needed; xtgeo is imported by nothing here (``from_xtgeo`` reads the object it is
given through :func:`geocull.io.from_xtgeo_grid`).
"""

from __future__ import annotations

from typing import Any, Literal

# The GRDECL pillar geometry lives with the GRDECL reader (``_grdecl``); this is its public face.
from ._grdecl import CornerArrays, from_grdecl, mapaxes_transform
from .io import GridKwargs, from_xtgeo_grid

__all__ = ["from_grdecl", "from_xtgeo", "mapaxes_transform", "CornerArrays", "GridInput"]


#: What :func:`from_xtgeo` returns: corners, active and values (or None) of one grid, the same
#: keys as :func:`geocull.io.from_xtgeo_grid` (keyword arguments of ``Scene.add_grid``).
GridInput = GridKwargs


def from_xtgeo(grid: Any, property: Any = None, z_positive: Literal["up", "down"] = "down") -> GridInput:
    """An xtgeo ``Grid`` as ``dict(corners=..., active=..., values=...)``, keyword arguments of
    ``Scene.add_grid``: ``scene.add_grid(**from_xtgeo(grid, "PORO"), name="Reek")``.

    :func:`geocull.io.from_xtgeo_grid` itself (same keys, same corner order, z = -depth metres for
    ``z_positive="down"``): ``property`` is a property name of ``grid`` or an
    ``xtgeo.GridProperty``, whose values ((nk, nj, ni); masked / inactive / undefined cells NaN)
    become ``values``; None gives ``values=None``.
    """
    return from_xtgeo_grid(grid, values=property, z_positive=z_positive)
