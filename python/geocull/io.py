"""Geoscience data in and out: xtgeo surfaces, cubes and grids, SEG-Y cubes (segyio), trimesh and
PyVista meshes, each with its conventions translated, so that a scene needs no glue beyond a call.

>>> import geocull as gc, xtgeo
>>> scene = gc.Scene()
>>> scene.add_heightfield(xtgeo.surface_from_file("top.gri"), tiles=(8, 8))   # xtgeo objects directly
>>> scene.add_heightfield(**gc.io.from_xtgeo_surface(surf), name="Top", tiles=(8, 8))  # or through a dict
>>> scene.add_well(xtgeo.well_from_file("OP_1.w"), log="Poro", radius=15.0)
>>> vol = gc.Volume(cube)                                    # or gc.Volume.from_segy("cube.sgy")
>>> scene.add_mesh(trimesh.load("fault.stl"), kind="fault")  # trimesh / PyVista meshes directly
>>> gc.io.to_trimesh(scene, 0).export("top.ply")

``from_xtgeo_surface``  xtgeo RegularSurface -> ``Scene.add_heightfield`` keyword arguments
``from_xtgeo_cube``     xtgeo Cube -> ``Volume`` keyword arguments
``from_xtgeo_grid``     xtgeo Grid -> ``Scene.add_grid`` keyword arguments (corners, active, values)
``from_xtgeo_well``     xtgeo Well -> ``Scene.add_well`` keyword arguments (path, values)
``xtgeo_property``      an xtgeo GridProperty (or a grid's property by name) -> (nk, nj, ni) array
``xtgeo_kind``          which xtgeo object something is, by its attributes (no import)
``from_segy``           a SEG-Y file -> ``Volume`` keyword arguments (``Volume.from_segy`` builds it)
``read_grdecl``         an Eclipse GRDECL file -> ``Scene.add_grid`` keyword arguments (MAPAXES applied)
``to_pyvista``          one scene object -> ``pyvista.PolyData``
``to_trimesh``          one scene object -> ``trimesh.Trimesh``

The dictionaries hold geometry and data only, never a name or any presentation argument, so every
keyword of the function they feed can be added to them: ``add_heightfield(**kw, name="Top",
cmap="terrain")``. Passing the xtgeo object itself (``add_heightfield(surf)``, ``add_grid(grid,
values="PORO")``, ``add_well(well, log="Poro")``, ``add_mesh(trisurf)``, ``Volume(cube)``) also takes
its name; any keyword given there wins over what the object says.

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
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal, TypedDict

import numpy as np

from . import _lazy
from ._convert import z_sign
from ._errors import InputError
from ._segy_survey import fit_survey

if TYPE_CHECKING:
    from .pyvista import SceneLike

__all__ = [
    "from_xtgeo_surface",
    "from_xtgeo_cube",
    "from_xtgeo_grid",
    "from_xtgeo_well",
    "xtgeo_property",
    "xtgeo_kind",
    "from_segy",
    "read_grdecl",
    "to_pyvista",
    "to_trimesh",
    "HeightfieldKwargs",
    "VolumeKwargs",
    "GridKwargs",
    "WellKwargs",
    "XTGEO_UNDEF_LIMIT",
]

#: Values at or beyond this magnitude are undefined and become holes / NaN (no data): xtgeo's
#: UNDEF is 1e33 (its UNDEF_LIMIT 9.9e32), which it writes for undefined surface nodes, missing
#: cube traces and log samples; no measured value comes near 1e30.
XTGEO_UNDEF_LIMIT = 1e30
#: xtgeo's undefined value of discrete (integer) logs and properties.
XTGEO_UNDEF_INT = 2_000_000_000


class HeightfieldKwargs(TypedDict):
    """What :func:`from_xtgeo_surface` returns: keyword arguments of ``Scene.add_heightfield``."""

    z: np.ma.MaskedArray
    origin: tuple[float, float]
    spacing: tuple[float, float]
    rotation: float
    yflip: bool


class VolumeKwargs(TypedDict):
    """What :func:`from_xtgeo_cube` and :func:`from_segy` return: keyword arguments of ``Volume``
    (values, origin, spacing, order, z_positive, rotation, yflip, and the survey's inline,
    crossline and sample numbers in the file's order)."""

    values: np.ndarray
    origin: tuple[float, float, float]
    spacing: tuple[float, float, float]
    order: Literal["zyx", "xyz"]
    z_positive: Literal["up", "down"]
    rotation: float
    yflip: bool
    inlines: np.ndarray
    crosslines: np.ndarray
    samples: np.ndarray


class GridKwargs(TypedDict):
    """What :func:`from_xtgeo_grid` (and :func:`geocull.grid.from_xtgeo`) return: keyword arguments
    of ``Scene.add_grid`` (see there for the corner order); ``values`` None without a property."""

    corners: np.ndarray
    active: np.ndarray
    values: np.ndarray | None


class WellKwargs(TypedDict):
    """What :func:`from_xtgeo_well` returns: keyword arguments of ``Scene.add_well``."""

    path: np.ndarray
    values: np.ndarray | None


def _import(name: str) -> Any:
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError as e:
        raise ImportError(f"geocull.io needs the optional package {name!r} here: pip install {name}") from e


def _undefined_masked(values: Any) -> np.ma.MaskedArray:
    """A float64 masked array with the undefined values (:data:`XTGEO_UNDEF_LIMIT`, NaN) masked."""
    v = np.ma.asarray(values)
    data = np.asarray(np.ma.getdata(v), dtype=np.float64)
    mask = np.ma.getmaskarray(v) | ~np.isfinite(data) | (np.abs(data) >= XTGEO_UNDEF_LIMIT)
    return np.ma.MaskedArray(data, mask=mask)


def _undefined_nan(values: Any, discrete: bool = False) -> np.ndarray:
    """float64 copy of ``values`` with masked, non-finite and undefined samples (magnitude >=
    :data:`XTGEO_UNDEF_LIMIT`; :data:`XTGEO_UNDEF_INT` too for ``discrete`` data) set to NaN."""
    v = np.ma.asarray(values)
    data = np.array(np.ma.getdata(v), dtype=np.float64)
    bad = np.ma.getmaskarray(v) | ~np.isfinite(data) | (np.abs(data) >= XTGEO_UNDEF_LIMIT)
    if discrete:
        bad |= data == XTGEO_UNDEF_INT
    data[bad] = np.nan
    return data


# The attributes that identify each xtgeo class (duck typing: xtgeo is never imported to check).
_XTGEO_ATTRS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("cube", ("ncol", "nrow", "nlay", "xinc", "yinc", "zinc", "xori", "yori", "zori", "ilines", "xlines", "values")),
    ("surface", ("ncol", "nrow", "xinc", "yinc", "xori", "yori", "rotation", "yflip", "values")),
    ("grid", ("dimensions", "get_xyz_corners", "get_actnum")),
    ("gridproperty", ("dimensions", "values", "name", "isdiscrete")),
    ("well", ("xname", "yname", "zname", "lognames", "get_dataframe")),
    ("trisurface", ("vertices", "triangles", "num_triangles", "num_vertices", "to_rms")),
)

