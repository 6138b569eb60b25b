"""Geoscience data in and out: xtgeo surfaces, cubes and grids, SEG-Y cubes (segyio), trimesh and
PyVista meshes, each with its conventions translated, so that a scene needs no glue beyond a call.

>>> import geocull as gc, xtgeo
>>> scene = gc.Scene()
>>> scene.add_heightfield(**gc.io.from_xtgeo_surface(xtgeo.surface_from_file("top.gri")), tiles=(8, 8))
>>> vol = gc.Volume(**gc.io.from_xtgeo_cube(cube))          # or gc.Volume.from_segy("cube.sgy")
>>> scene.add_mesh(trimesh.load("fault.stl"), kind="fault")  # trimesh / PyVista meshes directly
>>> gc.io.to_trimesh(scene, 0).export("top.ply")

``from_xtgeo_surface``  xtgeo RegularSurface -> ``Scene.add_heightfield`` keyword arguments
``from_xtgeo_cube``     xtgeo Cube -> ``Volume`` keyword arguments
``from_xtgeo_grid``     xtgeo Grid -> corner-point arrays (corners, active, properties)
``from_segy``           a SEG-Y file -> ``Volume`` keyword arguments (``Volume.from_segy`` builds it)
``to_pyvista``          one scene object -> ``pyvista.PolyData``
``to_trimesh``          one scene object -> ``trimesh.Trimesh``

Conventions. geocull's world is x east, y north, **z up**, in metres. xtgeo and SEG-Y give depth (or
time) positive *down*; with ``z_positive="down"`` (the default of every function here) a depth d
becomes z = -d, so horizons, cubes and grids from these sources stack the right way up and agree
with each other (``Volume(z_positive="down")`` follows the same rule). Pass ``z_positive="up"`` for
data that already hold elevations. Rotations are degrees counter-clockwise about the grid's origin
(xtgeo's convention); xtgeo's ``yflip=-1`` means rows run towards -y in the grid's frame.

xtgeo, segyio, trimesh and PyVista are optional dependencies: each is imported inside the function
that needs it (``pip install geocull[io]``); the functions that take an object read it by its
attributes and import nothing.
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any, Literal, TypedDict

import numpy as np

from ._errors import InputError

if TYPE_CHECKING:
    from .scene import Scene

__all__ = [
    "from_xtgeo_surface",
    "from_xtgeo_cube",
    "from_xtgeo_grid",
    "from_segy",
    "to_pyvista",
    "to_trimesh",
    "HeightfieldKwargs",
    "VolumeKwargs",
    "GridArrays",
    "XTGEO_UNDEF_LIMIT",
]

#: Values at or beyond this magnitude are xtgeo's undefined marker (UNDEF is 1e33; its
#: UNDEF_LIMIT is 9.9e32) and become holes.
XTGEO_UNDEF_LIMIT = 9.9e32


class HeightfieldKwargs(TypedDict):
    """What :func:`from_xtgeo_surface` returns: keyword arguments of ``Scene.add_heightfield``."""

    z: np.ma.MaskedArray
    origin: tuple[float, float]
    spacing: tuple[float, float]
    rotation: float
    yflip: bool
    name: str | None


class VolumeKwargs(TypedDict):
    """What :func:`from_xtgeo_cube` and :func:`from_segy` return: keyword arguments of ``Volume``."""

    values: np.ndarray
    origin: tuple[float, float, float]
    spacing: tuple[float, float, float]
    order: Literal["zyx", "xyz"]
    z_positive: Literal["up", "down"]
    rotation: float


class GridArrays(TypedDict):
    """What :func:`from_xtgeo_grid` returns (see there for the corner order)."""

    corners: np.ndarray
    active: np.ndarray
    properties: dict[str, np.ndarray]


def _import(name: str) -> Any:
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError as e:
        raise ImportError(f"geocull.io needs the optional package {name!r} here: pip install {name}") from e


def _zsign(z_positive: str) -> float:
    if z_positive not in ("up", "down"):
        raise InputError(f"z_positive: {z_positive!r}; expected 'up' or 'down'")
    return -1.0 if z_positive == "down" else 1.0


def _undefined_masked(values: Any) -> np.ma.MaskedArray:
    """A float64 masked array with xtgeo's undefined values (and NaN) masked."""
    v = np.ma.asarray(values)
    data = np.asarray(np.ma.getdata(v), dtype=np.float64)
    mask = np.ma.getmaskarray(v) | ~np.isfinite(data) | (np.abs(data) >= XTGEO_UNDEF_LIMIT)
    return np.ma.MaskedArray(data, mask=mask)


# --------------------------------------------------------------------------------------------- xtgeo


