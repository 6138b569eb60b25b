"""Argument coercion and checking shared by the public wrappers: numpy in, plain Python values out.

Every helper takes the value and ``arg``, the argument's name, and raises
:class:`geocull.InputError` whose message starts with that name. Only types and shapes are checked
here; every value and range check (finite, positive, in range, index bounds) has one owner, the
Rust core, which raises the same InputError naming the argument.
"""

from __future__ import annotations

import numbers
import warnings
from dataclasses import dataclass
from typing import Any, Protocol, TypeAlias, runtime_checkable

import numpy as np

from ._errors import GeocullWarning, InputError

__all__ = [
    "MAX_COORD",
    "FLOAT_KINDS",
    "INT_KINDS",
    "checked_array",
    "first_infinite",
    "refuse_infinite",
    "float_array",
    "unmasked",
    "heights",
    "vertices",
    "int_array",
    "flags",
    "vec",
    "vec2",
    "vec3",
    "number",
    "integer",
    "expect_instance",
    "color",
    "Coloring",
    "coloring",
    "cmap_table",
    "name",
    "boolean",
    "TrimeshLike",
    "PolyDataLike",
    "MeshLike",
    "MeshArrays",
    "mesh_arrays",
]

#: Largest coordinate magnitude (metres) accepted anywhere: the core's ``camera::MAX_COORD``
#: (src/camera.rs), which every object and the camera check in Rust; volumes are checked here.
MAX_COORD = 1e12

FLOAT_KINDS = "fiu"  # numpy dtype kinds accepted as real numbers: float, signed int, unsigned int
INT_KINDS = "iu"  # numpy dtype kinds accepted as integers: signed int, unsigned int


def checked_array(x: Any, arg: str, ndim: int, last: int | None = None, kinds: str = FLOAT_KINDS) -> np.ndarray:
    """numpy view of ``x`` (no copy) with rank ``ndim``, last axis ``last`` (if given), dtype kind in ``kinds``."""
    try:
        a = np.asarray(x)
    except Exception as e:  # ragged lists, objects that refuse conversion
        raise InputError(f"{arg}: cannot be read as an array ({e})") from None
    if a.dtype.kind not in kinds:
        want = {INT_KINDS: "integers", FLOAT_KINDS: "real numbers (float or int)", "b": "bools",
                "b" + INT_KINDS: "bools or integers"}.get(kinds, f"dtype kinds {kinds!r}")
        raise InputError(f"{arg}: dtype {a.dtype} is not supported; expected {want}")
    if a.ndim != ndim or (last is not None and a.shape[-1] != last):
        want = f"({', '.join(['n'] * (ndim - 1) + [str(last)])})" if last is not None else f"{ndim}-D"
        raise InputError(f"{arg}: shape {a.shape} is not {want}")
    return a


def first_infinite(a: np.ndarray) -> tuple[int, ...] | None:
    """Index of the first +-inf element of a float array in its own C order, or None (volumes: a
    slice of the first axis at a time, no full-size temporary)."""
    if a.dtype.kind != "f" or a.size == 0:
        return None
    if a.ndim < 3:
        bad = np.isinf(a)
        return tuple(int(i) for i in np.argwhere(bad)[0]) if bad.any() else None
    for k in range(a.shape[0]):
        bad = np.isinf(a[k])
        if bad.any():
            return (k, *(int(i) for i in np.argwhere(bad)[0]))
    return None


def refuse_infinite(a: np.ndarray, arg: str) -> None:
    """InputError naming ``arg[index]``, the first +-inf element of ``a`` in the array's own index
    order. geocull's one rule for infinities in sampled data (volume samples, height-field z,
    colouring values): refused, with NaN (or a masked element) as no data. The core refuses them
    too, but names some by their stored or flat index; this names the caller's."""
    idx = first_infinite(a)
    if idx is not None:
        raise InputError(f"{arg}[{', '.join(map(str, idx))}] is {a[idx]}; use NaN for no data (infinite values are "
                         "refused)")


def float_array(x: Any, arg: str, ndim: int, last: int | None = None) -> np.ndarray:
    """C-contiguous, aligned float64 copy (or view) of a real-valued array checked as by
    :func:`checked_array` (buffers from other processes, e.g. Dask's out-of-band pickles, may be
    misaligned, which the core cannot read in place)."""
    a = checked_array(x, arg, ndim, last)
    return np.require(a, dtype=np.float64, requirements=["C", "A"])