XtgeoKind = Literal["cube", "surface", "grid", "gridproperty", "well", "trisurface"]


def xtgeo_kind(x: Any) -> XtgeoKind | None:
    """Which xtgeo object ``x`` is, by its attributes (xtgeo is not imported): "cube" (``Cube``),
    "surface" (``RegularSurface``), "grid" (``Grid``), "gridproperty" (``GridProperty``), "well"
    (``Well``), "trisurface" (``TriangulatedSurface``), or None (arrays, lists, anything else)."""
    if x is None or isinstance(x, np.ndarray | list | tuple | str | bytes | dict):
        return None
    for kind, attrs in _XTGEO_ATTRS:
        if all(hasattr(x, a) for a in attrs):
            return kind  # type: ignore[return-value]
    return None


def xtgeo_name(x: Any) -> str | None:
    """The ``name`` of an xtgeo object, None for xtgeo's placeholders ("unknown", "noname", "")."""
    name = getattr(x, "name", None)
    if name is None or str(name).strip().lower() in ("", "unknown", "noname", "none"):
        return None
    return str(name)


# --------------------------------------------------------------------------------------------- xtgeo


def from_xtgeo_surface(surf: Any, z_positive: Literal["up", "down"] = "down") -> HeightfieldKwargs:
    """An xtgeo ``RegularSurface`` as keyword arguments of :meth:`geocull.Scene.add_heightfield`:
    ``scene.add_heightfield(**from_xtgeo_surface(surf), name="Top", tiles=(8, 8))`` (or
    ``scene.add_heightfield(surf, ...)``, which calls this and takes the surface's name too).

    z: ``surf.values`` transposed to (nrow, ncol) (xtgeo stores (ncol, nrow)), a masked array whose
    mask (xtgeo's undefined nodes, values >= :data:`XTGEO_UNDEF_LIMIT`, NaN) becomes holes; negated
    for z_positive="down" (xtgeo's depth / time positive down, metres or ms -> z up; "up" keeps the
    values). origin (xori, yori) metres, spacing (xinc, yinc) metres, rotation (degrees
    counter-clockwise about the origin), yflip (``surf.yflip == -1``). No ``name``: the dictionary
    holds the geometry only, so ``name=`` and every other keyword can be added to it.
    Node (i, j) of the surface lies at ``(xori, yori) + R(rotation) @ (i*xinc, j*yinc*yflip)``, as in
    ``surf.get_xyz_values()``.
    """
    sign = z_sign(z_positive)
    z = _undefined_masked(surf.values).T * sign
    yflip = int(surf.yflip)
    if yflip not in (1, -1):
        raise InputError(f"surf: yflip is {surf.yflip!r}; xtgeo's yflip is 1 or -1")
    return HeightfieldKwargs(
        z=z,
        origin=(float(surf.xori), float(surf.yori)),
        spacing=(float(surf.xinc), float(surf.yinc)),
        rotation=float(surf.rotation),
        yflip=yflip == -1,
    )


