"""Scalar volumes on regular grids, with a lazily built min/max octree (for isosurfaces, see
:mod:`geocull.iso`)."""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from . import _convert as cv
from . import _geocull, _lazy
from ._errors import InputError

if TYPE_CHECKING:
    from ._geocull import OctreeNodes

__all__ = ["Volume", "VolumeOrder", "ZPositive", "X_DIMS", "Y_DIMS", "Z_DIMS", "DOWN_DIMS"]

#: Index order of a volume's values: "zyx" = ``values[k, j, i]`` (numpy's (nz, ny, nx)); "xyz" =
#: ``values[i, j, k]`` (segyio's (inline, crossline, sample), xtgeo's ``Cube.values``).
VolumeOrder = Literal["zyx", "xyz"]
#: Direction of the z (sample) axis: "up", or "down" for depth / time (the sample index grows downwards).
ZPositive = Literal["up", "down"]

#: xarray dimension names (compared in lower case) read as the x, y and z axes of a volume.
X_DIMS = frozenset({"x", "easting", "inline", "iline", "il", "inlines"})
Y_DIMS = frozenset({"y", "northing", "crossline", "xline", "xl", "crosslines"})
Z_DIMS = frozenset({"z", "depth", "time", "twt", "sample", "samples", "tvd", "tvdss"})
#: z dimension names whose axis grows downwards (z_positive="down" unless given).
DOWN_DIMS = frozenset({"depth", "time", "twt", "sample", "samples", "tvd", "tvdss"})
#: Dimension names whose coordinates are line numbers, not metres (origin and spacing must be given).
_LINE_DIMS = frozenset({"inline", "iline", "il", "inlines", "crossline", "xline", "xl", "crosslines"})


def _values(values: Any) -> np.ndarray:
    """A float32/float64 3-D view of ``values`` (numpy, np.memmap, anything with ``__array__``) in
    its own index order and strides: transposes and flips are left to the core, which reads the
    samples once into its buffer. Copied here only when the dtype demands it (other real dtypes,
    non-native byte order) or a mask must become NaN."""
    values, mask = cv.unmasked(values, "values")
    try:
        a = np.asarray(values)
    except Exception as e:
        raise InputError(f"values: cannot be read as an array ({e})") from None
    if a.ndim != 3:
        raise InputError(f"values: shape {a.shape} is not 3-D")
    if a.dtype.kind not in "fiu" or a.dtype.kind == "c":
        raise InputError(f"values: dtype {a.dtype} is not supported; expected real numbers")
    if min(a.shape) < 2:
        raise InputError(f"values: shape {a.shape} needs at least 2 samples per axis")
    if mask is not None:  # masked samples are no data (NaN): a float copy with them set
        a = np.array(a, dtype=a.dtype if a.dtype.kind == "f" and a.dtype.itemsize >= 4 else np.float64)
        a[mask] = np.nan
    if a.dtype.kind == "f" and a.dtype.itemsize != 8:  # float64: the core checks while it reads them
        cv.refuse_infinite(a, "values")
    # By kind and size, not by dtype identity: a big-endian '>f8' is not `== np.float64` but must
    # keep float64's precision (its residuals) as a native one does.
    if a.dtype.kind == "f" and a.dtype.itemsize in (4, 8):
        if not a.dtype.isnative:
            a = a.astype(a.dtype.newbyteorder("="))
        return a
    # float16 fits float32 exactly; long double and integers go through float64, whose residuals
    # keep them (int32 / int64 samples of 1e8 and 1e8 + 1 differ in float64 but not in float32).
    return a.astype(np.float32 if a.dtype.kind == "f" and a.dtype.itemsize < 4 else np.float64)


#: The largest float32: float64 samples farther than this from the volume's midrange cannot be
#: stored as float32 residuals.
_F32_MAX = float(np.finfo(np.float32).max)


def _where(idx: Any) -> str:
    return ", ".join(str(int(i)) for i in idx)


