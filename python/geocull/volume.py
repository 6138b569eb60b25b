"""Scalar volumes on regular grids, with a lazily built min/max octree (for isosurfaces, see
:mod:`geocull.iso`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _convert as cv
from . import _geocull
from ._errors import InputError

if TYPE_CHECKING:
    from ._geocull import OctreeNodes

__all__ = ["Volume"]


def _values(values: Any) -> np.ndarray:
    """A C-contiguous float32/float64 (nz, ny, nx) view of ``values`` (numpy, np.memmap, xarray,
    anything with ``__array__``), copied only when the layout or dtype demands it."""
    if hasattr(values, "variable") and hasattr(values, "dims") and hasattr(values, "data"):
        values = values.data  # xarray.DataArray: its backing array (numpy, or dask -> computed below)
    values, mask = cv.unmasked(values, "values")
    try:
        a = np.asarray(values)
    except Exception as e:
        raise InputError(f"values: cannot be read as an array ({e})") from None
    if a.ndim != 3:
        raise InputError(f"values: shape {a.shape} is not 3-D (nz, ny, nx)")
    if a.dtype.kind not in "fiu" or a.dtype.kind == "c":
        raise InputError(f"values: dtype {a.dtype} is not supported; expected real numbers")
    if min(a.shape) < 2:
        raise InputError(f"values: shape {a.shape} needs at least 2 samples per axis")
    if mask is not None:  # masked samples are no data (NaN): a float copy with them set
        a = np.array(a, dtype=a.dtype if a.dtype.kind == "f" and a.dtype.itemsize >= 4 else np.float64)
        a[mask] = np.nan
    if a.dtype == np.float32 or a.dtype == np.float64:
        if not a.dtype.isnative:
            a = a.astype(a.dtype.newbyteorder("="))
        return np.ascontiguousarray(a)
    # float16 fits float32 exactly; integers go through float64, whose residuals keep them
    # (int32 / int64 samples of 1e8 and 1e8 + 1 differ in float64 but not in float32).
    return np.ascontiguousarray(a, dtype=np.float32 if a.dtype.kind == "f" else np.float64)


class Volume:
    """A scalar field on a regular grid: ``values[k, j, i]`` sits at
    ``origin + (i*dx, j*dy, k*dz)``; x varies fastest. NaN samples, and the masked samples of a
    ``numpy.ma.MaskedArray``, are "no data" (outside the domain: no surface in cells touching them).

    values: (nz, ny, nx) array, float32 or float64 (other real dtypes are converted); numpy
    arrays, memory maps and numpy-backed xarray DataArrays are read in place and copied exactly once,
    into the core's float32 buffer (the octree and the surface extraction read that buffer).
    float64 (and integer) values are stored as float32 *residuals* about :attr:`offset`, the
    midrange of the finite samples, so values such as 1e8 ± 1 keep their differences; float32
    values are stored as they are (offset 0). Isovalues and the octree's min/max are in the
    values' own units either way.
    origin: (x0, y0, z0) world position of ``values[0, 0, 0]`` (metres).  spacing: (dx, dy, dz) > 0
    sample spacing (metres).
    """

    def __init__(self, values: Any, origin: Sequence[float] = (0.0, 0.0, 0.0),
                 spacing: Sequence[float] = (1.0, 1.0, 1.0)) -> None:
        a = _values(values)
        self._v = _geocull.Volume(a, cv.vec3(origin, "origin"), cv.vec3(spacing, "spacing"))

    @classmethod
    def _wrap(cls, inner: _geocull.Volume) -> Volume:
        v = cls.__new__(cls)
        v._v = inner
        return v

    def to_bytes(self) -> bytes:
        """The volume as bytes (shape, origin, spacing, :attr:`offset` and the float32 residuals,
        versioned little-endian); :meth:`from_bytes` reads them. Pickling uses it."""
        return self._v.to_bytes()

    @staticmethod
    def from_bytes(data: bytes) -> Volume:
        """A volume from :meth:`to_bytes`' bytes (InputError naming ``data`` if damaged)."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InputError(f"data: expected bytes, got {type(data).__name__}")
        return Volume._wrap(_geocull.Volume.from_bytes(bytes(data)))

    def __reduce__(self) -> tuple[Any, tuple[bytes]]:
        return (Volume.from_bytes, (self.to_bytes(),))

    def __copy__(self) -> Volume:
        return self  # immutable: copies may share it

    def __deepcopy__(self, memo: dict[int, Any]) -> Volume:
        return self

    @property
    def shape(self) -> tuple[int, int, int]:
        """(nz, ny, nx)"""
        return self._v.shape

    @property
    def origin(self) -> tuple[float, float, float]:
        """(x0, y0, z0) world position of ``values[0, 0, 0]`` (metres)."""
        return self._v.origin

    @property
    def spacing(self) -> tuple[float, float, float]:
        """(dx, dy, dz) sample spacing (metres)."""
        return self._v.spacing

    @property
    def offset(self) -> float:
        """The float64 value the stored float32 residuals are relative to (value = offset + residual;
        the midrange of the finite samples for float64 input, 0 for float32)."""
        return self._v.offset

    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """((xmin, ymin, zmin), (xmax, ymax, zmax)) in world units (metres)."""
        nz, ny, nx = self.shape
        o, s = self.origin, self.spacing
        return o, (o[0] + (nx - 1) * s[0], o[1] + (ny - 1) * s[1], o[2] + (nz - 1) * s[2])

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
        of the node's size), bbox_min / bbox_max (n, 3) float64 world (metres), min / max (n,) float64
        value range in the values' units (+inf / -inf for nodes whose samples are all NaN)."""
        return self._v.nodes(cv.integer(depth, "depth"))

    def __repr__(self) -> str:
        return f"<geocull.Volume shape={self.shape} origin={self.origin} spacing={self.spacing}>"
