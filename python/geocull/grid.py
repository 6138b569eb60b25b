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

from typing import Any, Literal, TypedDict

import numpy as np

from ._convert import float_array, integer
from ._errors import InputError
from .io import GridKwargs, from_xtgeo_grid

__all__ = ["from_grdecl", "from_xtgeo", "mapaxes_transform", "CornerArrays", "GridInput"]


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
    mapaxes: Any = None,
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
    mapaxes: MAPAXES, 6 numbers ``(X1, Y1, X2, Y2, X3, Y3)`` (any shape of that size, e.g. (3, 2)):
        a point on the local y axis, the origin, a point on the local x axis, world metres. COORD's
        x, y are then local: each pillar point moves to ``origin + x * ex + y * ey``
        (:func:`mapaxes_transform`; the module docstring has the convention). None: COORD is in
        world coordinates already. An InputError naming ``mapaxes`` for another size, non-finite
        numbers, an axis of zero length or two parallel axes.
    z_positive: "down" (default: ZCORN and COORD z are depths, drawn at z = -depth) or "up".

    Returns ``dict(corners=(nz, ny, nx, 8, 3), active=(nz, ny, nx))`` in the corner order of the
    module docstring, world metres, z = -depth for ``z_positive="down"``.
    """
    sign = _zsign(z_positive)
    axes = None if mapaxes is None else mapaxes_transform(mapaxes)
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
    if axes is not None:
        origin, ex, ey = axes
        pil = pil.copy()
        for col in (0, 3):  # the top and the bottom point of each pillar
            x, y = pil[..., col].copy(), pil[..., col + 1].copy()
            pil[..., col] = origin[0] + x * ex[0] + y * ey[0]
            pil[..., col + 1] = origin[1] + x * ex[1] + y * ey[1]
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


def mapaxes_transform(mapaxes: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(origin, ex, ey)`` of Eclipse's MAPAXES ``(X1, Y1, X2, Y2, X3, Y3)`` (6 numbers, any shape
    of that size; world metres): the origin (X2, Y2) and the unit vectors ex towards (X3, Y3) and ey
    towards (X1, Y1), each a (2,) float64. A local (x, y) lies at ``origin + x * ex + y * ey``.

    InputError naming ``mapaxes``: not 6 finite numbers, a point on the origin (an axis of zero
    length) or the two axes parallel (the map would squash the grid onto a line)."""
    try:
        m = np.asarray(mapaxes, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"mapaxes: {mapaxes!r} is not 6 numbers (X1 Y1 X2 Y2 X3 Y3)") from None
    if m.size != 6:
        raise InputError(f"mapaxes: {m.size} values (shape {m.shape}); MAPAXES is 6 numbers X1 Y1 X2 Y2 X3 Y3 "
                         "(a point on the y axis, the origin, a point on the x axis)")
    m = m.reshape(3, 2)
    if not np.isfinite(m).all():
        raise InputError(f"mapaxes: {m.ravel().tolist()} holds a non-finite number")
    y_point, origin, x_point = m
    scale = max(1.0, float(np.abs(m).max()))
    ex, ey = x_point - origin, y_point - origin
    lx, ly = float(np.hypot(*ex)), float(np.hypot(*ey))
    for name, length in (("x", lx), ("y", ly)):
        if length <= 1e-9 * scale:
            raise InputError(f"mapaxes: the point on the {name} axis is the origin {origin.tolist()} "
                             f"({m.ravel().tolist()}): the axis has no direction")
    ex, ey = ex / lx, ey / ly
    if abs(float(ex[0] * ey[1] - ex[1] * ey[0])) < 1e-6:
        raise InputError(f"mapaxes: the x axis {ex.tolist()} and the y axis {ey.tolist()} are parallel "
                         f"({m.ravel().tolist()}): they would map the grid onto a line")
    return origin.copy(), ex, ey


def from_xtgeo(grid: Any, property: Any = None, z_positive: Literal["up", "down"] = "down") -> GridInput:
    """An xtgeo ``Grid`` as ``dict(corners=..., active=..., values=...)``, keyword arguments of
    ``Scene.add_grid``: ``scene.add_grid(**from_xtgeo(grid, "PORO"), name="Reek")``.

    :func:`geocull.io.from_xtgeo_grid` itself (same keys, same corner order, z = -depth metres for
    ``z_positive="down"``): ``property`` is a property name of ``grid`` or an
    ``xtgeo.GridProperty``, whose values ((nk, nj, ni); masked / inactive / undefined cells NaN)
    become ``values``; None gives ``values=None``.
    """
    return from_xtgeo_grid(grid, values=property, z_positive=z_positive)