def from_xtgeo_surface(surf: Any, z_positive: Literal["up", "down"] = "down") -> HeightfieldKwargs:
    """An xtgeo ``RegularSurface`` as keyword arguments of :meth:`geocull.Scene.add_heightfield`:
    ``scene.add_heightfield(**from_xtgeo_surface(surf), tiles=(8, 8))``.

    z: ``surf.values`` transposed to (nrow, ncol) (xtgeo stores (ncol, nrow)), a masked array whose
    mask (xtgeo's undefined nodes, values >= :data:`XTGEO_UNDEF_LIMIT`, NaN) becomes holes; negated
    for z_positive="down" (xtgeo's depth / time positive down -> z up; "up" keeps the values).
    origin (xori, yori), spacing (xinc, yinc), rotation (degrees counter-clockwise about the origin),
    yflip (``surf.yflip == -1``), name (``surf.name``; None for xtgeo's default "unknown").
    Node (i, j) of the surface lies at ``(xori, yori) + R(rotation) @ (i*xinc, j*yinc*yflip)``, as in
    ``surf.get_xyz_values()``.
    """
    sign = _zsign(z_positive)
    z = _undefined_masked(surf.values).T * sign
    yflip = int(surf.yflip)
    if yflip not in (1, -1):
        raise InputError(f"surf: yflip is {surf.yflip!r}; xtgeo's yflip is 1 or -1")
    name = getattr(surf, "name", None)
    if name == "unknown":  # xtgeo's default: no name (IRAP files store none)
        name = None
    return HeightfieldKwargs(
        z=z,
        origin=(float(surf.xori), float(surf.yori)),
        spacing=(float(surf.xinc), float(surf.yinc)),
        rotation=float(surf.rotation),
        yflip=yflip == -1,
        name=None if name is None else str(name),
    )


def _right_handed(
    values: np.ndarray, x0: float, y0: float, ystep: float, rotation: float, flip: bool
) -> tuple[np.ndarray, float, float]:
    """(values, x0, y0) of a grid indexed [i, j, ...] whose rows run towards -y in its frame when
    ``flip``: the j axis reversed (a view) and the origin moved to the last row, so that the grid is
    right-handed (a Volume has a rotation, no mirror). ``ystep`` is the row spacing."""
    if not flip:
        return values, x0, y0
    n = values.shape[1]
    t = math.radians(rotation)
    d = -(n - 1) * ystep  # the last row, at -(n-1)*ystep along the grid's y axis
    return values[:, ::-1], x0 - math.sin(t) * d, y0 + math.cos(t) * d


def from_xtgeo_cube(cube: Any, z_positive: Literal["up", "down"] | None = None) -> VolumeKwargs:
    """An xtgeo ``Cube`` as keyword arguments of :class:`geocull.Volume`: ``gc.Volume(**from_xtgeo_cube(c))``.

    values: ``cube.values`` (ncol, nrow, nlay) as it is (order="xyz": column -> x, row -> y,
    layer -> z; no copy); origin (xori, yori, zori), spacing (xinc, yinc, zinc), rotation.
    z_positive: None follows ``cube.zflip`` (1: z positive down, the usual depth / time cube,
    "down"; -1: "up"). xtgeo's yflip=-1 reverses the row axis (a view) with the origin on the last
    row, the same samples in a right-handed grid.
    """
    zflip = int(getattr(cube, "zflip", 1))
    zp: Literal["up", "down"] = z_positive if z_positive is not None else ("down" if zflip == 1 else "up")
    _zsign(zp)
    values = np.ma.getdata(cube.values)
    values, x0, y0 = _right_handed(
        values, float(cube.xori), float(cube.yori), float(cube.yinc), float(cube.rotation), int(cube.yflip) == -1
    )
    return VolumeKwargs(
        values=values,
        origin=(x0, y0, float(cube.zori)),
        spacing=(float(cube.xinc), float(cube.yinc), float(cube.zinc)),
        order="xyz",
        z_positive=zp,
        rotation=float(cube.rotation),
    )