def from_xtgeo_cube(cube: Any, z_positive: Literal["up", "down"] | None = None) -> VolumeKwargs:
    """An xtgeo ``Cube`` as keyword arguments of :class:`geocull.Volume`: ``gc.Volume(**from_xtgeo_cube(c))``
    (``gc.Volume(cube)`` does the same).

    values: ``cube.values`` (ncol, nrow, nlay) (order="xyz": column -> x, row -> y, layer -> z),
    no copy unless it holds undefined samples: values of magnitude >= :data:`XTGEO_UNDEF_LIMIT`
    (xtgeo's 1e33 for missing traces) and masked ones become NaN (no data) in a copy of the cube.
    origin (xori, yori, zori), spacing (xinc, yinc, zinc) metres (zinc in the cube's units: ms for
    time), rotation (degrees counter-clockwise), yflip (``cube.yflip == -1``: rows run towards -y
    in the cube's frame; the Volume reverses them, a view, with its origin on the last row).
    z_positive: None follows ``cube.zflip`` (1: z positive down, the usual depth / time cube,
    "down"; -1: "up"). inlines, crosslines: ``cube.ilines`` (ncol,), ``cube.xlines`` (nrow,);
    samples: (nlay,) ``zori + k*zinc``, the sample times / depths in the cube's order.
    """
    zflip = int(getattr(cube, "zflip", 1))
    zp: Literal["up", "down"] = z_positive if z_positive is not None else ("down" if zflip == 1 else "up")
    z_sign(zp)
    raw = cube.values
    values = np.ma.getdata(raw)
    if not isinstance(values, np.ndarray) or values.dtype.kind != "f":
        values = np.asarray(values, dtype=np.float32)
    bad = (values >= XTGEO_UNDEF_LIMIT) | (values <= -XTGEO_UNDEF_LIMIT)
    if isinstance(raw, np.ma.MaskedArray):
        bad |= np.ma.getmaskarray(raw)
    if bad.any():
        values = np.where(bad, values.dtype.type(np.nan), values)
    nlay = int(values.shape[2]) if values.ndim == 3 else int(cube.nlay)
    zori, zinc = float(cube.zori), float(cube.zinc)
    return VolumeKwargs(
        values=values,
        origin=(float(cube.xori), float(cube.yori), zori),
        spacing=(float(cube.xinc), float(cube.yinc), zinc),
        order="xyz",
        z_positive=zp,
        rotation=float(cube.rotation),
        yflip=int(cube.yflip) == -1,
        inlines=np.asarray(cube.ilines).copy(),
        crosslines=np.asarray(cube.xlines).copy(),
        samples=zori + zinc * np.arange(nlay, dtype=np.float64),
    )


def _grid_dims(grid: Any) -> tuple[int, int, int]:
    ni, nj, nk = (int(v) for v in grid.dimensions)
    return ni, nj, nk


