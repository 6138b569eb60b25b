"""Reservoir corner-point grids in: the Eclipse pillar layout (GRDECL COORD / ZCORN / ACTNUM) and
xtgeo ``Grid`` objects, as the arrays geocull's reservoir grids take.

``from_grdecl``  COORD, ZCORN (, ACTNUM) -> ``dict(corners=..., active=...)``
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

Only numpy is needed; xtgeo is imported by nothing here (``from_xtgeo`` reads the object it is
given through :func:`geocull.io.from_xtgeo_grid`).
"""

from __future__ import annotations

from typing import Any, Literal, TypedDict

import numpy as np

from ._convert import float_array, integer
from ._errors import InputError
from .io import GridKwargs, from_xtgeo_grid

__all__ = ["from_grdecl", "from_xtgeo", "CornerArrays", "GridInput"]


class CornerArrays(TypedDict):
    """What :func:`from_grdecl` returns: corners (nk, nj, ni, 8, 3) float64 and active (nk, nj, ni)."""

    corners: np.ndarray
    active: np.ndarray


#: What :func:`from_xtgeo` returns: corners, active and values (or None) of one grid, the same
#: keys as :func:`geocull.io.from_xtgeo_grid` (keyword arguments of ``Scene.add_grid``).
GridInput = GridKwargs


def _zsign(z_positive: str) -> float:
    if z_positive not in ("up", "down"):
        raise InputError(f"z_positive: {z_positive!r}; expected 'up' or 'down'")
    return -1.0 if z_positive == "down" else 1.0


def from_grdecl(
    coord: Any,
    zcorn: Any,
    actnum: Any = None,
    *,
    nx: int,
    ny: int,
    nz: int | None = None,
    z_positive: Literal["up", "down"] = "down",
) -> CornerArrays:
    """Corner-point arrays from Eclipse's pillar layout (the GRDECL keywords, as numbers).

    coord: COORD, (ny+1) * (nx+1) pillars of 6 floats (any shape of that size), pillar (i, j) at
        index ``j * (nx+1) + i``: x, y, z of its top point, then of its bottom point. A corner at
        depth d on a pillar lies where the pillar's line reaches d (a vertical pillar, top z =
        bottom z, gives its top x, y).
    zcorn: ZCORN, 8 * nx * ny * nz depths in Eclipse order: for each layer its top then its base;
        in each, for each row j the corners at j-bit 0 then 1; in each, for each i the corners at
        i-bit 0 then 1 (i fastest).
    actnum: ACTNUM, nx * ny * nz ints (i fastest) or None = all active.
    nx, ny: cells along i and j; nz: layers (default: from the length of ``zcorn``).

    Returns ``dict(corners=(nz, ny, nx, 8, 3), active=(nz, ny, nx))`` in the corner order of the
    module docstring, z = -depth for ``z_positive="down"``.
    """
    sign = _zsign(z_positive)
    nx = integer(nx, "nx")
    ny = integer(ny, "ny")
    if nx < 1 or ny < 1:
        raise InputError(f"nx, ny: ({nx}, {ny}) must be at least 1")
    c = float_array(coord, "coord", np.ndim(coord)).reshape(-1)
    if c.size != 6 * (nx + 1) * (ny + 1):
        raise InputError(f"coord: {c.size} values, expected 6 * (nx+1) * (ny+1) = {6 * (nx + 1) * (ny + 1)}")
    z = float_array(zcorn, "zcorn", np.ndim(zcorn)).reshape(-1)
    if nz is None:
        if z.size % (8 * nx * ny) != 0:
            raise InputError(f"zcorn: {z.size} values is not a multiple of 8 * nx * ny = {8 * nx * ny}")
        nz = z.size // (8 * nx * ny)
    nz = integer(nz, "nz")
    if nz < 1 or z.size != 8 * nx * ny * nz:
        raise InputError(f"zcorn: {z.size} values, expected 8 * nx * ny * nz = {8 * nx * ny * max(nz, 0)}")
    # (k, kbit, j, jbit, i, ibit) -> (k, j, i, kbit, jbit, ibit) -> corner c = 4 kbit + 2 jbit + ibit.
    depth = z.reshape(nz, 2, ny, 2, nx, 2).transpose(0, 2, 4, 1, 3, 5).reshape(nz, ny, nx, 8)
    pil = c.reshape(ny + 1, nx + 1, 6)
    cbits = np.arange(8)
    pi = np.arange(nx)[None, :, None] + (cbits & 1)[None, None, :]  # (1, nx, 8)
    pj = np.arange(ny)[:, None, None] + ((cbits >> 1) & 1)[None, None, :]  # (ny, 1, 8)
    p = pil[pj, pi]  # (ny, nx, 8, 6): each corner's pillar
    top, bot = p[..., 0:3], p[..., 3:6]
    dz = bot[..., 2] - top[..., 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(dz != 0.0, (depth - top[None, ..., 2]) / np.where(dz != 0.0, dz, 1.0)[None], 0.0)
    corners = np.empty((nz, ny, nx, 8, 3))
    corners[..., 0] = top[None, ..., 0] + t * (bot[None, ..., 0] - top[None, ..., 0])
    corners[..., 1] = top[None, ..., 1] + t * (bot[None, ..., 1] - top[None, ..., 1])
    corners[..., 2] = sign * depth
    if actnum is None:
        active = np.ones((nz, ny, nx), dtype=bool)
    else:
        a = np.asarray(actnum).reshape(-1)
        if a.size != nx * ny * nz:
            raise InputError(f"actnum: {a.size} values, expected nx * ny * nz = {nx * ny * nz}")
        active = a.reshape(nz, ny, nx) != 0
    return CornerArrays(corners=corners, active=active)


def from_xtgeo(grid: Any, property: Any = None, z_positive: Literal["up", "down"] = "down") -> GridInput:
    """An xtgeo ``Grid`` as ``dict(corners=..., active=..., values=...)``, keyword arguments of
    ``Scene.add_grid``: ``scene.add_grid(**from_xtgeo(grid, "PORO"), name="Reek")``.

    :func:`geocull.io.from_xtgeo_grid` itself (same keys, same corner order, z = -depth metres for
    ``z_positive="down"``): ``property`` is a property name of ``grid`` or an
    ``xtgeo.GridProperty``, whose values ((nk, nj, ni); masked / inactive / undefined cells NaN)
    become ``values``; None gives ``values=None``.
    """
    return from_xtgeo_grid(grid, values=property, z_positive=z_positive)
