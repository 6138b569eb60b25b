"""A small reader of Eclipse GRDECL text (numpy only): the keywords of a corner-point grid and its
cell properties, as :func:`geocull.io.read_grdecl` uses when xtgeo is not installed (or
``engine="geocull"``).

The format: a keyword (up to 8 characters, starting a line) followed by its data, numbers or quoted
strings over any number of lines, ended by ``/``; ``--`` starts a comment; ``n*value`` is n copies
of value; ``n*`` alone is n defaulted items. Keywords without data (``ECHO``, ``NOECHO``, the
section headers ``GRID``, ``EDIT``, ``PROPS`` ...) have no ``/``. ``INCLUDE 'file' /`` reads another
file (relative to the including one). Everything else (FAULTS, MULTFLT ...) is skipped. Keywords
that change arrays after they are given (EQUALS, COPY, ADD, MULTIPLY, BOX) are not applied: a
:class:`geocull.GeocullWarning` names them.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal, TypedDict

import numpy as np

from ._convert import float_array, integer, z_sign
from ._errors import GeocullWarning, InputError

__all__ = ["GrdeclDeck", "read_deck", "numbers", "deck_grid", "check_mapaxes", "GRID_KEYWORDS", "CornerArrays",
           "from_grdecl", "mapaxes_transform"]

#: Keywords of the grid's geometry (and its header) that the reader keeps.
GRID_KEYWORDS = ("SPECGRID", "DIMENS", "COORD", "ZCORN", "ACTNUM", "MAPAXES", "MAPUNITS", "GRIDUNIT")
#: Keywords that take no data (no "/" follows them).
_NO_DATA = frozenset({
    "ECHO", "NOECHO", "GRID", "EDIT", "PROPS", "REGIONS", "SOLUTION", "SUMMARY", "SCHEDULE", "RUNSPEC",
    "END", "ENDBOX", "NONNC", "NEWTRAN", "OLDTRAN", "SKIP", "ENDSKIP", "SKIP100", "SKIP300", "ENDINC",
    "GRIDFILE", "INIT", "FILEUNIT",
})
#: Keywords that change arrays after they are given, which this reader does not apply.
_OPERATORS = frozenset({"EQUALS", "COPY", "ADD", "MULTIPLY", "BOX", "MINVALUE", "MAXVALUE", "OPERATE"})
#: Keywords known to take data ("/"-terminated); those of _STRING_DATA may hold words.
_STRING_DATA = frozenset({"SPECGRID", "MAPUNITS", "GRIDUNIT", "GDORIENT", "INCLUDE", "COORDSYS", "DIMENS"})
_KNOWN_DATA = _STRING_DATA | frozenset({
    "COORD", "ZCORN", "ACTNUM", "MAPAXES", "PORO", "PERMX", "PERMY", "PERMZ", "NTG", "DX", "DY", "DZ", "TOPS",
    "SATNUM", "FIPNUM", "EQLNUM", "PVTNUM", "MULTX", "MULTY", "MULTZ", "PINCH", "FAULTS", "MULTFLT", "NNC",
}) | _OPERATORS
_KEYWORD = re.compile(r"[A-Za-z][A-Za-z0-9_+-]{0,7}$")
_TOKEN = re.compile(r"'[^']*'|\"[^\"]*\"|/|[^\s/'\"]+")
_MAX_INCLUDE_DEPTH = 8


class GrdeclDeck:
    """The keywords read from one or more GRDECL files: ``data[name]`` the data tokens (strings) of
    the keyword's last occurrence, ``where[name]`` its ``(file, line)``; ``operators`` the array
    operators seen (not applied)."""

    def __init__(self) -> None:
        self.data: dict[str, list[str]] = {}
        self.where: dict[str, tuple[str, int]] = {}
        self.seen: list[str] = []
        self.operators: set[str] = set()


def _strip_comment(line: str) -> str:
    if "--" not in line:
        return line
    if "'" not in line and '"' not in line:
        return line.split("--", 1)[0]
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif line.startswith("--", i):
            return line[:i]
    return line


def read_deck(paths: Sequence[str | os.PathLike[str]], keep: set[str], arg: str = "path") -> GrdeclDeck:
    """The keywords named in ``keep`` (upper case) of the GRDECL files ``paths``, read in order as one
    deck. InputError naming ``arg`` and the file for a missing or unreadable file, data outside any
    keyword, a keyword whose data has no "/" terminator (a truncated file) or an INCLUDE loop."""
    deck = GrdeclDeck()
    for p in paths:
        _read_file(Path(p), keep, deck, arg, 0)
    if deck.operators:
        ops = sorted(deck.operators)
        warnings.warn(
            f"{arg}: the GRDECL deck uses {', '.join(ops)}, which geocull's reader does not apply: arrays "
            "they change are read as given before them", GeocullWarning, stacklevel=3)
    return deck


def _read_file(path: Path, keep: set[str], deck: GrdeclDeck, arg: str, depth: int) -> None:
    where = os.fspath(path)
    if depth > _MAX_INCLUDE_DEPTH:
        raise InputError(f"{arg}: {where!r}: INCLUDE nested more than {_MAX_INCLUDE_DEPTH} deep (a loop?)")
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = f.read().splitlines()
    except FileNotFoundError:
        raise InputError(f"{arg}: no such file {where!r}") from None
    except (OSError, UnicodeError) as e:
        raise InputError(f"{arg}: cannot read {where!r}: {e}") from e
    if any("\x00" in line for line in lines[:50]):
        raise InputError(f"{arg}: {where!r} is not GRDECL text (binary data: an EGRID / binary GRDECL file?)")
    kw: str | None = None  # the keyword whose data is being read
    kw_line = 0
    tokens: list[str] = []
    after_unknown = False  # stray records after a keyword this reader does not know are skipped
    for n, raw in enumerate(lines, start=1):
        line = _strip_comment(raw).strip()
        if not line:
            continue
        if kw is not None:
            first = line.split(None, 1)[0]
            if _is_keyword(first.split("/", 1)[0]) and first.upper() not in ("T", "F"):
                if not tokens and kw not in keep and kw not in _KNOWN_DATA:
                    kw = None  # an unknown keyword followed by a keyword: it took no data
                elif kw not in _STRING_DATA and (kw in keep or kw in _KNOWN_DATA):
                    raise InputError(f"{arg}: {where!r}: keyword {kw} (line {kw_line}) has no '/' terminator "
                                     f"before {first!r} (line {n})")
            elif "/" not in line and "'" not in line and '"' not in line:
                tokens.extend(line.split())  # the bulk of the data: plain numbers and n*value
                continue
        for t in _TOKEN.findall(line):
            if kw is None:
                if t == "/":
                    break  # a stray terminator (e.g. "ECHO /"): nothing to read
                if not _is_keyword(t):
                    if after_unknown:
                        break  # the rest of an unknown keyword's records
                    raise InputError(f"{arg}: {where!r} line {n}: {t!r} is not a keyword (data outside any keyword)")
                name = t.upper()
                deck.seen.append(name)
                if name in _OPERATORS:
                    deck.operators.add(name)
                if name in _NO_DATA:
                    after_unknown = False
                else:
                    kw, kw_line, tokens = name, n, []
                    after_unknown = name not in keep  # multi-record keywords (FAULTS ...)
            elif t == "/":
                _finish(kw, tokens, kw_line, path, keep, deck, arg, depth)
                kw = None
                break  # the rest of the line after "/" is a comment
            else:
                tokens.append(t)
    if kw is not None:
        raise InputError(f"{arg}: {where!r}: keyword {kw} (line {kw_line}) has no '/' terminator: the file "
                         f"ends inside its data (truncated?)")


def _is_keyword(t: str) -> bool:
    return bool(_KEYWORD.match(t)) and not _looks_numeric(t)


def _looks_numeric(t: str) -> bool:
    try:
        float(t.replace("D", "E").replace("d", "e"))
        return True
    except ValueError:
        return "*" in t


def _finish(kw: str | None, tokens: list[str], line: int, path: Path, keep: set[str], deck: GrdeclDeck,
            arg: str, depth: int) -> None:
    if kw is None:
        return
    if kw == "INCLUDE":
        if not tokens:
            raise InputError(f"{arg}: {os.fspath(path)!r} line {line}: INCLUDE without a file name")
        inc = Path(tokens[0].strip("'\""))
        _read_file(inc if inc.is_absolute() else path.parent / inc, keep, deck, arg, depth + 1)
        return
    if kw in keep:
        deck.data[kw] = tokens
        deck.where[kw] = (os.fspath(path), line)


def numbers(deck: GrdeclDeck, kw: str, arg: str = "path", count: int | None = None) -> np.ndarray:
    """The data of keyword ``kw`` as float64, ``n*value`` repeats expanded; InputError naming ``arg``,
    the file and line for a token that is no number, a defaulted item (``n*``) or a count other
    than ``count``."""
    tokens = deck.data[kw]
    file, line = deck.where[kw]
    here = f"{arg}: {file!r}: {kw} (line {line})"
    try:
        if not any("*" in t for t in tokens):
            out = _floats(tokens)
        else:
            values: list[str] = []
            reps: list[int] = []
            for t in tokens:
                if "*" in t:
                    c, _, v = t.partition("*")
                    if not c.isdigit() or int(c) < 1:
                        raise InputError(f"{here}: {t!r} is not a repeat count n*value")
                    if not v:
                        raise InputError(f"{here}: {t!r} defaults {c} values; {kw} needs every value")
                    values.append(v)
                    reps.append(int(c))
                else:
                    values.append(t)
                    reps.append(1)
            out = np.repeat(_floats(values), reps)
    except ValueError as e:
        if isinstance(e, InputError):
            raise
        bad = next((t for t in tokens if not _looks_numeric(t)), "?")
        raise InputError(f"{here}: {bad!r} is not a number") from None
    if count is not None and out.size != count:
        raise InputError(f"{here}: {out.size} values, expected {count}")
    return out


def _floats(tokens: list[str]) -> np.ndarray:
    try:
        return np.array(tokens, dtype=np.float64)
    except ValueError:
        # Fortran exponents (1.5D+03)
        return np.array([t.replace("D", "E").replace("d", "e") for t in tokens], dtype=np.float64)


# ------------------------------------------------------------------------------------ grid assembly

#: Length units of GRIDUNIT / MAPUNITS in metres.
_UNITS = {"METRES": 1.0, "METERS": 1.0, "FEET": 0.3048, "CM": 0.01}


def _word(deck: GrdeclDeck, kw: str, index: int) -> str:
    toks = deck.data.get(kw, [])
    return toks[index].strip("'\"").strip().upper() if len(toks) > index else ""


def deck_grid(
    deck: GrdeclDeck, properties: str | None, z_positive: str, arg: str = "path"
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """``(corners, active, values or None)`` (:func:`geocull.grid.from_grdecl`'s arrays) of the grid in
    ``deck`` (SPECGRID or DIMENS, COORD, ZCORN, ACTNUM, MAPAXES, GRIDUNIT, MAPUNITS) and its property
    ``properties`` ((nk, nj, ni), NaN on inactive cells)."""
    def missing(kw: str) -> InputError:
        files = sorted({f for f, _ in deck.where.values()}) or "the file(s)"
        return InputError(f"{arg}: no {kw} keyword in {files} (the deck has {sorted(set(deck.seen))}); "
                          "a corner-point grid needs SPECGRID, COORD and ZCORN")

    dims_kw = "SPECGRID" if "SPECGRID" in deck.data else "DIMENS" if "DIMENS" in deck.data else None
    if dims_kw is None:
        raise missing("SPECGRID (or DIMENS)")
    file, line = deck.where[dims_kw]
    toks = deck.data[dims_kw]
    try:
        nx, ny, nz = (int(t) for t in toks[:3])
    except ValueError:
        raise InputError(f"{arg}: {file!r}: {dims_kw} (line {line}): {toks[:3]} is not three cell counts") from None
    if min(nx, ny, nz) < 1:
        raise InputError(f"{arg}: {file!r}: {dims_kw} (line {line}): cell counts {(nx, ny, nz)} must be >= 1")
    if dims_kw == "SPECGRID" and _word(deck, "SPECGRID", 4) == "T":
        raise InputError(f"{arg}: {file!r}: SPECGRID (line {line}) is a radial (cylindrical) grid; geocull "
                         "reads cartesian corner-point grids")
    for kw in ("COORD", "ZCORN"):
        if kw not in deck.data:
            raise missing(kw)
    n = nx * ny * nz
    coord = numbers(deck, "COORD", arg, 6 * (nx + 1) * (ny + 1))
    zcorn = numbers(deck, "ZCORN", arg, 8 * n)
    actnum = numbers(deck, "ACTNUM", arg, n) if "ACTNUM" in deck.data else None
    mapaxes = numbers(deck, "MAPAXES", arg, 6) if "MAPAXES" in deck.data else None
    if mapaxes is not None and _word(deck, "GRIDUNIT", 1) == "MAP":
        mapaxes = None  # COORD is relative to the map already
    if mapaxes is not None:
        gu, mu = _word(deck, "GRIDUNIT", 0), _word(deck, "MAPUNITS", 0)
        if gu and mu and gu != mu:
            if gu not in _UNITS or mu not in _UNITS:
                warnings.warn(f"{arg}: GRIDUNIT {gu!r} and MAPUNITS {mu!r} differ and geocull does not know "
                              "both; the grid is read in its own units", GeocullWarning, stacklevel=3)
            else:  # to the map's units, as xtgeo does
                f = _UNITS[gu] / _UNITS[mu]
                coord, zcorn = coord * f, zcorn * f
    try:
        out = from_grdecl(coord, zcorn, actnum, nx=nx, ny=ny, nz=nz, mapaxes=mapaxes,
                          z_positive=z_positive)  # type: ignore[arg-type]
    except InputError as e:
        kw = str(e).split(":", 1)[0].upper()
        where = deck.where.get(kw)
        at = f"{where[0]!r}: {kw} (line {where[1]}): " if where else ""
        raise InputError(f"{arg}: {at}{e}") from None
    values = None
    if properties is not None:
        name = properties.upper()
        if name not in deck.data:
            files = sorted({f for f, _ in deck.where.values()})
            raise InputError(f"properties: no keyword {name} in {files} (the deck has {sorted(set(deck.seen))})")
        values = numbers(deck, name, arg, n).reshape(nz, ny, nx)
        values[~out["active"]] = np.nan
    return out["corners"], out["active"], values


def check_mapaxes(path: str, arg: str = "path") -> None:
    """InputError naming ``arg``, ``path`` and MAPAXES when the file's MAPAXES is no valid map (not 6
    numbers, an axis of no length, parallel axes), which xtgeo's reader would apply as NaN corners or
    a squashed grid without a word."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError as e:
        raise InputError(f"{arg}: cannot read {path!r}: {e}") from e
    m = re.search(r"^[ \t]*MAPAXES\b(.*?)/", text, re.M | re.S)
    if m is None:
        return
    body = " ".join(_strip_comment(line) for line in m.group(1).splitlines())
    line = text.count("\n", 0, m.start()) + 1
    try:
        mapaxes_transform(_floats(body.split()))
    except (InputError, ValueError) as e:
        raise InputError(f"{arg}: {path!r}: MAPAXES (line {line}): {e}") from None