def xtgeo_property(prop: Any, grid: Any = None, arg: str = "values") -> np.ndarray:
    """One cell property as a C-contiguous (nk, nj, ni) float64 array (k = 0 the top layer; masked,
    inactive and undefined cells NaN, :data:`XTGEO_UNDEF_INT` too for discrete properties):
    ``prop`` an ``xtgeo.GridProperty``, or a property name of ``grid`` (``grid.get_prop_by_name``).
    ``arg`` names the argument in errors."""
    if isinstance(prop, str):
        if grid is None:
            raise InputError(f"{arg}: a property name ({prop!r}) needs an xtgeo Grid")
        found = grid.get_prop_by_name(prop)
        if found is None:
            names = [str(p.name) for p in (getattr(grid, "props", None) or [])]
            raise InputError(f"{arg}: the grid has no property {prop!r} (it has {names})")
        prop = found
    if xtgeo_kind(prop) != "gridproperty":
        raise InputError(f"{arg}: {type(prop).__name__} is neither an xtgeo GridProperty nor a property name")
    discrete = bool(getattr(prop, "isdiscrete", False))
    data = _undefined_nan(prop.values, discrete)
    if grid is not None and data.shape != _grid_dims(grid):
        raise InputError(f"{arg}: {prop.name!r} has shape {data.shape}, the grid {_grid_dims(grid)}")
    if data.ndim != 3:
        raise InputError(f"{arg}: {prop.name!r} has shape {data.shape}, not (ncol, nrow, nlay)")
    return np.ascontiguousarray(data.transpose(2, 1, 0))


def from_xtgeo_grid(grid: Any, values: Any = None, z_positive: Literal["up", "down"] = "down") -> GridKwargs:
    """An xtgeo corner-point ``Grid`` as keyword arguments of :meth:`geocull.Scene.add_grid`:
    ``scene.add_grid(**from_xtgeo_grid(grid, "PORO"), cmap="viridis")`` (or
    ``scene.add_grid(grid, values="PORO")``); :func:`geocull.grid.from_xtgeo` returns the same.

    corners: (nk, nj, ni, 8, 3) float64 world (x, y, z) metres of each cell's 8 corners. **Corner
        order:** corner c has i-bit ``c & 1``, j-bit ``(c >> 1) & 1`` and k-bit ``(c >> 2) & 1``, i.e.
        c = 0..3 the cell's top face at (i, j), (i+1, j), (i, j+1), (i+1, j+1), c = 4..7 its base in
        the same order (xtgeo's corners 1..8); k = 0 is the top layer. z is -depth for
        z_positive="down" (xtgeo's Z_TVDSS is positive down), the stored value for "up".
    active: (nk, nj, ni) bool (xtgeo's ACTNUM != 0).
    values: (nk, nj, ni) float64 of ``values`` (an ``xtgeo.GridProperty`` or a property name of the
        grid; masked / inactive / undefined cells NaN, see :func:`xtgeo_property`), or None.
    """
    sign = z_sign(z_positive)
    ni, nj, nk = _grid_dims(grid)
    parts = grid.get_xyz_corners()  # 24 GridProperty: x, y, z of corner 1, then corner 2, ...
    if len(parts) != 24:
        raise InputError(f"grid: get_xyz_corners() gave {len(parts)} arrays, expected 24")
    c = np.stack([np.asarray(np.ma.getdata(p.values), dtype=np.float64) for p in parts])  # (24, ni, nj, nk)
    corners = c.reshape(8, 3, ni, nj, nk).transpose(4, 3, 2, 0, 1).copy()  # (nk, nj, ni, 8, 3)
    corners[..., 2] *= sign
    active = np.asarray(np.ma.getdata(grid.get_actnum().values)).transpose(2, 1, 0) != 0
    vals = None if values is None else xtgeo_property(values, grid, "values")
    return GridKwargs(corners=corners, active=np.ascontiguousarray(active), values=vals)