def unmasked(x: Any, arg: str) -> tuple[Any, np.ndarray | None]:
    """``(data, mask)`` of ``x``: for a ``numpy.ma.MaskedArray`` its data and its boolean mask
    (None when nothing is masked), else ``(x, None)``. ``np.asarray`` would silently drop the mask."""
    if not isinstance(x, np.ma.MaskedArray):
        return x, None
    mask = np.ma.getmaskarray(x)
    return np.ma.getdata(x), (mask if mask.any() else None)


def heights(z: Any, null_value: float | None, arg: str = "z") -> np.ndarray:
    """C-contiguous float64 (ny, nx) heights with the no-data samples as NaN: the masked samples of a
    ``numpy.ma.MaskedArray``, and the samples equal to ``null_value`` compared in ``z``'s own dtype
    (float32 cannot hold -999.1, so a float32 ``z`` holds ``float32(-999.1)``, which an f64
    comparison with -999.1 would never match). For an integer ``z`` only an integral
    ``null_value`` can match (it is not rounded onto an integer). The value checks stay in Rust."""
    data, mask = unmasked(z, arg)
    a = checked_array(data, arg, 2)
    null = np.zeros(a.shape, bool) if mask is None else mask.copy()
    if null_value is not None and not np.isnan(null_value):
        if a.dtype.kind == "f":
            with np.errstate(over="ignore"):
                nv = np.asarray(null_value, dtype=a.dtype)
            if np.isfinite(nv):  # a null_value beyond the dtype's range matches nothing
                null |= a == nv
        elif float(null_value).is_integer():
            info = np.iinfo(a.dtype)
            if info.min <= null_value <= info.max:
                null |= a == np.asarray(int(null_value), dtype=a.dtype)
    out = np.require(a, dtype=np.float64, requirements=["C", "A"])
    if null.any():
        if out is a or np.shares_memory(out, a):
            out = out.copy()
        out[null] = np.nan
    return out


def vertices(v: Any, arg: str = "vertices") -> np.ndarray:
    """C-contiguous float64 (n, 3) vertices; a masked vertex has no position, so a
    ``numpy.ma.MaskedArray`` with a masked element is an InputError naming the first one."""
    data, mask = unmasked(v, arg)
    a = float_array(data, arg, 2, 3)
    if mask is not None:
        i, j = (int(k) for k in np.argwhere(mask)[0])
        raise InputError(f"{arg}[{i}, {j}] is masked; a mesh vertex needs a position (fill or drop it)")
    return a


def int_array(x: Any, arg: str, ndim: int, last: int | None = None) -> np.ndarray:
    """numpy view of an integer-valued array (signed or unsigned, dtype kept) checked as by :func:`checked_array`."""
    return checked_array(x, arg, ndim, last, kinds=INT_KINDS)


def flags(x: Any, arg: str, ndim: int) -> np.ndarray:
    """C-contiguous bool array of rank ``ndim`` from bools or integers (integers as Eclipse's ACTNUM
    and xtgeo's actnum: 0 = False, any other value = True); other dtypes are an InputError naming
    ``arg`` that says so."""
    a = checked_array(x, arg, ndim, kinds="b" + INT_KINDS)
    return np.ascontiguousarray(a if a.dtype.kind == "b" else a != 0)


def vec(x: Any, arg: str, n: int) -> tuple[float, ...]:
    """Tuple of ``n`` Python floats from a length-``n`` 1-D sequence or array of real numbers."""
    a = checked_array(x, arg, 1, n)
    return tuple(float(v) for v in a)


def vec2(x: Any, arg: str) -> tuple[float, float]:
    """:func:`vec` with n = 2, typed as a pair (e.g. (x, y) or (dx, dy))."""
    u, v = vec(x, arg, 2)
    return u, v


def vec3(x: Any, arg: str) -> tuple[float, float, float]:
    """:func:`vec` with n = 3, typed as a triple (e.g. a point (x, y, z) or a colour (r, g, b))."""
    u, v, w = vec(x, arg, 3)
    return u, v, w


def number(x: Any, arg: str) -> float:
    """Python float of a real number (``numbers.Real``, not bool); finiteness is checked in Rust."""
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise InputError(f"{arg}: {x!r} is not a real number")
    return float(x)


def z_sign(z_positive: Any) -> float:
    """-1.0 for ``z_positive="down"`` (depths, drawn at z = -depth), 1.0 for "up"; else an
    InputError naming ``z_positive``."""
    if z_positive not in ("up", "down"):
        raise InputError(f"z_positive: {z_positive!r}; expected 'up' or 'down'")
    return -1.0 if z_positive == "down" else 1.0