def _range_error(a: np.ndarray) -> InputError:
    """The InputError of float64 values whose range does not fit float32 residuals about their
    midrange, naming the first sample truly out of range: the first one farther than float32's
    range from the finite samples' median (one always is: a range over twice float32's has an end
    beyond it on one side of the median), in the values' own index order."""
    fin = a[np.isfinite(a)]
    med = float(np.median(fin)) if fin.size else 0.0
    for k in range(a.shape[0]):
        with np.errstate(over="ignore", invalid="ignore"):
            far = np.abs(a[k].astype(np.float64) - med) > _F32_MAX
        if far.any():
            idx = (k, *(int(i) for i in np.argwhere(far)[0]))
            return InputError(
                f"values[{_where(idx)}] is {a[idx]:g}, over {_F32_MAX:.3g} from the median of the values "
                f"({med:g}): the volume's value range does not fit float32 even about its midrange (float64 "
                "values are stored as float32 residuals)")
    return InputError("values: the volume's value range does not fit float32 even about its midrange")


def _is_dataarray(x: Any) -> bool:
    return all(hasattr(x, k) for k in ("dims", "coords", "transpose", "isel", "variable"))


def _regular(c: np.ndarray, dim: str) -> tuple[float, float]:
    """(first value, step) of a regular 1-D coordinate, else InputError."""
    d = np.diff(c.astype(np.float64))
    if not (np.all(np.isfinite(d)) and np.allclose(d, d[0], rtol=1e-6, atol=0.0)) or d[0] == 0:
        raise InputError(f"values: the coordinate of dim {dim!r} is not regularly spaced; pass origin and spacing")
    return float(c[0]), float(d[0])


def _from_dataarray(
    da: Any, origin: ArrayLike | None, spacing: ArrayLike | None, z_positive: ZPositive | None
) -> tuple[Any, tuple[float, float, float] | None, tuple[float, float, float] | None, ZPositive]:
    """A DataArray as (its samples as a (z, y, x) view, origin, spacing, z_positive), axes found by
    dim name (X_DIMS, Y_DIMS, Z_DIMS); origin and spacing from regular coordinates where not given
    (axes whose coordinate decreases are reversed, as views)."""
    axes: dict[str, str] = {}
    for d in da.dims:
        low = str(d).lower()
        for ax, names in (("x", X_DIMS), ("y", Y_DIMS), ("z", Z_DIMS)):
            if low in names:
                if ax in axes:
                    raise InputError(f"values: dims {axes[ax]!r} and {d!r} are both read as the {ax} axis")
                axes[ax] = d
    if len(axes) != 3 or len(da.dims) != 3:
        raise InputError(
            f"values: a DataArray's dims {tuple(da.dims)} must name an x, a y and a z axis "
            f"(x: {sorted(X_DIMS)}, y: {sorted(Y_DIMS)}, z: {sorted(Z_DIMS)}), or pass order="
        )
    zdim = axes["z"]
    zp: ZPositive = z_positive if z_positive is not None else ("down" if str(zdim).lower() in DOWN_DIMS else "up")
    da = da.transpose(axes["z"], axes["y"], axes["x"])
    o = [0.0, 0.0, 0.0]
    sp = [1.0, 1.0, 1.0]
    for k, dim in enumerate((axes["x"], axes["y"], axes["z"])):
        if dim not in da.coords or (origin is not None and spacing is not None):
            continue
        if str(dim).lower() in _LINE_DIMS:
            raise InputError(
                f"spacing: the DataArray's {dim!r} coordinate holds line numbers, not metres; pass origin and spacing "
                "(Volume.from_segy reads them from the trace headers)"
            )
        first, step = _regular(np.asarray(da.coords[dim].values), str(dim))
        if step < 0:  # a decreasing coordinate: reverse the axis (a view) so that the spacing is > 0
            da = da.isel({dim: slice(None, None, -1)})
            first, step = float(np.asarray(da.coords[dim].values)[0]), -step
        o[k], sp[k] = first, step
    return (
        # (A lazily backed DataArray's variable: slicing it reads only the slice; .data would load it.)
        da.variable if _lazy.backend_is_lazy(da) else da.data,
        None if origin is not None else (o[0], o[1], o[2]),
        None if spacing is not None else (sp[0], sp[1], sp[2]),
        zp,
    )


def _is_xtgeo_cube(x: Any) -> bool:
    """An xtgeo ``Cube``, recognised by its attributes (xtgeo is not imported)."""
    return not isinstance(x, np.ndarray) and all(
        hasattr(x, k) for k in ("ncol", "nrow", "nlay", "xinc", "yinc", "zinc", "xori", "yori", "zori", "ilines",
                                "xlines", "values")
    )