def from_xtgeo_well(
    well: Any,
    log: str | None = None,
    max_stations: int | None = None,
    z_positive: Literal["up", "down"] = "down",
) -> WellKwargs:
    """An xtgeo ``Well`` as keyword arguments of :meth:`geocull.Scene.add_well`:
    ``scene.add_well(**from_xtgeo_well(well, log="Poro"), radius=15.0, name=well.name)`` (or
    ``scene.add_well(well, log="Poro")``, which takes the well's name too).

    path: (n, 3) float64 stations (x, y, z) metres from the well's dataframe columns
        ``well.xname``, ``well.yname``, ``well.zname`` (X_UTME, Y_UTMN, Z_TVDSS), z = -depth for
        z_positive="down" (xtgeo's TVDSS is positive down; "up" keeps it); stations with an
        undefined or NaN coordinate are dropped.
    values: (n,) float64 of the log ``log`` (one of ``well.lognames``) at the same stations, its
        undefined values (NaN, magnitude >= :data:`XTGEO_UNDEF_LIMIT`, :data:`XTGEO_UNDEF_INT` for
        discrete logs) NaN; None without ``log``.
    max_stations: at most this many stations (>= 2), evenly spaced in station order, first and
        last kept (RMS well files hold a station every ~0.15 m: thousands per well); None keeps all.
    """
    sign = z_sign(z_positive)
    df = well.get_dataframe()
    cols = [str(well.xname), str(well.yname), str(well.zname)]
    for c in cols:
        if c not in df.columns:
            raise InputError(f"well: its dataframe has no column {c!r}")
    xyz = _undefined_nan(np.column_stack([np.asarray(df[c], dtype=np.float64) for c in cols]))
    vals = None
    if log is not None:
        if not isinstance(log, str):
            raise InputError(f"log: {log!r} is not a string (a log name)")
        names = list(well.lognames)
        if log not in names or log not in df.columns:
            raise InputError(f"log: the well {xtgeo_name(well)!r} has no log {log!r} (it has {names})")
        discrete = bool(well.isdiscrete(log)) if hasattr(well, "isdiscrete") else False
        vals = _undefined_nan(np.asarray(df[log], dtype=np.float64), discrete)
    keep = np.isfinite(xyz).all(axis=1)
    if not keep.all():
        xyz = xyz[keep]
        vals = None if vals is None else vals[keep]
    if max_stations is not None:
        if isinstance(max_stations, bool) or not isinstance(max_stations, int | np.integer) or max_stations < 2:
            raise InputError(f"max_stations: {max_stations!r} is not an integer >= 2")
        if len(xyz) > max_stations:
            idx = np.unique(np.round(np.linspace(0, len(xyz) - 1, int(max_stations))).astype(np.int64))
            xyz = xyz[idx]
            vals = None if vals is None else vals[idx]
    if len(xyz) < 2:
        raise InputError(f"well: {len(xyz)} station(s) with defined coordinates; a well needs 2")
    xyz[:, 2] *= sign
    return WellKwargs(path=np.ascontiguousarray(xyz), values=vals)


# -------------------------------------------------------------------------------------------- GRDECL

#: Reader failures (of xtgeo's GRDECL reader, of a damaged or truncated file) that become InputErrors.
_READ_ERRORS = (ValueError, OSError, RuntimeError, IndexError, KeyError, EOFError, MemoryError, TypeError,
                AttributeError)


def read_grdecl(
    path: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    properties: str | None = None,
    z_positive: Literal["up", "down"] = "down",
    engine: Literal["auto", "xtgeo", "geocull"] = "auto",
) -> GridKwargs:
    """An Eclipse GRDECL corner-point grid as keyword arguments of :meth:`geocull.Scene.add_grid`:
    ``scene.add_grid(**read_grdecl([grid_file, poro_file], properties="PORO"), name="Reek")``.

    path: the GRDECL text file of the grid (SPECGRID, COORD, ZCORN, optional ACTNUM, MAPAXES,
        GRIDUNIT / MAPUNITS), or a list of files read as one deck, the grid's first (property files
        such as ``reek_sim_poro.grdecl`` after it).
    properties: the name of one cell property keyword in those files (``"PORO"``) that becomes
        ``values``, (nk, nj, ni) float64, NaN on inactive cells; None: ``values=None``. Several
        properties: one call each, or recolour with ``Scene.set_color_by``.
    z_positive: "down" (default: Eclipse depths, drawn at z = -depth metres) or "up".
    engine: "xtgeo" reads through ``xtgeo.grid_from_file(..., fformat="grdecl")`` and
        :func:`from_xtgeo_grid`; "geocull" through geocull's own keyword reader (numpy only:
        ``n*value`` repeat counts, ``--`` comments, ``/`` terminators, ECHO / NOECHO and section
        keywords skipped, ``INCLUDE`` followed, unknown keywords skipped, EQUALS / COPY / ADD /
        MULTIPLY / BOX not applied but warned of) and :func:`geocull.grid.from_grdecl`; "auto"
        (default) is xtgeo when it is installed. Both give the same corners on the same file
        (xtgeo joins vertically split layers, with its own warning).

    MAPAXES is applied (unless GRIDUNIT says the grid is relative to the map already): local
    COORD (x, y) becomes ``origin + x * ex + y * ey`` (:func:`geocull.grid.mapaxes_transform`), so
    the grid lands in the map (UTM) coordinates of horizons and wells; coordinates in GRIDUNIT
    units other than MAPUNITS' are converted to MAPUNITS (METRES, FEET, CM), as xtgeo does.

    Returns ``dict(corners=(nk, nj, ni, 8, 3), active=(nk, nj, ni), values=... or None)``, the
    conventions of :mod:`geocull.grid`. A missing, unreadable, truncated (data without its ``/``)
    or inconsistent file (a count other than SPECGRID's, a number that is none, a degenerate
    MAPAXES) is an :class:`geocull.InputError` naming ``path``, the file and the cause; a property
    not in the files one naming ``properties``.
    """
    from . import _grdecl

    z_sign(z_positive)
    if isinstance(path, str | os.PathLike):
        paths = [os.fspath(path)]
    elif isinstance(path, Sequence) and path and all(isinstance(p, str | os.PathLike) for p in path):
        paths = [os.fspath(p) for p in path]
    else:
        raise InputError(f"path: {path!r} is neither a path nor a non-empty list of paths")
    for p in paths:
        if not os.path.isfile(p):
            raise InputError(f"path: no such file {p!r}")
    if properties is not None and not isinstance(properties, str):
        raise InputError(f"properties: {properties!r} is not a property keyword name (a string such as 'PORO')")
    if engine not in ("auto", "xtgeo", "geocull"):
        raise InputError(f"engine: {engine!r}; expected 'auto', 'xtgeo' or 'geocull'")
    if engine == "auto":
        import importlib.util

        engine = "xtgeo" if importlib.util.find_spec("xtgeo") is not None else "geocull"
    if engine == "geocull":
        keep = set(_grdecl.GRID_KEYWORDS) | ({properties.upper()} if properties else set())
        deck = _grdecl.read_deck(paths, keep)
        corners, active, values = _grdecl.deck_grid(deck, properties, z_positive)
        return GridKwargs(corners=corners, active=active, values=values)
    xtgeo = _import("xtgeo")
    _grdecl.check_mapaxes(paths[0])  # xtgeo applies a degenerate one as NaN corners
    try:
        grid = xtgeo.grid_from_file(paths[0], fformat="grdecl")
    except _READ_ERRORS as e:
        cause = str(e).strip() or type(e).__name__
        raise InputError(f"path: cannot read the GRDECL grid {paths[0]!r} (xtgeo): {cause} ({type(e).__name__})") from e
    prop = None
    if properties is not None:
        causes = []
        for p in paths:
            try:
                prop = xtgeo.gridproperty_from_file(p, fformat="grdecl", name=properties, grid=grid)
                break
            except _READ_ERRORS as e:
                causes.append(f"{p!r}: {str(e).strip() or type(e).__name__}")
        if prop is None:
            raise InputError(f"properties: no property {properties!r} that xtgeo reads in {'; '.join(causes)}")
    return from_xtgeo_grid(grid, values=prop, z_positive=z_positive)


