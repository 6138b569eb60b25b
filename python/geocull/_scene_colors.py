"""What :class:`geocull.Scene` keeps of its objects' colourings beside the core: colour bar labels
and tables, the shared depth range of the objects coloured by z without a ``clim`` of their own,
and the check that a new object does not lie far from the others (a mixin of the Scene)."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from . import _convert as cv
from . import _geocull
from ._errors import GeocullWarning, InputError
from .results import ObjectColoring

__all__ = ["FAR_APART"]

#: Objects farther apart than this (metres, the gap between their bounding boxes) get a
#: :class:`geocull.GeocullWarning` when the second is added.
FAR_APART = 1_000_000.0

class SharedZ(NamedTuple):
    """An object coloured by z without a ``clim`` of its own, so over the scene's depth range: its
    colour map (name, table), NaN colour, its own z range, and the range last given to the core."""

    cmap: str | None
    table: np.ndarray | None
    nan: tuple[float, float, float] | None
    own: tuple[float, float]
    applied: tuple[float, float] | None


def _object_boxes(table: np.ndarray) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Object id -> (lo (3,), hi (3,)) world box of its tiles (empty tiles, NaN boxes, skipped)."""
    out: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    if len(table) == 0:
        return out
    ok = np.isfinite(table["bbox_min"]).all(axis=1) & np.isfinite(table["bbox_max"]).all(axis=1)
    t = table[ok]
    for obj in np.unique(t["object"]):
        rows = t[t["object"] == obj]
        out[int(obj)] = (rows["bbox_min"].min(axis=0), rows["bbox_max"].max(axis=0))
    return out


def label_arg(label: Any, values: Any = None) -> str | None:
    """The colour bar label: ``label`` (None or a str, else InputError), else the ``name`` of
    ``values`` where it has one (xarray DataArray, pandas Series, xtgeo GridProperty), else None."""
    if label is not None:
        if not isinstance(label, str):
            raise InputError(f"label: {label!r} is not a string")
        return label
    n = getattr(values, "name", None)
    return n if isinstance(n, str) and n else None


def pair(v: Any) -> tuple[float, float]:
    """(lo, hi) floats of a pair (TypeError / ValueError otherwise)."""
    lo, hi = (float(x) for x in v)
    return lo, hi