def _right_handed(
    a: np.ndarray, origin: tuple[float, float, float], ystep: float, rotation: float
) -> tuple[np.ndarray, tuple[float, float, float]]:
    """``a`` (indexed [.., j, ..] on axis 1 in either order) with its j axis reversed (a view) and
    the origin moved to the last row, for a grid whose rows run towards -y in its frame (xtgeo's
    yflip=-1, a left-handed survey), so that the grid is right-handed (a Volume has a rotation, no
    mirror)."""
    n = a.shape[1]
    t = math.radians(rotation)
    d = -(n - 1) * ystep  # the last row, at -(n-1)*ystep along the grid's y axis
    return a[:, ::-1], (origin[0] - math.sin(t) * d, origin[1] + math.cos(t) * d, origin[2])


def _numbers(x: Any, arg: str, n: int) -> np.ndarray | None:
    """A read-only 1-D copy of survey numbers (inline, crossline or sample numbers) of length ``n``."""
    if x is None:
        return None
    a = np.array(cv.checked_array(x, arg, 1))
    if a.shape != (n,):
        raise InputError(f"{arg}: {a.shape[0]} numbers for an axis of {n} samples")
    if a.dtype.kind == "f" and not np.isfinite(a).all():
        raise InputError(f"{arg}: not all finite")
    a.setflags(write=False)
    return a


def _check_extent(
    origin: tuple[float, float, float], spacing: tuple[float, float, float], n: tuple[int, int, int],
    rotation: float, yflip: bool, down: bool, arg: str | None = None,
) -> None:
    """InputError when a volume's origin or its grid's far corners (``n`` samples along x, y, z, as
    given) lie beyond :data:`geocull._convert.MAX_COORD`, the limit of every object's coordinates:
    naming ``origin`` (a component) or ``spacing`` (the grid reaches beyond it), or ``arg``
    (``data`` for bytes) with the same words. Non-finite values are left to the core's checks."""
    lim = cv.MAX_COORD
    for i, o in enumerate(origin):
        if math.isfinite(o) and abs(o) > lim:
            raise InputError(f"{arg or 'origin'}: {'origin ' if arg else ''}component {i} is {o:g}; "
                             f"coordinates must be within +-{lim:g}")
    if not all(math.isfinite(v) for v in (*origin, *spacing, rotation)):
        return
    t = math.radians(rotation)
    c, s = math.cos(t), math.sin(t)
    sy = -1.0 if yflip else 1.0
    ex, ey, ez = ((k - 1) * d for k, d in zip(n, spacing, strict=True))
    for corner, (u, v) in enumerate(((0.0, 0.0), (ex, 0.0), (0.0, sy * ey), (ex, sy * ey))):
        for ax, w in ((0, origin[0] + c * u - s * v), (1, origin[1] + s * u + c * v)):
            if abs(w) > lim:
                raise InputError(f"{arg or 'spacing'}: {'spacing ' if arg else ''}component {ax}: the grid reaches "
                                 f"{w:g} at corner {corner}; coordinates must be within +-{lim:g}")
    z = origin[2] + ez
    if abs(z) > lim:
        raise InputError(f"{arg or 'spacing'}: {'spacing ' if arg else ''}component 2: the grid reaches "
                         f"{-z if down else z:g} at its last sample; coordinates must be within +-{lim:g}")