def from_xtgeo_grid(
    grid: Any, properties: Any = None, z_positive: Literal["up", "down"] = "down"
) -> GridArrays:
    """An xtgeo corner-point ``Grid`` as plain arrays (for geocull's future reservoir-grid object kind,
    or any use):

    corners: (nk, nj, ni, 8, 3) float64 world (x, y, z) of each cell's 8 corners. **Corner order:**
        corner c has i-bit ``c & 1``, j-bit ``(c >> 1) & 1`` and k-bit ``(c >> 2) & 1``, i.e.
        c = 0..3 the cell's top face at (i, j), (i+1, j), (i, j+1), (i+1, j+1), c = 4..7 its base in
        the same order (xtgeo's corners 1..8); k = 0 is the top layer. z is -depth for
        z_positive="down" (xtgeo's Z_TVDSS is positive down), the stored value for "up".
    active: (nk, nj, ni) bool (xtgeo's ACTNUM != 0).
    properties: name -> (nk, nj, ni) float64 (masked / inactive cells NaN), for every
        ``xtgeo.GridProperty`` given (or property name of ``grid``) in ``properties``.
    """
    sign = _zsign(z_positive)
    ni, nj, nk = (int(v) for v in grid.dimensions)
    parts = grid.get_xyz_corners()  # 24 GridProperty: x, y, z of corner 1, then corner 2, ...
    if len(parts) != 24:
        raise InputError(f"grid: get_xyz_corners() gave {len(parts)} arrays, expected 24")
    c = np.stack([np.asarray(np.ma.getdata(p.values), dtype=np.float64) for p in parts])  # (24, ni, nj, nk)
    corners = c.reshape(8, 3, ni, nj, nk).transpose(4, 3, 2, 0, 1).copy()  # (nk, nj, ni, 8, 3)
    corners[..., 2] *= sign
    active = np.asarray(np.ma.getdata(grid.get_actnum().values)).transpose(2, 1, 0) != 0
    props: dict[str, np.ndarray] = {}
    for p in [] if properties is None else ([properties] if isinstance(properties, str) else list(properties)):
        prop = grid.get_prop_by_name(p) if isinstance(p, str) else p
        if prop is None:
            raise InputError(f"properties: the grid has no property {p!r}")
        v = np.ma.asarray(prop.values)
        data = np.asarray(np.ma.getdata(v), dtype=np.float64).copy()
        data[np.ma.getmaskarray(v)] = np.nan
        if data.shape != (ni, nj, nk):
            raise InputError(f"properties: {prop.name!r} has shape {data.shape}, the grid ({ni}, {nj}, {nk})")
        props[str(prop.name)] = np.ascontiguousarray(data.transpose(2, 1, 0))
    return GridArrays(corners=corners, active=np.ascontiguousarray(active), properties=props)


# --------------------------------------------------------------------------------------------- SEG-Y


def from_segy(
    source: str | os.PathLike[str] | Any,
    iline: int = 189,
    xline: int = 193,
    z_positive: Literal["up", "down"] = "down",
) -> VolumeKwargs:
    """A post-stack 3-D SEG-Y cube as keyword arguments of :class:`geocull.Volume` (needs segyio);
    ``Volume.from_segy(source)`` builds the volume.

    source: a path or an open ``segyio.SegyFile`` (read as it is, e.g. after ``f.mmap()``).
    iline, xline: trace header bytes of the inline and crossline numbers (segyio's defaults).

    Axes: inline -> x, crossline -> y, sample -> z (order="xyz"; crossline-sorted files are
    transposed as a view). z: ``f.samples`` (the delay and sample interval of the headers, in the
    file's units: ms for time, m or ft for depth) with z_positive="down", so the first sample is the
    shallowest and the cube renders the right way up. x, y: the CDP_X / CDP_Y trace headers scaled by
    their SourceGroupScalar (negative = divide). The position of trace (inline index a, crossline
    index b) must be ``P0 + a*u + b*v`` for two perpendicular steps u, v (checked on every trace, to
    5 % of the smaller step): spacing (|u|, |v|), rotation = the direction of u (degrees
    counter-clockwise from +x), origin = P0. **Rotated surveys** are supported at any angle; a
    survey whose crossline step points clockwise of the inline step (a left-handed grid) gets its
    crossline axis reversed (a view) and its origin on the last crossline. Skewed (non-perpendicular)
    or irregular geometries, pre-stack (several offsets) and unstructured files are InputErrors.

    The samples are read once, by ``segyio.tools.cube`` (one array), which the Volume copies once
    into its buffer: no further copy, whatever the axis order.
    """
    segyio = _import("segyio")
    if isinstance(source, str | os.PathLike):
        with segyio.open(os.fspath(source), iline=iline, xline=xline) as f:
            return _segy_kwargs(segyio, f, z_positive)
    if not hasattr(source, "trace") or not hasattr(source, "header"):
        raise InputError(f"source: {type(source).__name__} is neither a path nor an open segyio.SegyFile")
    return _segy_kwargs(segyio, source, z_positive)