def integer(x: Any, arg: str) -> int:
    """Python int of an integer (``numbers.Integral``, not bool) that fits a signed 64-bit integer
    (the core's argument type; it checks the range)."""
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise InputError(f"{arg}: {x!r} is not an integer")
    v = int(x)
    if not -(2**63) <= v < 2**63:
        raise InputError(f"{arg}: {v} is too large")
    return v


def fail_type(x: Any, arg: str, expected: str) -> Any:
    """Raises InputError: ``arg`` is ``x``, which is not ``expected`` (e.g. "a string")."""
    raise InputError(f"{arg}: {x!r} is not {expected}")


def expect_instance(x: Any, cls: type, arg: str) -> Any:
    """``x`` itself if it is an instance of ``cls`` (a geocull class), else InputError naming the argument."""
    if not isinstance(x, cls):
        raise InputError(f"{arg}: expected a geocull.{cls.__name__}, got {type(x).__name__}")
    return x


def color(c: Any) -> tuple[float, float, float] | None:
    """None, or an (r, g, b) tuple of floats from a length-3 sequence (the [0, 1] range is checked in Rust)."""
    return None if c is None else vec3(c, "color")


#: What the extension's add functions take for a colouring: (color_by, values, colour-map name,
#: colour-map table (n, 3) float64, clim, nan_color); None = the object kind's default.
Coloring: TypeAlias = tuple[
    str, np.ndarray | None, str | None, np.ndarray | None, tuple[float, float] | None,
    tuple[float, float, float] | None,
]


def cmap_table(cmap: Any) -> tuple[str | None, np.ndarray | None]:
    """(name, table) of a colour map argument: a name (resolved by matplotlib when it is installed
    and knows it, so every matplotlib colour map works; else passed on for the core's built-ins), a
    matplotlib ``Colormap`` (sampled at 256 points), or an (n, 3) / (n, 4) array of RGB(A) rows in
    [0, 1] (alpha dropped). None: the default."""
    if cmap is None:
        return None, None
    if isinstance(cmap, str):
        try:
            import matplotlib
        except ImportError:
            return cmap, None
        try:
            cmap = matplotlib.colormaps[cmap]
        except KeyError:
            return cmap, None  # the core names the argument and lists its built-ins
    if callable(cmap) and hasattr(cmap, "N"):  # a matplotlib Colormap
        rgba = np.asarray(cmap(np.linspace(0.0, 1.0, 256)), dtype=np.float64)
        return str(getattr(cmap, "name", "custom")), np.ascontiguousarray(rgba[:, :3])
    a = checked_array(cmap, "cmap", 2)
    if a.shape[1] not in (3, 4):
        raise InputError(f"cmap: shape {a.shape} is not (n, 3) or (n, 4) RGB(A) rows")
    return None, np.ascontiguousarray(a[:, :3], dtype=np.float64)


def coloring(
    color_by: Any, values: Any, cmap: Any, clim: Any, nan_color: Any, ndim: int
) -> Coloring | None:
    """The colouring tuple of an add function, or None when nothing was asked. ``values`` (rank
    ``ndim``; masked samples become NaN) implies ``color_by="values"``; a colour map or range alone
    implies ``"z"``."""
    if color_by is None and values is None and cmap is None and clim is None and nan_color is None:
        return None
    if color_by is None:
        color_by = "values" if values is not None else "z"
    if not isinstance(color_by, str):
        raise InputError(f"color_by: {color_by!r} is not a string")
    vals = None
    if values is not None:
        data, mask = unmasked(values, "values")
        vals = float_array(data, "values", ndim)
        if mask is not None:
            vals = vals.copy() if np.shares_memory(vals, data) else vals
            vals[mask] = np.nan
        refuse_infinite(vals, "values")
    name_, table = cmap_table(cmap)
    lim = None if clim is None else vec2(clim, "clim")
    nan = None if nan_color is None else vec3(nan_color, "nan_color")
    return (color_by, vals, name_, table, lim, nan)


def name(n: Any) -> str | None:
    """None or a str (an object's name), else InputError."""
    if n is not None and not isinstance(n, str):
        raise InputError(f"name: {n!r} is not a string")
    return n