# --------------------------------------------------------------------------------------------- SEG-Y

#: The reader failures of segyio (and of a truncated or lying file) that become InputErrors.
_SEGY_ERRORS = (ValueError, OSError, RuntimeError, IndexError, KeyError, EOFError, MemoryError)
#: The sample format codes of the SEG-Y standard (rev. 2) that segyio reads; others it would read
#: as IBM floats after a warning, i.e. as wrong numbers.
_SEGY_FORMATS = {1: "IBM float", 2: "int32", 3: "int16", 5: "IEEE float32", 6: "IEEE float64", 8: "int8",
                 9: "int64", 10: "uint32", 11: "uint16", 12: "uint64", 16: "uint8"}


def from_segy(
    source: str | os.PathLike[str] | Any,
    iline: int = 189,
    xline: int = 193,
    z_positive: Literal["up", "down"] = "down",
    tolerance: float | None = None,
    lazy: bool = False,
) -> VolumeKwargs:
    """A post-stack 3-D SEG-Y cube as keyword arguments of :class:`geocull.Volume` (needs segyio);
    ``Volume.from_segy(source)`` builds the volume.

    source: a path or an open ``segyio.SegyFile`` (read as it is, e.g. after ``f.mmap()``).
    iline, xline: trace header bytes of the inline and crossline numbers (segyio's defaults).
    tolerance: how far (in the CDP coordinates' units, metres) a trace may lie from the regular
        grid fitted to all traces; None: 10 % of the smaller bin size, enough for coordinates
        rounded to whole metres (off by up to 0.71 m on 12.5 m bins).

    Axes: inline -> x, crossline -> y, sample -> z (order="xyz"; crossline-sorted files are
    transposed as a view). z: ``f.samples`` (the delay and sample interval of the headers, in the
    file's units: ms for time, m or ft for depth) with z_positive="down", so the first sample is the
    shallowest and the cube renders the right way up. x, y: the CDP_X / CDP_Y trace headers scaled by
    their SourceGroupScalar (negative = divide). The trace at (inline index a, crossline index b)
    must lie at ``P0 + a*u + b*v`` for two perpendicular steps u, v fitted by least squares to every
    trace present (within ``tolerance``): spacing (|u|, |v|), rotation = the direction of u (degrees
    counter-clockwise from +x), origin = P0. **Rotated surveys** are supported at any angle; a
    survey whose crossline step points clockwise of the inline step (a left-handed grid) gets
    ``yflip=True`` (the Volume reverses its crossline axis, a view; crossline indices still count in
    the file's order). Skewed (non-perpendicular) or irregular geometries, pre-stack (several
    offsets) and unstructured files are InputErrors.

    No-data: dead traces (trace identification code 2) and missing traces (a file whose traces do
    not fill the inline x crossline rectangle) are NaN; the geometry comes from the traces present.
    inlines, crosslines, samples: the survey's numbers (``f.ilines``, ``f.xlines``, ``f.samples``)
    in the file's order, which :meth:`geocull.Scene.add_slice` takes as ``inline=``, ``crossline=``,
    ``time=`` / ``depth=``.

    Every reader failure (a missing, truncated or damaged file, headers that contradict the file
    size, an unknown sample format code) is an :class:`geocull.InputError` naming ``source``, the
    path and the cause. The samples are read once (``segyio.tools.cube`` for complete files), which
    the Volume copies once into its buffer. ``lazy``: no sample is read; ``values`` is then a
    ``geocull._lazy.SegyCube`` reading the traces of a box when sliced (a path stays open while it lives).
    """
    segyio = _import("segyio")
    z_sign(z_positive)
    tol = None
    if tolerance is not None:
        if isinstance(tolerance, bool) or not isinstance(tolerance, int | float | np.floating | np.integer):
            raise InputError(f"tolerance: {tolerance!r} is not a number")
        tol = float(tolerance)
        if not (math.isfinite(tol) and tol > 0):
            raise InputError(f"tolerance: {tol!r}; expected a positive distance (metres)")
    if isinstance(source, str | os.PathLike):
        where = os.fspath(source)
        if not os.path.isfile(where):
            raise InputError(f"source: no such file {where!r}")
        def kwargs(sparse: bool) -> VolumeKwargs:
            f, kw = segyio.open(where, iline=iline, xline=xline, ignore_geometry=sparse), None
            try:  # a lazy cube owns the open file
                kw = _segy_kwargs(segyio, f, z_positive, tol, iline, xline, sparse=sparse, lazy=lazy)
                return kw
            finally:
                if not (lazy and kw is not None):
                    f.close()

        try:
            try:
                return kwargs(False)
            except ValueError as e:
                if isinstance(e, InputError) or "should match the number of traces" not in str(e):
                    raise
            # Missing traces: segyio cannot infer the geometry; read the traces as they come.
            return kwargs(True)
        except InputError as e:
            msg = str(e).removeprefix("source: ")
            raise InputError(f"source: {where!r}: {msg}") from None
        except _SEGY_ERRORS as e:
            cause = str(e).strip() or type(e).__name__
            raise InputError(f"source: cannot read the SEG-Y file {where!r}: {cause} ({type(e).__name__})") from e
    if not hasattr(source, "trace") or not hasattr(source, "header"):
        raise InputError(f"source: {type(source).__name__} is neither a path nor an open segyio.SegyFile")
    try:
        return _segy_kwargs(segyio, source, z_positive, tol, iline, xline, bool(source.unstructured), lazy, False)
    except InputError:
        raise
    except _SEGY_ERRORS as e:
        cause = str(e).strip() or type(e).__name__
        raise InputError(f"source: cannot read the open SEG-Y file: {cause} ({type(e).__name__})") from e


