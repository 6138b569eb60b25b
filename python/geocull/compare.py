"""Image and depth comparison metrics (pure numpy; no extension needed).

``image_error``          differing-pixel fraction, PSNR, max abs diff, missing tiles
``coverage``             mask of pixels where something was drawn (finite depth)
``coverage_agreement``   fraction of pixels where two depth images agree on coverage
``depth_error``          relative depth error over pixels covered in both

Bad inputs raise :class:`geocull.InputError` when the extension is loaded (a ``ValueError``
subclass), plain ``ValueError`` otherwise; messages start with the argument's name.
"""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

__all__ = ["image_error", "coverage", "coverage_agreement", "depth_error"]


def _input_error(msg: str) -> ValueError:
    """geocull.InputError if the package exposes it (never imports the extension), else ValueError."""
    cls = getattr(sys.modules.get("geocull"), "InputError", None)
    if not (isinstance(cls, type) and issubclass(cls, ValueError)):
        cls = ValueError
    return cls(msg)


def _image(name: str, x: Any) -> np.ndarray:
    x = np.asarray(x)
    if x.dtype != np.uint8:
        raise _input_error(f"{name}: expected a uint8 image, got dtype {x.dtype}")
    if x.ndim != 3 or x.shape[2] not in (3, 4):
        raise _input_error(f"{name}: expected shape (H, W, 3) or (H, W, 4), got {x.shape}")
    return x


def _depth(name: str, x: Any) -> np.ndarray:
    x = np.asarray(x)
    if x.ndim != 2:
        raise _input_error(f"{name}: expected a 2-D (H, W) depth image, got shape {x.shape}")
    if not np.issubdtype(x.dtype, np.floating):
        raise _input_error(f"{name}: expected a float depth image, got dtype {x.dtype}")
    return x


def image_error(
    a: np.ndarray,
    b: np.ndarray,
    tile_drawn: np.ndarray | None = None,
    reference_tile_pixels: np.ndarray | None = None,
    threshold: int = 0,
) -> dict[str, Any]:
    """Compare image ``a`` (e.g. culled) with reference ``b`` (e.g. unculled).

    ``a`` and ``b`` are uint8 ``(H, W, 3)`` or ``(H, W, 4)`` of equal height and width. With equal
    channel counts all channels are compared; an RGBA image against an RGB one compares RGB only.

    Returns a dict:

    - ``differing_pixel_fraction``: fraction of pixels where any channel differs by more than
      ``threshold``;
    - ``psnr``: peak signal-to-noise ratio in dB over the compared channels (``inf`` if identical);
    - ``max_abs_diff``: largest channel difference (int);
    - ``missing_tiles``: number of tiles with ``reference_tile_pixels > 0`` that are not
      ``tile_drawn`` (``None`` unless both arrays are given).
    """
    a = _image("a", a)
    b = _image("b", b)
    if a.shape[:2] != b.shape[:2]:
        raise _input_error(f"b: shape {b.shape} does not match a's shape {a.shape}")
    c = min(a.shape[2], b.shape[2])
    if a.shape[2] != b.shape[2]:
        a, b = a[..., :c], b[..., :c]
    try:
        threshold = int(threshold)
    except (TypeError, ValueError):
        raise _input_error(f"threshold: expected an integer >= 0, got {threshold!r}") from None
    if threshold < 0:
        raise _input_error(f"threshold: expected an integer >= 0, got {threshold}")

    diff = np.abs(a.astype(np.int16) - b.astype(np.int16))
    n_pix = a.shape[0] * a.shape[1]
    if n_pix == 0:
        frac, mx, psnr = 0.0, 0, math.inf
    else:
        per_pixel = diff.max(axis=2)
        frac = float(np.count_nonzero(per_pixel > threshold)) / n_pix
        mx = int(per_pixel.max())
        mse = float(np.mean(diff.astype(np.float64) ** 2))
        psnr = math.inf if mse == 0.0 else 10.0 * math.log10(255.0**2 / mse)

    missing = None
    if tile_drawn is not None or reference_tile_pixels is not None:
        if tile_drawn is None:
            raise _input_error("tile_drawn: required when reference_tile_pixels is given")
        if reference_tile_pixels is None:
            raise _input_error("reference_tile_pixels: required when tile_drawn is given")
        td = np.asarray(tile_drawn)
        rp = np.asarray(reference_tile_pixels)
        if td.ndim != 1:
            raise _input_error(f"tile_drawn: expected a 1-D array, got shape {td.shape}")
        if rp.shape != td.shape:
            raise _input_error(
                f"reference_tile_pixels: shape {rp.shape} does not match tile_drawn's shape {td.shape}"
            )
        missing = int(np.count_nonzero((rp > 0) & ~td.astype(bool)))

    return dict(differing_pixel_fraction=frac, psnr=psnr, max_abs_diff=mx, missing_tiles=missing)


def coverage(depth: np.ndarray) -> np.ndarray:
    """(H, W) bool mask of the pixels of an (H, W) depth image where something was drawn (finite depth;
    ``inf``/NaN = empty)."""
    return np.isfinite(_depth("depth", depth))


def _pair(depth_a, depth_b) -> tuple[np.ndarray, np.ndarray]:
    a = _depth("depth_a", depth_a)
    b = _depth("depth_b", depth_b)
    if a.shape != b.shape:
        raise _input_error(f"depth_b: shape {b.shape} does not match depth_a's shape {a.shape}")
    return a, b


def coverage_agreement(depth_a: np.ndarray, depth_b: np.ndarray) -> float:
    """Fraction of pixels where the (H, W) depth images ``depth_a`` and ``depth_b`` agree on whether
    something is drawn (1.0 for empty images)."""
    a, b = _pair(depth_a, depth_b)
    if a.size == 0:
        return 1.0
    return float(np.count_nonzero(np.isfinite(a) == np.isfinite(b))) / a.size


def depth_error(depth_a: np.ndarray, depth_b: np.ndarray, rel_tol: float = 1e-3) -> dict[str, Any]:
    """Relative depth error ``|a - b| / |b|`` (``b`` is the reference) over pixels covered in both.

    Returns ``n_common`` (pixels covered in both), ``mean_rel``, ``median_rel``, ``p99_rel``,
    ``max_rel`` (NaN when ``n_common`` is 0) and ``fraction_over_tol`` (share of common pixels whose
    relative error exceeds ``rel_tol``; 0.0 when none are common).
    """
    a, b = _pair(depth_a, depth_b)
    both = np.isfinite(a) & np.isfinite(b)
    n = int(np.count_nonzero(both))
    if n == 0:
        nan = float("nan")
        return dict(n_common=0, mean_rel=nan, median_rel=nan, p99_rel=nan, max_rel=nan, fraction_over_tol=0.0)
    av = a[both].astype(np.float64)
    bv = b[both].astype(np.float64)
    denom = np.abs(bv)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(denom > 0, np.abs(av - bv) / denom, np.where(av == bv, 0.0, np.inf))
    return dict(
        n_common=n,
        mean_rel=float(rel.mean()),
        median_rel=float(np.median(rel)),
        p99_rel=float(np.percentile(rel, 99)),
        max_rel=float(rel.max()),
        fraction_over_tol=float(np.count_nonzero(rel > rel_tol)) / n,
    )
