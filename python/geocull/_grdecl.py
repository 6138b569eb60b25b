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

import numpy as np

from ._errors import GeocullWarning, InputError

__all__ = ["GrdeclDeck", "read_deck", "numbers", "deck_grid", "check_mapaxes", "GRID_KEYWORDS"]

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
    from .grid import from_grdecl

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
    from .grid import mapaxes_transform

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
