"""Where a seismic slice of :class:`geocull.Scene` lies: its axis and stored index from an axis and
an index in the file's order, or from one survey number (inline, crossline, time, depth)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from . import _convert as cv
from ._errors import InputError

if TYPE_CHECKING:
    from .volume import Volume

#: The slice axes of :meth:`Scene.add_slice`: constant i, j or k of the volume.
SliceAxis = Literal["inline", "crossline", "sample"]
_AXES = {"inline": 0, "crossline": 1, "sample": 2, "x": 0, "y": 1, "z": 2}

def _nearest(numbers: np.ndarray, value: float, arg: str) -> int:
    """Index of the entry of ``numbers`` (survey numbers, either direction) nearest ``value``;
    InputError naming ``arg`` and listing the range when ``value`` lies over half a step outside."""
    nums = np.asarray(numbers, dtype=np.float64)
    lo, hi = float(nums.min()), float(nums.max())
    step = float(np.median(np.abs(np.diff(nums)))) if len(nums) > 1 else 0.0
    if not (lo - step / 2 <= value <= hi + step / 2):
        raise InputError(f"{arg}: {value:g} is outside the volume's {arg}s {lo:g}..{hi:g} (step {step:g}, "
                         f"{len(nums)} values)")
    return int(np.argmin(np.abs(nums - value)))


def stored_range(volume: Any, axis: int, i0: int, i1: int) -> tuple[int, int]:
    """An inclusive index range along ``axis`` in the file's order as the stored grid's (sorted)."""
    n = (volume.shape[2], volume.shape[1], volume.shape[0])[axis]
    if not (0 <= i0 < n and 0 <= i1 < n):
        raise InputError(f"box[{axis}]: ({i0}, {i1}) is outside 0..{n - 1}")
    a, b = volume._stored_index(axis, i0), volume._stored_index(axis, i1)
    return (min(a, b), max(a, b))



def axis_index(axis: Any) -> int:
    """The axis number of ``axis`` ("inline", "crossline", "sample", x, y, z, or 0..2)."""
    if isinstance(axis, str):
        if axis not in _AXES:
            raise InputError(f"axis: {axis!r}; expected 'inline', 'crossline', 'sample' or 0, 1, 2")
        return _AXES[axis]
    return cv.integer(axis, "axis")


def slice_position(
    volume: Volume, axis: Any, index: Any, inline: Any, crossline: Any, time: Any, depth: Any,
    fixed_axis: int | None = None,
) -> tuple[int, int]:
    """(axis, stored index) of a slice given by (axis, index) in the file's order or by one survey
    number; ``fixed_axis``: the axis of a slice being moved (``axis`` is then not given)."""
    numbers = [(k, v) for k, v in (("inline", inline), ("crossline", crossline), ("time", time),
                                   ("depth", depth)) if v is not None]
    if len(numbers) > 1:
        raise InputError(f"{numbers[1][0]}: give one of inline=, crossline=, time=, depth= (got "
                         f"{', '.join(k for k, _ in numbers)})")
    if numbers:
        key, value = numbers[0]
        if index is not None or (axis is not None and fixed_axis is None):
            raise InputError(f"{key}: give either axis and index or {key}=, not both")
        ax = {"inline": 0, "crossline": 1, "time": 2, "depth": 2}[key]
        if fixed_axis is not None and ax != fixed_axis:
            along = ("inline", "crossline", "sample")[fixed_axis]
            raise InputError(f"{key}: this slice lies along axis {fixed_axis} ({along})")
        nums = (volume.inlines, volume.crosslines, volume.samples)[ax]
        if nums is None:
            what = ("inline", "crossline", "sample")[ax]
            raise InputError(f"{key}: the volume has no {what} numbers (volumes from SEG-Y or xtgeo carry them, "
                             f"or pass {what}s= to Volume); give axis and index")
        file_index = _nearest(nums, cv.number(value, key), key)
        return ax, volume._stored_index(ax, file_index)
    if fixed_axis is None:
        if axis is None or index is None:
            raise InputError("axis: give axis and index, or one of inline=, crossline=, time=, depth=")
        ax = axis_index(axis)
    else:
        ax = fixed_axis
        if index is None:
            raise InputError("index: give index, or one of inline=, crossline=, time=, depth=")
    i = cv.integer(index, "index")
    if not 0 <= ax <= 2:
        raise InputError(f"axis: {ax}; expected 'inline', 'crossline', 'sample' or 0, 1, 2")
    return ax, volume._stored_index(ax, i)
