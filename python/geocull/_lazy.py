"""Volumes larger than memory: the readers behind a lazy :class:`geocull.Volume`.

A lazy volume keeps no samples: the core asks its reader for boxes of the stored grid (x fastest,
z up, ``read(lo, hi)`` with ``lo``/``hi`` the (x, y, z) corners, ``hi`` exclusive) as it needs them
(one streaming pass for the octree, one plane per slice, the bricks of the nodes a frame extracts;
``src/iso/store.rs``), through a bounded brick cache. The reader maps a box onto the user's array
(its index order, a z axis growing downwards, a reversed y axis) and slices only that: zarr and
dask arrays, xarray DataArrays backed by them (or by any lazily indexed backend), memory maps, and
SEG-Y files opened without reading their traces (:class:`SegyCube`). Nothing here imports zarr,
dask or xarray: arrays are recognised by their type's module.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ._errors import InputError

#: Default byte budget of a lazy volume's brick cache (``cache_bytes=``): 512 MiB.
DEFAULT_CACHE_BYTES = 512 << 20

#: Bytes per slab of the float64 midrange pass (:func:`midrange`).
_SLAB_BYTES = 64 << 20


def _module(x: Any) -> str:
    return type(x).__module__.split(".")[0]


def backend_is_lazy(da: Any) -> bool:
    """A DataArray whose samples are not a loaded numpy array (dask, zarr, a lazily indexed file)."""
    data = getattr(getattr(da, "variable", None), "_data", None)
    return data is not None and not isinstance(data, np.ndarray)


def is_lazy_source(x: Any) -> bool:
    """True for the arrays a Volume reads lazily by default: zarr and dask arrays, xarray
    DataArrays backed by them (or by any lazily indexed backend), SEG-Y cubes (:class:`SegyCube`)."""
    if isinstance(x, SegyCube):
        return True
    if _module(x) in ("zarr", "dask"):
        return hasattr(x, "shape") and hasattr(x, "dtype")
    if _module(x) == "xarray" and hasattr(x, "variable"):
        return backend_is_lazy(x)
    return False


def array_of(x: Any) -> Any:
    """The sliceable 3-D array behind a lazy source (a DataArray's variable: slicing it reads only
    the slice, where ``.data`` of a lazily indexed backend would load it all)."""
    if _module(x) == "xarray" and hasattr(x, "variable"):
        return x.variable
    return x


def check_array(a: Any) -> tuple[tuple[int, int, int], np.dtype[Any]]:
    """Shape and dtype of a lazy source, or InputError naming ``values``."""
    shape = tuple(int(n) for n in getattr(a, "shape", ()))
    if len(shape) != 3:
        raise InputError(f"values: shape {shape} is not 3-D")
    dt = np.dtype(a.dtype)
    if dt.kind not in "fiu":
        raise InputError(f"values: dtype {dt} is not supported; expected real numbers")
    if min(shape) < 2:
        raise InputError(f"values: shape {shape} needs at least 2 samples per axis")
    return (shape[0], shape[1], shape[2]), dt


def wide(dt: np.dtype[Any]) -> bool:
    """True when samples of ``dt`` are stored as float32 residuals about a midrange (float64,
    integers, long double); False for float16 / float32 (offset 0)."""
    return not (dt.kind == "f" and dt.itemsize <= 4)


def midrange(a: Any) -> float:
    """The midrange of the finite samples of ``a`` (0 when none), in one pass over slabs of
    its first axis (about 64 MiB each): the offset of float64 residuals."""
    n = a.shape[0]
    step = max(1, _SLAB_BYTES // max(1, 8 * int(np.prod(a.shape[1:]))))
    lo, hi = math.inf, -math.inf
    for k in range(0, n, step):
        b = np.asarray(a[k:k + step], dtype=np.float64)
        f = b[np.isfinite(b)]
        if f.size:
            lo, hi = min(lo, float(f.min())), max(hi, float(f.max()))
    return 0.5 * lo + 0.5 * hi if lo <= hi else 0.0


class BlockReader:
    """Reads boxes of the stored grid from ``array`` (the user's array, indexed as ``order`` says,
    its y axis reversed when ``yflip``, its z axis growing downwards when ``down``) as float32
    residuals about ``offset``: see the module docs."""

    def __init__(self, array: Any, order: str, down: bool, yflip: bool, offset: float, as_f64: bool) -> None:
        self.array = array
        self.xyz = order == "xyz"
        self.down = down
        self.yflip = yflip
        self.offset = offset
        self.as_f64 = as_f64
        s = array.shape
        self.n = (s[0], s[1], s[2]) if self.xyz else (s[2], s[1], s[0])  # nx, ny, nz

    def read(self, lo: tuple[int, int, int], hi: tuple[int, int, int]) -> np.ndarray:
        """The box ``lo..hi`` (x, y, z; exclusive) as a float32 (z, y, x) array."""
        nx, ny, nz = self.n
        xs = slice(lo[0], hi[0])
        ys = slice(ny - hi[1], ny - lo[1]) if self.yflip else slice(lo[1], hi[1])
        zs = slice(nz - hi[2], nz - lo[2]) if self.down else slice(lo[2], hi[2])
        b = np.asarray(self.array[xs, ys, zs] if self.xyz else self.array[zs, ys, xs])
        if self.xyz:
            b = b.transpose(2, 1, 0)
        if self.down:
            b = b[::-1]
        if self.yflip:
            b = b[:, ::-1]
        if self.as_f64:
            return np.ascontiguousarray(b.astype(np.float64) - self.offset, dtype=np.float32)
        return np.ascontiguousarray(b, dtype=np.float32)


class SegyCube:
    """A post-stack SEG-Y cube as a lazily read (inline, crossline, sample) array: ``cube[a, b, s]``
    (basic slices) reads only the traces of the box, and of each trace only the samples asked for.
    ``traces[a, b]`` is the trace index of inline index a, crossline index b (-1: missing or dead,
    read as NaN). The file stays open while the cube lives (:meth:`close` closes it)."""

    def __init__(self, f: Any, ta: np.ndarray, tb: np.ndarray, shape: tuple[int, int, int], owned: bool) -> None:
        """``f``: the open file; trace t (file order) lies at inline index ``ta[t]``, crossline index
        ``tb[t]``; ``owned``: close ``f`` with the cube."""
        self.f = f
        self.traces = np.full(shape[:2], -1, dtype=np.int64)
        self.traces[ta, tb] = np.arange(len(ta))
        self.shape = shape
        dtype = np.dtype(getattr(f, "dtype", np.float32))
        self.dtype = np.dtype(np.float32) if dtype.kind == "f" and dtype.itemsize <= 4 else np.dtype(np.float64)
        self.ndim = 3
        self._owned = owned

    def __getitem__(self, key: tuple[slice, slice, slice]) -> np.ndarray:
        a, b, s = (range(*k.indices(n)) for k, n in zip(key, self.shape, strict=True))
        out = np.full((len(a), len(b), len(s)), np.nan, dtype=self.dtype)
        if len(s) == 0:
            return out
        sl = slice(s.start, s.stop, s.step)
        for i, ai in enumerate(a):
            for j, bj in enumerate(b):
                t = int(self.traces[ai, bj])
                if t >= 0:
                    out[i, j] = self.f.trace[t, sl] if (s.start, len(s)) != (0, self.shape[2]) else self.f.trace[t]
        return out

    def close(self) -> None:
        if self._owned:
            self.f.close()
            self._owned = False

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # noqa: BLE001 - a closing file at exit has nothing to report
            pass