def _segy_kwargs(segyio: Any, f: Any, z_positive: Literal["up", "down"]) -> VolumeKwargs:
    _zsign(z_positive)
    if f.unstructured:
        raise InputError("source: the SEG-Y file has no inline/crossline geometry (unstructured); check iline=/xline=")
    if len(f.offsets) != 1:
        raise InputError(f"source: a pre-stack file ({len(f.offsets)} offsets); geocull reads post-stack cubes")
    il, xl = np.asarray(f.ilines), np.asarray(f.xlines)
    samples = np.asarray(f.samples, dtype=np.float64)
    na, nb, ns = len(il), len(xl), len(samples)
    if min(na, nb, ns) < 2:
        raise InputError(f"source: {na} inlines x {nb} crosslines x {ns} samples; a volume needs 2 of each")
    dz = np.diff(samples)
    if not np.allclose(dz, dz[0], rtol=1e-6):
        raise InputError("source: the samples are not regularly spaced")
    inline_sorted = f.sorting == segyio.TraceSortingFormat.INLINE_SORTING
    cube = segyio.tools.cube(f)  # (inlines, crosslines, samples) or (crosslines, inlines, samples)
    if not inline_sorted:
        cube = cube.transpose(1, 0, 2)
    tf = segyio.TraceField
    x = np.asarray(f.attributes(tf.CDP_X)[:], dtype=np.float64)
    y = np.asarray(f.attributes(tf.CDP_Y)[:], dtype=np.float64)
    sc = np.asarray(f.attributes(tf.SourceGroupScalar)[:], dtype=np.float64)
    scale = np.where(sc < 0, 1.0 / np.abs(np.where(sc == 0, 1, sc)), np.where(sc == 0, 1.0, sc))
    x, y = x * scale, y * scale
    # Trace t in file order -> (inline index a, crossline index b).
    shape = (na, nb) if inline_sorted else (nb, na)
    xs, ys = x.reshape(shape), y.reshape(shape)
    if not inline_sorted:
        xs, ys = xs.T, ys.T
    p0 = np.array([xs[0, 0], ys[0, 0]])
    u = (np.array([xs[-1, 0], ys[-1, 0]]) - p0) / (na - 1)
    v = (np.array([xs[0, -1], ys[0, -1]]) - p0) / (nb - 1)
    lu, lv = float(np.hypot(*u)), float(np.hypot(*v))
    if lu == 0 or lv == 0:
        raise InputError("source: CDP_X / CDP_Y do not change along the inlines or crosslines (no coordinates?)")
    if abs(float(u @ v)) > 1e-3 * lu * lv:
        raise InputError(
            f"source: the inline step {u.tolist()} and the crossline step {v.tolist()} are not perpendicular "
            "(a skewed survey); a Volume is a rectangular grid, possibly rotated"
        )
    a, b = np.meshgrid(np.arange(na), np.arange(nb), indexing="ij")
    err = np.hypot(p0[0] + a * u[0] + b * v[0] - xs, p0[1] + a * u[1] + b * v[1] - ys).max()
    if err > 0.05 * min(lu, lv):
        raise InputError(f"source: the trace coordinates are not a regular grid (off by up to {err:g})")
    rotation = math.degrees(math.atan2(u[1], u[0]))
    left_handed = u[0] * v[1] - u[1] * v[0] < 0
    values, x0, y0 = _right_handed(cube, float(p0[0]), float(p0[1]), lv, rotation, left_handed)
    return VolumeKwargs(
        values=values,
        origin=(x0, y0, float(samples[0])),
        spacing=(lu, lv, float(dz[0])),
        order="xyz",
        z_positive=z_positive,
        rotation=rotation,
    )


# --------------------------------------------------------------------------------------------- meshes


def to_pyvista(scene: Scene, id: int) -> Any:
    """Object ``id`` of ``scene`` as a ``pyvista.PolyData`` (fine triangles, world coordinates, offset
    applied; ``field_data``: name, kind, color, object_id), which ``Scene.add_mesh`` takes back."""
    from . import pyvista as gpv

    return gpv.to_polydata(scene, id)


def to_trimesh(scene: Scene, id: int) -> Any:
    """Object ``id`` of ``scene`` as a ``trimesh.Trimesh`` (fine triangles, world coordinates, offset
    applied, vertices kept as they are: ``process=False``); ``metadata`` holds name, kind and
    object_id, the face colours the object's colour. ``Scene.add_mesh`` takes it back."""
    trimesh = _import("trimesh")
    v, f = scene.geometry(id)
    info = scene.object_info(id)
    m = trimesh.Trimesh(vertices=v, faces=f, process=False)
    m.metadata.update(name=info["name"], kind=info["kind"], object_id=int(id))
    rgba = np.array([*(round(255 * c) for c in info["color"]), 255], dtype=np.uint8)
    m.visual.face_colors = np.tile(rgba, (len(f), 1))
    return m