class Volume:
    """A scalar field on a regular grid (a seismic cube, a property model), rendered as isosurfaces
    (:meth:`geocull.Renderer.render_isosurface`, :func:`geocull.extract_isosurface`). NaN samples, and
    the masked samples of a ``numpy.ma.MaskedArray``, are "no data" (no surface in cells touching them).
    +-inf samples are refused in every dtype and reader (InputError naming ``values[...]``, the first
    one in the values' own index order; ``source`` and the trace for SEG-Y), as in height fields
    and colouring values: use NaN for no data (xtgeo cubes' undefined values, >= 1e33, are NaN).

    values: a 3-D array, float32 or float64 in either byte order (other real dtypes are converted: float16
        to float32, long double and integers to float64, by value); numpy arrays, memory
        maps and numpy-backed xarray DataArrays are read in place (transposes and flips too) and
        copied exactly once, into the core's float32 buffer. float64 (and integer) values are stored
        as float32 *residuals* about :attr:`offset`, the midrange of the finite samples, so values
        such as 1e8 ± 1 keep their differences; float32 values are stored as they are (offset 0).
        Isovalues and the octree's min/max are in the values' own units either way.
    order: how ``values`` is indexed. "zyx" (default): ``values[k, j, i]``, numpy's (nz, ny, nx).
        "xyz": ``values[i, j, k]``: the first index is x, the second y, the last z. segyio's
        (inline, crossline, sample) cubes (``segyio.tools.cube``) and xtgeo's ``Cube.values``
        (ncol, nrow, nlay) go in as they are with order="xyz": inline -> x, crossline -> y,
        sample -> z (for a rotated survey, x and y are the grid's own axes; see ``rotation``).
    origin: (x0, y0, z0) position of ``values``' first sample (index [0, 0, 0]), metres; the origin
        and the grid's far corners lie within +-1e12 (``MAX_COORD``), as every object's coordinates.
        spacing: (dx, dy, dz) > 0 sample spacing. Sample (i, j, k) lies at
        ``(x0, y0) + R(rotation) @ (i*dx, j*dy)`` horizontally and at z0 + k*dz
        (z_positive="up") or at **z = -(z0 + k*dz)** (z_positive="down") vertically.
    z_positive: "up" (default), or "down" for depth / time cubes: the sample axis grows downwards
        and z0, dz are on that axis (z0 is the shallowest sample's depth or time, dz > 0), so the
        volume renders the right way up in geocull's z-up world, where a depth d is z = -d (the
        convention of :mod:`geocull.io`, whose xtgeo surfaces come in as z = -depth too).
    rotation: degrees counter-clockwise (seen from above) about the vertical through the origin, as
        xtgeo's and a rotated survey's; the octree and its node boxes stay in the grid's own frame
        (:meth:`nodes`), the renderer and :func:`geocull.extract_isosurface` turn them into the world.

    xarray: a DataArray's axes are found by dim name (lower case: x ``X_DIMS`` = x, easting, inline,
    iline, il; y ``Y_DIMS`` = y, northing, crossline, xline, xl; z ``Z_DIMS`` = z, depth, time, twt,
    sample, samples, tvd, tvdss) in any order; z_positive defaults to "down" for the depth / time /
    sample names. origin and spacing, where not given, come from the dims' coordinates when those
    are regular (a decreasing coordinate reverses that axis); inline / crossline coordinates are
    line numbers, not metres, so such arrays need origin and spacing (or :meth:`from_segy`). With
    ``order=`` given, the DataArray is read as a plain array in that order.

    yflip: True for a grid whose rows (its y / crossline axis) run towards -y in its own frame
        (xtgeo's ``yflip=-1``, a left-handed survey): sample (i, j, k) lies at
        ``(x0, y0) + R(rotation) @ (i*dx, -j*dy)``; the j axis is reversed as a view (no copy).
    inlines, crosslines, samples: optional survey numbers of the x, y and z axes in the values' own
        order ((nx,), (ny,), (nz,)): inline and crossline numbers, sample times (ms) or depths;
        :meth:`Scene.add_slice` takes ``inline=``, ``crossline=``, ``time=`` / ``depth=`` in them.

    lazy: read the samples on demand instead of copying them into memory (volumes larger than
        memory). None (default): lazily for zarr and dask arrays and xarray DataArrays backed by them
        (or by any lazily indexed file), into memory for numpy arrays and memory maps; True: lazily
        for any array that slices (an ``np.memmap`` is then never read whole); False: into memory.
        A lazy volume holds no samples: its octree is built in one streaming pass (slabs of about 128
        MiB) the first time it is needed; a slice (:meth:`Scene.add_slice`, each move of
        ``set_slice_index``) reads the 32³-sample bricks its plane crosses and keeps them in the
        cache when they take at most a quarter of ``cache_bytes`` (the next moves within the same
        32 samples read nothing; else it reads its plane alone); isosurfaces read, through that
        cache of bricks, only the nodes they extract (:meth:`Renderer.render_isosurface` extracts the
        visible ones; its ``stats["bytes_read"]`` counts the bytes a frame read). Its frames'
        default ``occluder_depth`` and ``cull_depth`` are ``max_depth() - 3`` (the octree's stored
        bricks, which need no sample). float64 and integer sources are read once more at
        construction for their midrange (:attr:`offset`). Pickling a lazy volume raises InputError
        (its samples may not fit in memory); :meth:`to_bytes` reads them all.
    cache_bytes: a lazy volume's brick-cache budget in bytes (default 512 MiB,
        ``DEFAULT_CACHE_BYTES``); the cache never holds more (0 keeps no brick).
    xtgeo: an ``xtgeo.Cube`` passed as ``values`` is read by :func:`geocull.io.from_xtgeo_cube`
    (undefined samples NaN, rotation, yflip, z positive down, its inline / crossline numbers and
    sample depths), recognised by its attributes; any other argument given wins.

    The stored grid (:attr:`shape`, :attr:`origin`, :attr:`spacing`) is (nz, ny, nx) with z
    upwards: for z_positive="down" its origin is the deepest sample. Slice and lens indices
    (:meth:`Scene.add_slice`, :meth:`Scene.add_lens`) count in the values' own order instead: sample
    0 is the first sample given (the shallowest for z_positive="down"), crossline 0 the first row
    (also for ``yflip``).
    """

    def __init__(
        self,
        values: ArrayLike | Any,  # also zarr / dask arrays, DataArrays, xtgeo cubes
        origin: ArrayLike | None = None,
        spacing: ArrayLike | None = None,
        order: VolumeOrder | None = None,
        z_positive: ZPositive | None = None,
        rotation: float | None = None,
        *,
        yflip: bool | None = None,
        inlines: ArrayLike | None = None,
        crosslines: ArrayLike | None = None,
        samples: ArrayLike | None = None,
        lazy: bool | None = None,
        cache_bytes: int | None = None,
    ) -> None:
        use_lazy = None if lazy is None else cv.boolean(lazy, "lazy")
        if use_lazy is None:
            use_lazy = _lazy.is_lazy_source(values)
        if cache_bytes is not None and not use_lazy:
            raise InputError("cache_bytes: only a lazy volume has a brick cache (pass lazy=True, or a zarr / dask "
                             "array)")
        if _is_xtgeo_cube(values):  # an xtgeo Cube: its geometry and survey numbers, keywords winning
            from . import io

            kw = io.from_xtgeo_cube(values, z_positive=z_positive)
            values = kw["values"]
            origin = kw["origin"] if origin is None else origin
            spacing = kw["spacing"] if spacing is None else spacing
            order = kw["order"] if order is None else order
            z_positive = kw["z_positive"]
            rotation = kw["rotation"] if rotation is None else rotation
            yflip = kw["yflip"] if yflip is None else yflip
            inlines = kw["inlines"] if inlines is None else inlines
            crosslines = kw["crosslines"] if crosslines is None else crosslines
            samples = kw["samples"] if samples is None else samples
        o3 = None if origin is None else cv.vec3(origin, "origin")
        s3 = None if spacing is None else cv.vec3(spacing, "spacing")
        zp: str | None = z_positive
        if order is None and _is_dataarray(values):
            values, o3_, s3_, zp = _from_dataarray(values, o3, s3, z_positive)
            o3, s3 = o3 if o3 is not None else o3_, s3 if s3 is not None else s3_
            order = "zyx"
        for arg, v in (("order", order), ("z_positive", zp)):
            if v is not None and not isinstance(v, str):
                raise InputError(f"{arg}: {v!r} is not a string")
        rot = 0.0 if rotation is None else cv.number(rotation, "rotation")
        flip = False if yflip is None else cv.boolean(yflip, "yflip", hint="xtgeo's yflip=-1 is yflip=True")
        if use_lazy:
            self._init_lazy(values, o3, s3, order, zp, rot, flip, (inlines, crosslines, samples), cache_bytes)
            return
        a = given = _values(values)
        o = o3 if o3 is not None else (0.0, 0.0, 0.0)
        sp = s3 if s3 is not None else (1.0, 1.0, 1.0)
        if flip:  # rows towards -y: reverse the j axis (a view), origin on the last row (right-handed)
            a, o = _right_handed(a, o, sp[1], rot)
        # Lengths of the x, y, z axes of the values as given.
        if order in (None, "zyx"):
            n = (a.shape[2], a.shape[1], a.shape[0])
        else:
            n = (a.shape[0], a.shape[1], a.shape[2])
        _check_extent(o3 or (0.0, 0.0, 0.0), sp, n, rot, flip, (zp or "up") == "down")
        survey = tuple(
            _numbers(x, arg, k) for x, arg, k in ((inlines, "inlines", n[0]), (crosslines, "crosslines", n[1]),
                                                   (samples, "samples", n[2]))
        )
        try:
            self._v = _geocull.Volume(a, o, sp, order or "zyx", zp or "up", rot)
        except InputError as e:
            # The core names a float64 sample in its stored grid's order (z up, zyx): name the
            # values' own index, and for a range too wide the sample truly out of it.
            if not str(e).startswith("values["):
                raise
            cv.refuse_infinite(given, "values")
            raise _range_error(given) from None
        self._flip = (False, flip, (zp or "up") == "down")
        self._survey: tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None] = survey  # type: ignore[assignment]

    def _init_lazy(
        self, values: Any, o3: tuple[float, float, float] | None, s3: tuple[float, float, float] | None,
        order: str | None, zp: str | None, rot: float, flip: bool, numbers: tuple[Any, Any, Any],
        cache_bytes: int | None,
    ) -> None:
        """A lazy volume over ``values`` (see ``lazy=``): the checks of the resident path but the
        samples', a reader (``_lazy.BlockReader``) and the core's lazy volume."""
        if not all(hasattr(values, k) for k in ("shape", "dtype", "__getitem__")):
            raise InputError(f"values: a {type(values).__name__} cannot be read lazily; expected an array that "
                             "slices (zarr, dask, xarray, np.memmap)")
        arr = _lazy.array_of(values)
        shape, dt = _lazy.check_array(arr)
        o = o3 if o3 is not None else (0.0, 0.0, 0.0)
        sp = s3 if s3 is not None else (1.0, 1.0, 1.0)
        n = (shape[2], shape[1], shape[0]) if order in (None, "zyx") else shape
        if flip:  # rows towards -y: origin on the last row (the reader reverses the j axis)
            o = _right_handed(np.broadcast_to(np.float32(0), (1, n[1], 1)), o, sp[1], rot)[1]
        _check_extent(o3 or (0.0, 0.0, 0.0), sp, n, rot, flip, (zp or "up") == "down")
        survey = tuple(
            _numbers(x, arg, k) for x, arg, k in zip(numbers, ("inlines", "crosslines", "samples"), n, strict=True)
        )
        budget = _lazy.DEFAULT_CACHE_BYTES if cache_bytes is None else cv.integer(cache_bytes, "cache_bytes")
        if budget < 0:
            raise InputError(f"cache_bytes: {budget} is negative")
        wide = _lazy.wide(dt)
        offset = _lazy.midrange(arr) if wide else 0.0
        reader = _lazy.BlockReader(arr, order or "zyx", (zp or "up") == "down", flip, offset, wide)
        self._v = _geocull.Volume.lazy(reader, n, o, sp, zp or "up", offset, rot, budget)
        self._flip = (False, flip, (zp or "up") == "down")
        self._survey = survey  # type: ignore[assignment]

    @classmethod
    def from_segy(
        cls,
        source: str | os.PathLike[str] | Any,
        iline: int = 189,
        xline: int = 193,
        z_positive: ZPositive = "down",
        tolerance: float | None = None,
        lazy: bool = False,
        cache_bytes: int | None = None,
    ) -> Volume:
        """A post-stack 3-D SEG-Y cube (needs segyio): ``source`` is a path or an open
        ``segyio.SegyFile``; iline / xline: the trace header bytes of the inline and crossline numbers
        (segyio's defaults 189 / 193). See :func:`geocull.io.from_segy` for what is read: inline ->
        x, crossline -> y, sample -> z (``f.samples``, in the file's units: ms for time, m or ft for
        depth; z_positive="down"), origin and spacing from the CDP_X / CDP_Y headers (with their
        scalar), rotation from the inline direction; ``tolerance`` (metres, default 10 % of the
        smaller bin) how far a trace may lie off the fitted grid (coordinates rounded to whole
        metres load). Rotated surveys are supported when their inline and crossline axes are
        perpendicular (either handedness); dead and missing traces are NaN; skewed, irregular,
        unstructured and pre-stack files, and every reader failure (truncated file, headers that
        contradict it), are InputErrors naming ``source`` and the path. The volume carries the
        survey's numbers (:attr:`inlines`, :attr:`crosslines`, :attr:`samples`).

        lazy=True: the file is not read (only its headers): a lazy volume (see :class:`Volume`'s
        ``lazy``) whose reads take, for a box, only its traces and of each only the samples asked
        for (a path stays open while the volume lives); cache_bytes: its brick cache. Infinite
        samples are then refused when the octree's pass meets them (InputError naming ``values``)."""
        from . import io

        use_lazy = cv.boolean(lazy, "lazy")
        kw = io.from_segy(source, iline=iline, xline=xline, z_positive=z_positive, tolerance=tolerance,
                          lazy=use_lazy)
        if use_lazy:
            return cls(**kw, lazy=True, cache_bytes=cache_bytes)
        idx = cv.first_infinite(kw["values"])
        if idx is not None:  # the rule of every volume, named for the file (inline, crossline, sample)
            k = idx[2]
            where = repr(os.fspath(source)) if isinstance(source, str | os.PathLike) else "the open SEG-Y file"
            il, xl, sm = (x[n] if x is not None else n for x, n in zip(
                (kw["inlines"], kw["crosslines"], kw["samples"]), idx, strict=True))
            raise InputError(
                f"source: {where}: inline {il:g}, crossline {xl:g}, sample {k} (at {sm:g} in the file's units) is "
                f"{kw['values'][idx]}; infinite samples are refused (NaN is no data; dead and missing traces are "
                "read as NaN)")
        return cls(**kw)

    @classmethod
    def _wrap(cls, inner: _geocull.Volume) -> Volume:
        v = cls.__new__(cls)
        v._v = inner
        v._flip = (False, False, False)
        v._survey = (None, None, None)
        return v

    @staticmethod
    def _restore(data: bytes, flip: tuple[bool, bool, bool], survey: tuple[Any, Any, Any]) -> Volume:
        """Unpickling: the core's bytes and the Python side's index order and survey numbers."""
        v = Volume.from_bytes(data)
        nz, ny, nx = v.shape
        try:  # a damaged pickle's state is an InputError naming data, like its bytes
            if len(flip) != 3 or len(survey) != 3:
                raise ValueError("not three axes")
            v._flip = (bool(flip[0]), bool(flip[1]), bool(flip[2]))
            v._survey = tuple(  # type: ignore[assignment]
                _numbers(x, f"data: {name}", n) for x, name, n in zip(
                    survey, ("inlines", "crosslines", "samples"), (nx, ny, nz), strict=True))
        except (TypeError, ValueError) as e:
            raise InputError(f"data: the pickle's index order or survey numbers are damaged ({e})") from None
        return v

    def to_bytes(self) -> bytes:
        """The volume as bytes (shape, origin, spacing, :attr:`offset`, :attr:`rotation` and the float32
        residuals, versioned little-endian); :meth:`from_bytes` reads them. Pickling uses it and also
        keeps the survey numbers and the index order of :meth:`Scene.add_slice` (``from_bytes``
        alone gives a volume without them, indexed as its stored grid). A lazy volume's bytes hold
        every sample: they are all read (after the octree's pass, which refuses infinite ones)."""
        if self.is_lazy:
            self._v.max_depth()
        return self._v.to_bytes()

    @staticmethod
    def from_bytes(data: bytes) -> Volume:
        """A volume from :meth:`to_bytes`' bytes (InputError naming ``data`` if damaged)."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InputError(f"data: expected bytes, got {type(data).__name__}")
        data = bytes(data)
        v = Volume._wrap(_geocull.Volume.from_bytes(data))  # damaged: an InputError naming data
        nz, ny, nx = v.shape
        n = nx * ny * nz  # the residuals: the bytes' last 4 n (the core refuses trailing bytes)
        idx = cv.first_infinite(np.frombuffer(data, "<f4", count=n, offset=len(data) - 4 * n).reshape(nz, ny, nx))
        if idx is not None:  # to_bytes never writes one (a volume holds no infinite sample)
            raise InputError(f"data: the residual of stored sample [{_where(idx)}] is inf; damaged volume bytes")
        _check_extent(v.origin, v.spacing, (nx, ny, nz), v.rotation, False, False, arg="data")
        return v

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        if self.is_lazy:
            raise InputError("volume: a lazy volume is not pickled (its samples may not fit in memory); pickle its "
                             "source array and make the Volume again, or load it with lazy=False")
        return (Volume._restore, (self.to_bytes(), self._flip, self._survey))

    def __copy__(self) -> Volume:
        return self  # immutable: copies may share it

    def __deepcopy__(self, memo: dict[int, Any]) -> Volume:
        return self

    @property
    def shape(self) -> tuple[int, int, int]:
        """(nz, ny, nx) of the stored grid (z upwards)."""
        return self._v.shape

    @property
    def origin(self) -> tuple[float, float, float]:
        """(x0, y0, z0) world position (z up) of the stored grid's sample (0, 0, 0), metres: the
        given origin, except z for z_positive="down" (then the deepest sample, -(z0 + (nz-1)*dz))."""
        return self._v.origin

    @property
    def spacing(self) -> tuple[float, float, float]:
        """(dx, dy, dz) sample spacing (metres)."""
        return self._v.spacing

    @property
    def rotation(self) -> float:
        """Degrees counter-clockwise about the vertical through :attr:`origin`."""
        return self._v.rotation

    @property
    def is_lazy(self) -> bool:
        """True when the samples are read on demand (``lazy=``), not held in memory."""
        return self._v.is_lazy

    @property
    def bytes_read(self) -> int:
        """Bytes a lazy volume has read from its source so far (4 per float32 residual; the
        octree's pass, planes, brick-cache misses); 0 for a volume in memory."""
        return self._v.bytes_read

    @property
    def cache_info(self) -> tuple[int, int, int] | None:
        """A lazy volume's brick cache in bytes: (budget, held now, most ever held, never above the
        budget); None for a volume in memory."""
        return self._v.cache_info

    def clear_cache(self) -> None:
        """Drops a lazy volume's cached bricks (its next reads go to the source, e.g. to measure a
        cold frame's ``stats["bytes_read"]``); does nothing for a volume in memory."""
        self._v.clear_cache()

    @property
    def offset(self) -> float:
        """The float64 value the stored float32 residuals are relative to (value = offset + residual;
        the midrange of the finite samples for float64 input, 0 for float32)."""
        return self._v.offset

    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """((xmin, ymin, zmin), (xmax, ymax, zmax)) in world units (metres, z up), rotation applied
        (the box around the turned grid)."""
        return self._v.bounds

    @property
    def center(self) -> tuple[float, float, float]:
        """(x, y, z) centre of :attr:`bounds` (metres)."""
        lo, hi = self.bounds
        return (lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2

    def max_depth(self) -> int:
        """Depth of the octree's single-cell leaves (root = 0). Builds the octree on first use: it
        stores min/max down to bricks of 8³ cells (depth max_depth() - 3, about 0.02 bytes per
        sample) and computes the three finer depths from the samples when asked."""
        return self._v.max_depth()

    def nodes(self, depth: int) -> OctreeNodes:
        """Octree nodes at ``depth`` (0..max_depth()): dict of index (n, 3) uint32 [ix, iy, iz] (in units
        of the node's size), bbox_min / bbox_max (n, 3) float64 in the grid's frame (world metres for
        an unrotated volume; before the rotation about the origin otherwise), min / max (n,) float64
        value range in the values' units (+inf / -inf for nodes whose samples are all NaN)."""
        return self._v.nodes(cv.integer(depth, "depth"))

    @property
    def inlines(self) -> np.ndarray | None:
        """The survey's inline numbers along the volume's x axis (its first axis as given), in the
        file's order: (nx,) for volumes from SEG-Y (``f.ilines``) or xtgeo cubes (``cube.ilines``) or
        given as ``inlines=``; None otherwise. Read-only."""
        return self._survey[0]

    @property
    def crosslines(self) -> np.ndarray | None:
        """The survey's crossline numbers along the volume's y axis, in the file's order (also for
        left-handed surveys, whose stored grid runs the other way): (ny,) or None. Read-only."""
        return self._survey[1]

    @property
    def samples(self) -> np.ndarray | None:
        """The sample times / depths along the z axis in the file's order (ms, m or ft as the file
        has them: ``f.samples``, or xtgeo's ``zori + k*zinc``), first the shallowest for z_positive
        "down": (nz,) float64 or None. Read-only."""
        return self._survey[2]

    def _stored_index(self, axis: int, index: int) -> int:
        """The stored grid's index (of :attr:`shape`'s axis, counted along x, y, z = 0, 1, 2) of
        sample ``index`` along ``axis`` counted in the order of the values as given (the file's
        order): reversed along y for ``yflip`` volumes and along z for z_positive="down" ones, whose
        stored grids run the other way. InputError naming ``index`` when out of range."""
        n = (self.shape[2], self.shape[1], self.shape[0])[axis]
        if not 0 <= index < n:
            raise InputError(f"index: {index} is outside 0..{n - 1} along axis {axis}")
        return n - 1 - index if self._flip[axis] else index

    def __repr__(self) -> str:
        rot = f" rotation={self.rotation:g}" if self.rotation else ""
        return f"<geocull.Volume shape={self.shape} origin={self.origin} spacing={self.spacing}{rot}>"
