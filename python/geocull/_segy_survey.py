"""The survey grid of a SEG-Y file's traces (:func:`fit_survey`), for :func:`geocull.io.from_segy`."""

from __future__ import annotations

import math

import numpy as np

from ._errors import InputError

__all__ = ["fit_survey"]


def fit_survey(
    a: np.ndarray, b: np.ndarray, x: np.ndarray, y: np.ndarray, na: int, nb: int, tol: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, bool]:
    """(P0, u, v, rotation in degrees, left-handed) of the perpendicular grid ``P0 + a*u + b*v``
    nearest the traces at indices (a, b) and positions (x, y); InputError where a trace lies
    farther than ``tol`` (default 10 % of the smaller step) from it."""
    if len(np.unique(a)) < 2 or len(np.unique(b)) < 2:
        raise InputError("source: the live traces span fewer than 2 inlines or crosslines")
    m = np.column_stack([np.ones_like(a, dtype=np.float64), a, b]).astype(np.float64)
    coef, *_ = np.linalg.lstsq(m, np.column_stack([x, y]), rcond=None)
    u, v = coef[1], coef[2]
    lu, lv = float(np.hypot(*u)), float(np.hypot(*v))
    if lu < 1e-9 or lv < 1e-9:
        raise InputError("source: CDP_X / CDP_Y do not change along the inlines or crosslines (no coordinates?)")
    t = 0.1 * min(lu, lv) if tol is None else tol
    err = float(np.hypot(*(m @ coef - np.column_stack([x, y])).T).max())
    if err > t:
        raise InputError(f"source: the trace coordinates are not a regular grid (off by up to {err:g}; "
                         f"tolerance {t:g}, pass tolerance= to accept more)")
    cross = float(u[0] * v[1] - u[1] * v[0])
    hand = 1.0 if cross >= 0 else -1.0
    # The perpendicular grid nearest the affine one: one direction, the mean of u's and of v's turned
    # back by 90°, weighted by the extents they span.
    tu = math.atan2(u[1], u[0])
    tv = math.atan2(v[1], v[0]) - hand * math.pi / 2
    wu, wv = lu * (na - 1), lv * (nb - 1)
    th = math.atan2(wu * math.sin(tu) + wv * math.sin(tv), wu * math.cos(tu) + wv * math.cos(tv))
    up = lu * np.array([math.cos(th), math.sin(th)])
    vp = lv * hand * np.array([-math.sin(th), math.cos(th)])
    q = np.column_stack([x, y]) - np.outer(a, up) - np.outer(b, vp)
    p0p = q.mean(axis=0)
    perr = float(np.hypot(*(q - p0p).T).max())
    if perr > t:
        raise InputError(
            f"source: the inline step {u.tolist()} and the crossline step {v.tolist()} are not perpendicular "
            f"(a skewed survey: off a rectangular grid by up to {perr:g}, tolerance {t:g}); a Volume is a "
            "rectangular grid, possibly rotated"
        )
    return p0p, up, vp, math.degrees(th), hand < 0