def boolean(x: Any, arg: str, hint: str = "") -> bool:
    """Python bool of a ``bool`` or ``numpy.bool_`` (an int such as xtgeo's 1 / -1 flags is refused:
    ``bool(-1)`` and ``bool(1)`` are both True)."""
    if not isinstance(x, bool | np.bool_):
        more = f" ({hint})" if hint else ""
        raise InputError(f"{arg}: {x!r} is not a bool{more}")
    return bool(x)


@runtime_checkable
class TrimeshLike(Protocol):
    """What :meth:`geocull.Scene.add_mesh` reads of a ``trimesh.Trimesh``: (n, 3) ``vertices`` and
    (m, 3) ``faces``."""

    @property
    def vertices(self) -> Any: ...
    @property
    def faces(self) -> Any: ...


@runtime_checkable
class PolyDataLike(Protocol):
    """What :meth:`geocull.Scene.add_mesh` reads of a ``pyvista.PolyData``: ``points``, the flat
    ``faces`` cell array and ``triangulate()``."""

    @property
    def points(self) -> Any: ...
    @property
    def faces(self) -> Any: ...
    def triangulate(self) -> Any: ...


#: A mesh object :meth:`geocull.Scene.add_mesh` takes in place of (vertices, faces).
MeshLike: TypeAlias = TrimeshLike | PolyDataLike


@dataclass
class MeshArrays:
    """Vertices (n, 3), faces (m, 3) and the name / colour a mesh object carries (None if none)."""

    vertices: np.ndarray
    faces: np.ndarray
    name: str | None = None
    color: tuple[float, float, float] | None = None


def _field(pd: Any, key: str) -> Any:
    fd = getattr(pd, "field_data", None)
    try:
        return np.asarray(fd[key]).ravel() if fd is not None and key in fd.keys() else None
    except Exception:  # field data that cannot be read is no metadata
        return None



def surface_of(ds: Any) -> Any:
    """The outer surface of a PyVista dataset (``extract_surface`` with VTK's dataset-surface
    filter, the default of PyVista < 0.47, named there so that newer versions neither warn nor
    change it)."""
    try:
        return ds.extract_surface(algorithm="dataset_surface")
    except TypeError:  # PyVista < 0.47 has no `algorithm`
        return ds.extract_surface()

def mesh_arrays(x: Any, arg: str = "vertices") -> MeshArrays | None:
    """The triangles of a mesh object, or None when ``x`` is not one (an array, a list, ...).

    Recognised by duck typing, so trimesh and PyVista are never imported here:
    * a PyVista dataset (``points``, ``faces``, ``triangulate``; others with ``extract_surface`` are
      reduced to their surface first): polygons and strips triangulated; line and vertex cells
      ignored with a GeocullWarning; name / color from ``field_data`` when present;
    * a ``trimesh.Trimesh`` (``vertices`` and ``faces`` attributes).
    """
    if isinstance(x, np.ndarray | list | tuple):
        return None
    if not hasattr(x, "faces") and hasattr(x, "extract_surface") and hasattr(x, "points"):
        x = surface_of(x)  # a PyVista dataset other than PolyData (e.g. an UnstructuredGrid)
    if hasattr(x, "points") and hasattr(x, "faces") and hasattr(x, "triangulate"):
        n_lines, n_verts = int(getattr(x, "n_lines", 0) or 0), int(getattr(x, "n_verts", 0) or 0)
        if n_lines or n_verts:
            warnings.warn(
                f"{arg}: the {type(x).__name__}'s {n_lines} line and {n_verts} vertex cells are ignored "
                "(add_mesh takes surfaces; polygons and strips are triangulated)",
                GeocullWarning,
                stacklevel=3,
            )
        if not getattr(x, "is_all_triangles", False):
            x = x.triangulate()
        cells = np.asarray(x.faces, dtype=np.int64)
        if cells.size % 4 or (cells.size and not np.all(cells.reshape(-1, 4)[:, 0] == 3)):
            raise InputError(f"{arg}: the {type(x).__name__} still has non-triangle cells after triangulate()")
        faces = cells.reshape(-1, 4)[:, 1:]
        name = _field(x, "name")
        col = _field(x, "color")
        return MeshArrays(
            np.asarray(x.points),
            faces,
            None if name is None or name.size == 0 else str(name[0]),
            None if col is None or col.size != 3 else (float(col[0]), float(col[1]), float(col[2])),
        )
    if hasattr(x, "vertices") and hasattr(x, "faces"):
        return MeshArrays(np.asarray(x.vertices), np.asarray(x.faces))
    return None