class CornerArrays(TypedDict):
    """What :func:`from_grdecl` returns: corners (nk, nj, ni, 8, 3) float64 and active (nk, nj, ni)."""

    corners: np.ndarray
    active: np.ndarray


def from_grdecl(
    coord: Any,
    zcorn: Any,
    actnum: Any = None,
    *,
    nx: int,
    ny: int,
    nz: int | None = None,
    mapaxes: Any = None,
    z_positive: Literal["up", "down"] = "down",
) -> CornerArrays:
    """Corner-point arrays from Eclipse's pillar layout (the GRDECL keywords, as numbers).

    coord: COORD, (ny+1) * (nx+1) pillars of 6 floats (any shape of that size), pillar (i, j) at
        index ``j * (nx+1) + i``: x, y, z of its top point, then of its bottom point. A corner at
        depth d on a pillar lies where the pillar's line reaches d (a vertical pillar, top z =
        bottom z, gives its top x, y).
    zcorn: ZCORN, 8 * nx * ny * nz depths in Eclipse order: for each layer its top then its base;
        in each, for each row j the corners at j-bit 0 then 1; in each, for each i the corners at
        i-bit 0 then 1 (i fastest).
    actnum: ACTNUM, nx * ny * nz ints (i fastest) or None = all active.
    nx, ny: cells along i and j; nz: layers (default: from the length of ``zcorn``).
    mapaxes: MAPAXES, 6 numbers ``(X1, Y1, X2, Y2, X3, Y3)`` (any shape of that size, e.g. (3, 2)):
        a point on the local y axis, the origin, a point on the local x axis, world metres. COORD's
        x, y are then local: each pillar point moves to ``origin + x * ex + y * ey``
        (:func:`mapaxes_transform`; :mod:`geocull.grid` has the convention). None: COORD is in
        world coordinates already. An InputError naming ``mapaxes`` for another size, non-finite
        numbers, an axis of zero length or two parallel axes.
    z_positive: "down" (default: ZCORN and COORD z are depths, drawn at z = -depth) or "up".

    Returns ``dict(corners=(nz, ny, nx, 8, 3), active=(nz, ny, nx))`` in the corner order of the
    :mod:`geocull.grid` docstring, world metres, z = -depth for ``z_positive="down"``.
    """
    sign = z_sign(z_positive)
    axes = None if mapaxes is None else mapaxes_transform(mapaxes)
    nx = integer(nx, "nx")
    ny = integer(ny, "ny")
    if nx < 1 or ny < 1:
        raise InputError(f"nx, ny: ({nx}, {ny}) must be at least 1")
    c = float_array(coord, "coord", np.ndim(coord)).reshape(-1)
    if c.size != 6 * (nx + 1) * (ny + 1):
        raise InputError(f"coord: {c.size} values, expected 6 * (nx+1) * (ny+1) = {6 * (nx + 1) * (ny + 1)}")
    z = float_array(zcorn, "zcorn", np.ndim(zcorn)).reshape(-1)
    if nz is None:
        if z.size % (8 * nx * ny) != 0:
            raise InputError(f"zcorn: {z.size} values is not a multiple of 8 * nx * ny = {8 * nx * ny}")
        nz = z.size // (8 * nx * ny)
    nz = integer(nz, "nz")
    if nz < 1 or z.size != 8 * nx * ny * nz:
        raise InputError(f"zcorn: {z.size} values, expected 8 * nx * ny * nz = {8 * nx * ny * max(nz, 0)}")
    # (k, kbit, j, jbit, i, ibit) -> (k, j, i, kbit, jbit, ibit) -> corner c = 4 kbit + 2 jbit + ibit.
    depth = z.reshape(nz, 2, ny, 2, nx, 2).transpose(0, 2, 4, 1, 3, 5).reshape(nz, ny, nx, 8)
    pil = c.reshape(ny + 1, nx + 1, 6)
    if axes is not None:
        origin, ex, ey = axes
        pil = pil.copy()
        for col in (0, 3):  # the top and the bottom point of each pillar
            x, y = pil[..., col].copy(), pil[..., col + 1].copy()
            pil[..., col] = origin[0] + x * ex[0] + y * ey[0]
            pil[..., col + 1] = origin[1] + x * ex[1] + y * ey[1]
    cbits = np.arange(8)
    pi = np.arange(nx)[None, :, None] + (cbits & 1)[None, None, :]  # (1, nx, 8)
    pj = np.arange(ny)[:, None, None] + ((cbits >> 1) & 1)[None, None, :]  # (ny, 1, 8)
    p = pil[pj, pi]  # (ny, nx, 8, 6): each corner's pillar
    top, bot = p[..., 0:3], p[..., 3:6]
    dz = bot[..., 2] - top[..., 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(dz != 0.0, (depth - top[None, ..., 2]) / np.where(dz != 0.0, dz, 1.0)[None], 0.0)
    corners = np.empty((nz, ny, nx, 8, 3))
    corners[..., 0] = top[None, ..., 0] + t * (bot[None, ..., 0] - top[None, ..., 0])
    corners[..., 1] = top[None, ..., 1] + t * (bot[None, ..., 1] - top[None, ..., 1])
    corners[..., 2] = sign * depth
    if actnum is None:
        active = np.ones((nz, ny, nx), dtype=bool)
    else:
        a = np.asarray(actnum).reshape(-1)
        if a.size != nx * ny * nz:
            raise InputError(f"actnum: {a.size} values, expected nx * ny * nz = {nx * ny * nz}")
        active = a.reshape(nz, ny, nx) != 0
    return CornerArrays(corners=corners, active=active)


def mapaxes_transform(mapaxes: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(origin, ex, ey)`` of Eclipse's MAPAXES ``(X1, Y1, X2, Y2, X3, Y3)`` (6 numbers, any shape
    of that size; world metres): the origin (X2, Y2) and the unit vectors ex towards (X3, Y3) and ey
    towards (X1, Y1), each a (2,) float64. A local (x, y) lies at ``origin + x * ex + y * ey``.

    InputError naming ``mapaxes``: not 6 finite numbers, a point on the origin (an axis of zero
    length) or the two axes parallel (the map would squash the grid onto a line)."""
    try:
        m = np.asarray(mapaxes, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"mapaxes: {mapaxes!r} is not 6 numbers (X1 Y1 X2 Y2 X3 Y3)") from None
    if m.size != 6:
        raise InputError(f"mapaxes: {m.size} values (shape {m.shape}); MAPAXES is 6 numbers X1 Y1 X2 Y2 X3 Y3 "
                         "(a point on the y axis, the origin, a point on the x axis)")
    m = m.reshape(3, 2)
    if not np.isfinite(m).all():
        raise InputError(f"mapaxes: {m.ravel().tolist()} holds a non-finite number")
    y_point, origin, x_point = m
    scale = max(1.0, float(np.abs(m).max()))
    ex, ey = x_point - origin, y_point - origin
    lx, ly = float(np.hypot(*ex)), float(np.hypot(*ey))
    for name, length in (("x", lx), ("y", ly)):
        if length <= 1e-9 * scale:
            raise InputError(f"mapaxes: the point on the {name} axis is the origin {origin.tolist()} "
                             f"({m.ravel().tolist()}): the axis has no direction")
    ex, ey = ex / lx, ey / ly
    if abs(float(ex[0] * ey[1] - ex[1] * ey[0])) < 1e-6:
        raise InputError(f"mapaxes: the x axis {ex.tolist()} and the y axis {ey.tolist()} are parallel "
                         f"({m.ravel().tolist()}): they would map the grid onto a line")
    return origin.copy(), ex, ey