def _segy_kwargs(
    segyio: Any, f: Any, z_positive: Literal["up", "down"], tol: float | None, iline: int, xline: int,
    sparse: bool = False, lazy: bool = False, owned: bool = True,
) -> VolumeKwargs:
    fmt = int(f.bin[segyio.BinField.Format])
    if fmt not in _SEGY_FORMATS:
        raise InputError(f"source: the binary header's sample format code is {fmt}, not one of the SEG-Y "
                         f"formats {sorted(_SEGY_FORMATS)} (a damaged header?)")
    tf = segyio.TraceField
    samples = np.asarray(f.samples, dtype=np.float64)
    ns = len(samples)
    if sparse:
        # Traces as they come: each placed by its own inline / crossline numbers.
        til = np.asarray(f.attributes(iline)[:])
        txl = np.asarray(f.attributes(xline)[:])
        il, ta = np.unique(til, return_inverse=True)
        xl, tb = np.unique(txl, return_inverse=True)
        if len(il) * len(xl) > 4 * max(f.tracecount, 1) + 16:
            raise InputError(f"source: {f.tracecount} traces spread over {len(il)} inlines x {len(xl)} crosslines "
                             "(unstructured, or the wrong iline=/xline= header bytes)")
        pos = ta * len(xl) + tb
        if len(np.unique(pos)) != len(pos):
            raise InputError("source: several traces share an inline / crossline pair (pre-stack, or the wrong "
                             "iline=/xline= header bytes)")
        if lazy:
            cube: Any = _lazy.SegyCube(f, ta, tb, (len(il), len(xl), ns), owned)
        else:
            raw = np.asarray(f.trace.raw[:])
            if raw.shape != (f.tracecount, ns):
                raise InputError(f"source: read {raw.shape} samples, expected {f.tracecount} traces x {ns}")
            cube = np.full((len(il), len(xl), ns), np.nan, dtype=raw.dtype if raw.dtype.kind == "f" else np.float64)
            cube[ta, tb] = raw
        ta_all, tb_all = ta, tb
    else:
        if f.unstructured:
            raise InputError("source: the SEG-Y file has no inline/crossline geometry (unstructured); "
                             "check iline=/xline=")
        if len(f.offsets) != 1:
            raise InputError(f"source: a pre-stack file ({len(f.offsets)} offsets); geocull reads post-stack cubes")
        il, xl = np.asarray(f.ilines), np.asarray(f.xlines)
        inline_sorted = f.sorting == segyio.TraceSortingFormat.INLINE_SORTING
        if not lazy:
            cube = segyio.tools.cube(f)  # (inlines, crosslines, samples) or (crosslines, inlines, samples)
            if not inline_sorted:
                cube = cube.transpose(1, 0, 2)
        na_, nb_ = len(il), len(xl)
        a, b = np.meshgrid(np.arange(na_), np.arange(nb_), indexing="ij")  # (na, nb)
        if inline_sorted:
            ta_all, tb_all = a.ravel(), b.ravel()  # trace t in file order -> (a, b)
        else:
            ta_all, tb_all = a.T.ravel(), b.T.ravel()
        if lazy:
            cube = _lazy.SegyCube(f, ta_all, tb_all, (na_, nb_, ns), owned)
    na, nb = len(il), len(xl)
    if min(na, nb, ns) < 2:
        raise InputError(f"source: {na} inlines x {nb} crosslines x {ns} samples; a volume needs 2 of each")
    dz = np.diff(samples)
    if not np.allclose(dz, dz[0], rtol=1e-6) or dz[0] <= 0:
        raise InputError("source: the samples are not regularly spaced")
    x = np.asarray(f.attributes(tf.CDP_X)[:], dtype=np.float64)
    y = np.asarray(f.attributes(tf.CDP_Y)[:], dtype=np.float64)
    sc = np.asarray(f.attributes(tf.SourceGroupScalar)[:], dtype=np.float64)
    scale = np.where(sc < 0, 1.0 / np.abs(np.where(sc == 0, 1, sc)), np.where(sc == 0, 1.0, sc))
    x, y = x * scale, y * scale
    dead = np.asarray(f.attributes(tf.TraceIdentificationCode)[:]) == 2
    if dead.any() and lazy:
        cube.traces[ta_all[dead], tb_all[dead]] = -1
    elif dead.any():
        if cube.dtype.kind != "f":
            cube = cube.astype(np.float64)
        cube[ta_all[dead], tb_all[dead]] = np.nan
    live = ~dead if (~dead).sum() >= 3 else np.ones_like(dead)  # dead traces often carry no coordinates
    p0, u, v, rotation, left_handed = fit_survey(ta_all[live], tb_all[live], x[live], y[live], na, nb, tol)
    lu, lv = float(np.hypot(*u)), float(np.hypot(*v))
    return VolumeKwargs(
        values=cube,
        origin=(float(p0[0]), float(p0[1]), float(samples[0])),
        spacing=(lu, lv, float(dz[0])),
        order="xyz",
        z_positive=z_positive,
        rotation=rotation,
        yflip=left_handed,
        inlines=il.copy(),
        crosslines=xl.copy(),
        samples=samples,
    )


# --------------------------------------------------------------------------------------------- meshes


def to_pyvista(scene: SceneLike, id: int) -> Any:
    """Object ``id`` of ``scene`` as a ``pyvista.PolyData`` (fine triangles, world coordinates, offset
    applied; ``field_data``: name, kind, color, object_id), which ``Scene.add_mesh`` takes back."""
    from . import pyvista as gpv

    return gpv.to_polydata(scene, id)


def to_trimesh(scene: SceneLike, id: int) -> Any:
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