class SceneColorings:
    """The Scene's colour bookkeeping (see the module docs); the Scene sets the attributes."""

    _s: _geocull.Scene
    _zshared: dict[int, SharedZ]
    _labels: dict[int, str]
    _tables: dict[int, np.ndarray]
    _slices: dict[int, tuple[Any, int, str | None, cv.Coloring, float]]

    if TYPE_CHECKING:

        def tile_table(self) -> np.ndarray: ...

        def object_ids(self) -> list[int]: ...

    def _added(self, id: int, coloring: cv.Coloring | None = None, label: str | None = None,
               priority: int | None = None) -> int:
        """``id``, after setting its depth-tie ``priority`` (a bad one removes the object again and
        raises), noting its colouring (``coloring``: the tuple given to the core; the colour
        bar ``label``) and sharing the scene's depth range, and after a
        :class:`geocull.GeocullWarning` if the new object lies over :data:`FAR_APART` metres from
        another object of the scene (a grid in local coordinates beside UTM horizons renders as an
        empty image), naming both."""
        if priority is not None:
            try:
                self._s.set_priority(id, cv.integer(priority, "priority"))
            except BaseException:
                self._s.remove(id)
                raise
        self._note_coloring(id, coloring, label)
        try:
            boxes = _object_boxes(self.tile_table())
        except Exception:  # never let the check fail an add
            return id
        new = boxes.get(id)
        if new is None:
            return id
        lo, hi = new
        worst: tuple[float, int] | None = None
        for other, (olo, ohi) in boxes.items():
            if other == id:
                continue
            gap = float(np.linalg.norm(np.maximum(0.0, np.maximum(olo - hi, lo - ohi))))
            if gap > FAR_APART and (worst is None or gap > worst[0]):
                worst = (gap, other)
        if worst is not None:
            gap, other = worst
            warnings.warn(
                f"{self._label(id)} lies {gap / 1000:,.0f} km from {self._label(other)}: over "
                f"{FAR_APART / 1000:,.0f} km apart, one view cannot show both (local coordinates beside "
                "UTM ones? depth given as elevation?)",
                GeocullWarning,
                stacklevel=3,
            )
        return id

    def _note_coloring(self, id: int, coloring: cv.Coloring | None, label: str | None) -> None:
        """Keep what the core does not of object ``id``'s colouring (its table, its colour bar label;
        whether it follows the shared depth range), then give the depth range to the objects that
        follow it."""
        info = self._s.object_info(id)
        self._labels.pop(id, None)
        self._tables.pop(id, None)
        self._zshared.pop(id, None)
        if info["color_by"] is not None:
            if label is not None:
                self._labels[id] = label
            if coloring is not None and coloring[3] is not None:
                self._tables[id] = coloring[3]
        own = info["clim"]
        if info["color_by"] == "z" and (coloring is None or coloring[4] is None) and own is not None:
            self._zshared[id] = SharedZ(
                coloring[2] if coloring is not None else info["cmap"], coloring[3] if coloring is not None else None,
                coloring[5] if coloring is not None else None, (float(own[0]), float(own[1])), None)
        self._share_depth_range()

    def _share_depth_range(self) -> None:
        """Give every object coloured by z without a clim of its own the lowest and highest z over
        them all (each one's own range was read when its colouring was set). Objects already given
        this range are left alone."""
        if not self._zshared:
            return
        lo = min(v.own[0] for v in self._zshared.values())
        hi = max(v.own[1] for v in self._zshared.values())
        rng = (lo, hi) if lo < hi else None  # all flat at one z: the core's own range (a core rule: lo < hi)
        for id, v in list(self._zshared.items()):
            if v.applied == rng and rng is not None:
                continue
            self._s.set_color_by(id, ("z", None, v.cmap, v.table, rng, v.nan))
            self._zshared[id] = v._replace(applied=rng)

    def depth_range(self) -> tuple[float, float] | None:
        """``(zmin, zmax)`` metres: the scene's shared depth range, over which every object coloured
        by z without a ``clim`` of its own is coloured (the lowest and highest z of those objects,
        hidden ones included, offsets from :meth:`translate` not applied); None when there is no
        such object. ``object_info(id)["clim"]`` is the range each object is drawn with."""
        if not self._zshared:
            return None
        return (min(v.own[0] for v in self._zshared.values()), max(v.own[1] for v in self._zshared.values()))

    def colorings(self, ids: list[int] | None = None) -> list[ObjectColoring]:
        """The colourings by data of objects ``ids`` (default every object, in the order added;
        objects in one flat colour are left out): :class:`geocull.results.ObjectColoring` dicts with
        the object's id, name, kind, color_by, colour map (its name, and its table where it was given
        as a table or a matplotlib ``Colormap``), the ``clim`` it is drawn with, and its colour bar
        label: the ``label`` given (or the values' own name), else "values"; colour by z is labelled
        "depth (m)" (its bar counts depth = -z) where the range lies at or below z = 0, else
        "elevation (m)". :meth:`geocull.RenderResult.figure` draws one colour bar per distinct
        (colour map, clim, label) of the objects in the frame."""
        out: list[ObjectColoring] = []
        for i in self.object_ids() if ids is None else ids:
            info = self._s.object_info(cv.integer(i, "ids"))
            if info["color_by"] is None or info["clim"] is None:
                continue
            lo, hi = (float(x) for x in info["clim"])
            if info["color_by"] == "z":
                label = self._labels.get(info["id"]) or ("depth (m)" if hi <= 0 else "elevation (m)")
            else:
                label = self._labels.get(info["id"]) or "values"
            out.append(ObjectColoring(object=info["id"], name=info["name"], kind=info["kind"],
                                      color_by=info["color_by"], cmap=info["cmap"], table=self._tables.get(info["id"]),
                                      clim=(lo, hi), label=label))
        return out

    def _frame_objects(self, tile_drawn: np.ndarray, tile_pixels: np.ndarray, exact_counts: bool) -> list[int]:
        """Ids of the objects a frame shows: those with a tile holding pixels of the image (where
        ``tile_pixels`` counts the final image, ``exact_counts``; else those with a tile drawn), and
        translucent ones (lenses, slices with opacity < 1, which leave no pixel count) with a tile
        drawn."""
        key = (self._s.n_tiles, tuple(self._s.object_ids()))
        cached = getattr(self, "_tile_objects", None)  # each tile's object, kept while the tiles are the same
        if cached is None or cached[0] != key:
            cached = (key, np.asarray(self._s.tile_table()["object"]))
            self._tile_objects = cached
        t = cached[1]
        if len(t) != len(tile_drawn):  # the scene changed since the frame
            return []
        shown = (tile_pixels > 0) if exact_counts else tile_drawn
        ids = set(np.unique(t[shown]).tolist())
        for i in np.unique(t[tile_drawn]).tolist():
            if i in ids:
                continue
            kind = self._s.object_info(i)["kind"]
            sl = self._slices.get(i)
            if kind == "lens" or (kind == "slice" and (sl is None or sl[4] < 1.0)):
                ids.add(i)
        return [i for i in self.object_ids() if i in ids]

    def _label(self, id: int) -> str:
        info = self._s.object_info(id)
        return f"object {id} ({info['kind']}{', ' + repr(info['name']) if info['name'] else ''})"
