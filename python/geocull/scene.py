"""The scene: height fields and triangle meshes, tiled, with a fine and a coarse level of detail.

Every method checks its arguments' shapes and dtypes here (see :mod:`geocull._convert`) and their
values in Rust, and raises :class:`geocull.InputError` naming the argument on bad input.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _convert as cv
from . import _geocull
from ._errors import InputError

if TYPE_CHECKING:
    from ._geocull import ObjectInfo

__all__ = ["Scene"]

# dtype of the rows of Scene.tile_table().
_TILE_DTYPE = np.dtype([("object", "u4"), ("ix", "u4"), ("iy", "u4"), ("tris_fine", "u4"),
                        ("tris_coarse", "u4"), ("bbox_min", "f8", (3,)), ("bbox_max", "f8", (3,))])


class Scene:
    """A sub-surface scene: height fields and triangle meshes, each cut into tiles with a fine and
    a coarse level of detail. Coordinates are world units (metres), x and y horizontal, z up; inputs
    are kept in f64 and stored relative to one scene origin, so UTM-sized coordinates keep full
    precision. Building tiles runs in parallel; Ctrl-C during an ``add_*`` call raises
    KeyboardInterrupt within a fraction of a second and leaves the scene as it was."""

    def __init__(self) -> None:
        self._s = _geocull.Scene()

    def add_heightfield(
        self,
        z: Any,
        origin: Sequence[float] = (0.0, 0.0),
        spacing: Sequence[float] = (1.0, 1.0),
        tiles: Sequence[int] = (1, 1),
        coarse_factor: float = 1.0,
        name: str | None = None,
        color: Sequence[float] | None = None,
        null_value: float | None = None,
    ) -> int:
        """Add a height field (a horizon or a terrain).

        z: (ny, nx) array of heights (metres); x runs along columns, y along rows. NaN, or samples
            equal to ``null_value`` (e.g. -999.25), are holes: triangles touching them are dropped.
        origin: (x0, y0) world position of ``z[0, 0]`` (metres).  spacing: (dx, dy) > 0 sample
            spacing (metres), so ``z[j, i]`` sits at (x0 + i*dx, y0 + j*dy).
        tiles: (tx, ty) tiles along x and y (each at least one cell wide); tiles share border samples.
        coarse_factor: >= 1; the coarse proxy of each tile has about 1/coarse_factor of its triangles.
        name: an optional label.  color: (r, g, b) in [0, 1].  Returns the object id.
        """
        za = cv.float_array(z, "z", 2)
        o = cv.vec2(origin, "origin")
        sp = cv.vec2(spacing, "spacing")
        t = cv.int_array(tiles, "tiles", 1, 2)
        tt = (cv.integer(t[0], "tiles[0]"), cv.integer(t[1], "tiles[1]"))
        nv = None if null_value is None else cv.number(null_value, "null_value")
        return self._s.add_heightfield(
            za, o, sp, tt, cv.number(coarse_factor, "coarse_factor"), cv.name(name), cv.color(color), nv
        )

    def add_mesh(
        self,
        vertices: Any,
        faces: Any,
        kind: str = "mesh",
        tiles: int | None = None,
        coarse_factor: float = 1.0,
        name: str | None = None,
        color: Sequence[float] | None = None,
    ) -> int:
        """Add a triangle mesh (a fault, an isosurface, any surface).

        vertices: (n, 3) world coordinates (metres, finite).  faces: (m, 3) integer indices in [0, n),
        one row per triangle.  kind: a label ("fault", "mesh", ...).  tiles: None = one tile, k = about
        k spatially coherent clusters.  coarse_factor, name, color: as for :meth:`add_heightfield`.
        Returns the object id.
        """
        v = cv.float_array(vertices, "vertices", 2, 3)
        f = cv.int_array(faces, "faces", 2, 3)
        if f.dtype.kind == "u" and f.size and f.max() > np.iinfo(np.int64).max:
            raise InputError("faces: index too large")
        f = np.ascontiguousarray(f, dtype=np.int64)
        if not isinstance(kind, str):
            raise InputError(f"kind: {kind!r} is not a string")
        k = None if tiles is None else cv.integer(tiles, "tiles")
        return self._s.add_mesh(
            v, f, kind, k, cv.number(coarse_factor, "coarse_factor"), cv.name(name), cv.color(color)
        )

    def remove(self, id: int) -> None:
        """Remove object ``id``."""
        self._s.remove(cv.integer(id, "id"))

    def set_visible(self, id: int, visible: bool) -> None:
        """Show or hide object ``id`` (no re-upload)."""
        self._s.set_visible(cv.integer(id, "id"), bool(visible))

    def translate(self, id: int, offset: Sequence[float]) -> None:
        """Move object ``id`` by offset = (dx, dy, dz) metres, added to earlier offsets (no re-upload)."""
        self._s.translate(cv.integer(id, "id"), cv.vec3(offset, "offset"))

    def set_color(self, id: int, color: Sequence[float]) -> None:
        """Set the colour of object ``id``: (r, g, b) in [0, 1] (no re-upload)."""
        self._s.set_color(cv.integer(id, "id"), cv.vec3(color, "color"))

    @property
    def n_tiles(self) -> int:
        """Number of tiles over all objects."""
        return self._s.n_tiles

    @property
    def n_triangles(self) -> int:
        """Number of fine (level 0) triangles over all objects."""
        return self._s.n_triangles

    @property
    def origin(self) -> tuple[float, float, float]:
        """The f64 origin (x, y, z) in metres that positions are stored relative to (set by the first object)."""
        return self._s.origin

    @property
    def host_bytes(self) -> int:
        """Bytes of geometry held in host memory."""
        return self._s.host_bytes

    def object_ids(self) -> list[int]:
        """Ids of the scene's objects, in the order they were added."""
        return self._s.object_ids()

    def object_info(self, id: int) -> ObjectInfo:
        """Dict of object ``id``: id, name (str | None), kind, color (r, g, b), visible, offset
        (dx, dy, dz) metres, n_tiles, n_triangles (fine)."""
        return self._s.object_info(cv.integer(id, "id"))

    def geometry(self, id: int) -> tuple[np.ndarray, np.ndarray]:
        """The fine triangles of object ``id``: vertices (n, 3) float64 world coordinates (metres,
        offset applied) and faces (m, 3) int64 indices into them."""
        return self._s.geometry(cv.integer(id, "id"))

    def tile_table(self) -> np.ndarray:
        """One row per tile, in the renderer's tile order (the index of ``tile_pixels``), a structured
        array with fields object (id), ix, iy (tile position in its object),
        tris_fine, tris_coarse, bbox_min (3,), bbox_max (3,) (world coordinates, metres; NaN if empty)."""
        c: Mapping[str, Any] = self._s.tile_table()
        t = np.zeros(len(c["object"]), dtype=_TILE_DTYPE)
        for k in _TILE_DTYPE.names or ():
            t[k] = c[k]
        return t

    def __repr__(self) -> str:
        return f"<geocull.Scene objects={len(self.object_ids())} tiles={self.n_tiles} triangles={self.n_triangles}>"
