"""What :class:`geocull.Scene`'s ``add_heightfield``, ``add_mesh``, ``add_well`` and ``add_grid`` make
of their geometry arguments before the core checks their values: xtgeo objects read through
:mod:`geocull.io` (their origin, rotation, names, logs, properties; any argument given wins),
``z_positive="down"`` data mirrored to z up, and the arrays coerced by :mod:`geocull._convert`
in the order the methods always checked them (so the first bad argument is the one named)."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _convert as cv
from ._errors import InputError
from ._scene_colors import label_arg

__all__ = ["z_down", "heightfield_inputs", "mesh_inputs", "well_inputs", "grid_inputs"]


def z_down(z_positive: Any, default_down: bool) -> bool:
    """True for z_positive="down", False for "up", ``default_down`` for None; else InputError."""
    return default_down if z_positive is None else cv.z_sign(z_positive) < 0


def heightfield_inputs(
    z: Any, origin: Any, spacing: Any, rotation: Any, yflip: Any, null_value: Any, name: Any, z_positive: Any,
) -> tuple[np.ndarray, tuple[float, float], tuple[float, float], Any, Any, float | None, Any]:
    """``(heights, origin, spacing, rotation, yflip, null_value, name)`` of ``add_heightfield``:
    the heights (NaN holes, negated for z_positive="down", as is the null value they are compared
    with) and the checked origin and spacing; rotation, yflip and name with their defaults (an
    xtgeo surface's own), still to be checked."""
    from . import io

    surface = io.xtgeo_kind(z) == "surface"
    down = z_down(z_positive, surface)
    if surface:
        kw = io.from_xtgeo_surface(z, z_positive="down" if down else "up")
        name = io.xtgeo_name(z) if name is None else name
        z = kw["z"]
        origin = kw["origin"] if origin is None else origin
        spacing = kw["spacing"] if spacing is None else spacing
        rotation = kw["rotation"] if rotation is None else rotation
        yflip = kw["yflip"] if yflip is None else yflip
    elif down:
        data, mask = cv.unmasked(z, "z")
        neg = -cv.checked_array(data, "z", 2)
        z = neg if mask is None else np.ma.MaskedArray(neg, mask=mask)
    nv = None if null_value is None else cv.number(null_value, "null_value")
    if nv is not None and down:
        nv = -nv  # compared with the negated heights
    origin = (0.0, 0.0) if origin is None else origin
    spacing = (1.0, 1.0) if spacing is None else spacing
    rotation = 0.0 if rotation is None else rotation
    yflip = False if yflip is None else yflip
    za = cv.heights(z, nv)
    return za, cv.vec2(origin, "origin"), cv.vec2(spacing, "spacing"), rotation, yflip, nv, name


def mesh_inputs(
    vertices: Any, faces: Any, name: Any, color: Any, z_positive: Any,
) -> tuple[np.ndarray, np.ndarray, Any, Any]:
    """``(vertices, faces, name, color)`` of ``add_mesh``: (n, 3) float64 vertices and (m, 3) int64
    faces from arrays or a mesh object (trimesh, PyVista, xtgeo TriangulatedSurface, whose name
    and colour are the defaults), mirrored with each face's order reversed for z_positive="down"."""
    from . import io

    trisurf = io.xtgeo_kind(vertices) == "trisurface"
    down = z_down(z_positive, trisurf)
    mesh = cv.mesh_arrays(vertices) if not trisurf else None
    if trisurf:
        if faces is not None:
            raise InputError("faces: must be omitted when vertices is an xtgeo TriangulatedSurface")
        name = io.xtgeo_name(vertices) if name is None else name
        ts: Any = vertices
        vertices, faces = np.asarray(ts.vertices), np.asarray(ts.triangles)
    elif mesh is not None:
        if faces is not None:
            raise InputError(f"faces: must be omitted when vertices is a {type(vertices).__name__}")
        vertices, faces = mesh.vertices, mesh.faces
        name = mesh.name if name is None else name
        color = mesh.color if color is None else color
    elif faces is None:
        raise InputError("faces: required with a vertex array (or pass a trimesh.Trimesh / pyvista.PolyData)")
    v = cv.vertices(vertices)
    f = cv.int_array(faces, "faces", 2, 3)
    if f.dtype.kind == "u" and f.size and f.max() > np.iinfo(np.int64).max:
        raise InputError("faces: index too large")
    f = np.ascontiguousarray(f, dtype=np.int64)
    if down:  # z = -depth: a mirror, so each face's order is reversed to keep its normal's side
        v = v * np.array([1.0, 1.0, -1.0])
        f = np.ascontiguousarray(f[:, ::-1])
    return v, f, name, color


def well_inputs(
    path: Any, values: Any, label: Any, log: Any, max_stations: Any, name: Any, z_positive: Any,
) -> tuple[np.ndarray, Any, str | None, Any]:
    """``(path, values, label, name)`` of ``add_well``: (n, 3) float64 stations (z up) from an
    array or an ``xtgeo.Well`` (its log ``log`` as the values, its name), and the colour bar label."""
    from . import io

    well = io.xtgeo_kind(path) == "well"
    down = z_down(z_positive, well)
    lab = label_arg(label, values)
    if well:
        kw = io.from_xtgeo_well(path, log=log, max_stations=max_stations, z_positive="down" if down else "up")
        name = io.xtgeo_name(path) if name is None else name
        if values is None and lab is None and isinstance(log, str):
            lab = log
        values = kw["values"] if values is None else values
        p = cv.float_array(kw["path"], "path", 2, 3)
    else:
        for arg, x in (("log", log), ("max_stations", max_stations)):
            if x is not None:
                raise InputError(f"{arg}: only with an xtgeo Well as path (got {type(path).__name__})")
        p = cv.float_array(path, "path", 2, 3)
        if down:
            p = p * np.array([1.0, 1.0, -1.0])
    return p, values, lab, name


def grid_inputs(
    corners: Any, active: Any, region: Any, values: Any, label: Any, name: Any, z_positive: Any,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, Any, str | None, Any]:
    """``(corners, active, region, values, label, name)`` of ``add_grid``: float64 corners (z up),
    bool active flags and int32 region ids (None where not given) from arrays or an ``xtgeo.Grid``
    (its ACTNUM, its name), ``values`` and ``region`` read from xtgeo GridProperties or property
    names, and the colour bar label."""
    from . import io

    grid = io.xtgeo_kind(corners) == "grid"
    down = z_down(z_positive, grid)
    if grid:
        kw = io.from_xtgeo_grid(corners, values=None, z_positive="down" if down else "up")
        name = io.xtgeo_name(corners) if name is None else name
        active = kw["active"] if active is None else active
        xgrid: Any = corners
        corners = kw["corners"]
    else:
        xgrid = None
        if down:
            data, mask = cv.unmasked(corners, "corners")
            corners = cv.float_array(data, "corners", 5) * np.array([1.0, 1.0, -1.0])
            if mask is not None:
                corners = np.ma.MaskedArray(corners, mask=mask)
    lab = label_arg(label, values)
    if isinstance(values, str) or io.xtgeo_kind(values) == "gridproperty":
        if lab is None and isinstance(values, str):
            lab = values
        values = io.xtgeo_property(values, xgrid, "values")
    if isinstance(region, str) or io.xtgeo_kind(region) == "gridproperty":
        r = io.xtgeo_property(region, xgrid, "region")
        region = np.where(np.isfinite(r), r, -1).astype(np.int64)
    data, mask = cv.unmasked(corners, "corners")
    if mask is not None:
        raise InputError("corners: masked corners are not supported; mark their cells inactive")
    c = cv.float_array(data, "corners", 5)
    act = None if active is None else cv.flags(active, "active", 3)
    reg = None
    if region is not None:
        r = cv.int_array(region, "region", 3)
        if r.size and (r.min() < np.iinfo(np.int32).min or r.max() > np.iinfo(np.int32).max):
            raise InputError("region: ids must fit int32")
        reg = np.ascontiguousarray(r, dtype=np.int32)
    return c, act, reg, values, lab, name
