"""The scene: height fields and triangle meshes, tiled, with a fine and a coarse level of detail.

Every method checks its arguments' shapes and dtypes here (see :mod:`geocull._convert`) and their
values in Rust, and raises :class:`geocull.InputError` naming the argument on bad input.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from . import _convert as cv
from . import _geocull, _progress
from ._convert import MeshLike
from ._errors import InputError
from ._progress import ProgressLike

if TYPE_CHECKING:
    from ._geocull import ObjectInfo

__all__ = ["Scene"]

# dtype of the rows of Scene.tile_table().
_TILE_DTYPE = np.dtype([("object", "u4"), ("ix", "u4"), ("iy", "u4"), ("tris_fine", "u4"),
                        ("tris_coarse", "u4"), ("proxy_error", "f8"), ("bbox_min", "f8", (3,)),
                        ("bbox_max", "f8", (3,)), ("level_triangles", "u4", (6,)), ("level_error", "f8", (6,))])


class Scene:
    """A sub-surface scene: height fields and triangle meshes, each cut into tiles with a fine and
    a coarse level of detail. Coordinates are world units (metres), x and y horizontal, z up; inputs
    are kept in f64 and each object is stored relative to its own f64 origin (frames render relative
    to an origin near the camera), so UTM-sized coordinates keep full precision whatever the order
    objects are added in or how far they are translated. Building tiles runs in parallel; Ctrl-C
    during an ``add_*`` call raises KeyboardInterrupt within a fraction of a second and leaves the
    scene as it was."""

    def __init__(self) -> None:
        self._s = _geocull.Scene()

    @classmethod
    def _wrap(cls, inner: _geocull.Scene) -> Scene:
        s = cls.__new__(cls)
        s._s = inner
        return s

    def copy(self) -> Scene:
        """An independent copy: the same objects (ids, names, tiles, colours, visibility, offsets)
        in a new scene; editing either leaves the other as it is. ``copy.copy`` and
        ``copy.deepcopy`` do the same."""
        return Scene._wrap(self._s.copy())

    def __copy__(self) -> Scene:
        return self.copy()

    def __deepcopy__(self, memo: dict[int, Any]) -> Scene:
        return self.copy()

    def to_bytes(self) -> bytes:
        """The scene as bytes (a versioned little-endian layout of its objects and their tiles, as
        stored), for files and other processes; :meth:`from_bytes` reads them. Pickling uses it."""
        return self._s.to_bytes()

    @staticmethod
    def from_bytes(data: bytes) -> Scene:
        """A scene from :meth:`to_bytes`' bytes: it renders exactly the same images (InputError
        naming ``data`` if they are damaged or not a geocull scene)."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InputError(f"data: expected bytes, got {type(data).__name__}")
        return Scene._wrap(_geocull.Scene.from_bytes(bytes(data)))

    def __reduce__(self) -> tuple[Any, tuple[bytes]]:
        return (Scene.from_bytes, (self.to_bytes(),))

    def add_heightfield(
        self,
        z: ArrayLike,
        origin: ArrayLike = (0.0, 0.0),
        spacing: ArrayLike = (1.0, 1.0),
        tiles: ArrayLike = (1, 1),
        coarse_factor: float = 1.0,
        name: str | None = None,
        color: ArrayLike | None = None,
        null_value: float | None = None,
        rotation: float = 0.0,
        yflip: bool = False,
        progress: ProgressLike = None,
    ) -> int:
        """Add a height field (a horizon or a terrain).

        z: (ny, nx) array of heights (metres); x runs along columns, y along rows. NaN, masked samples
            of a ``numpy.ma.MaskedArray`` (e.g. xtgeo's ``surf.values``), and samples equal to
            ``null_value`` (e.g. -999.25, compared in z's own dtype, so float32 data matches
            ``float32(null_value)``) are holes: triangles touching them are dropped.
        origin: (x0, y0) world position of ``z[0, 0]`` (metres).  spacing: (dx, dy) > 0 sample
            spacing (metres), so ``z[j, i]`` sits at (x0 + i*dx, y0 + j*dy) when not rotated.
        tiles: (tx, ty) tiles along x and y (each at least one cell wide); tiles share border samples.
        coarse_factor: >= 1; the coarse proxy of each tile has about 1/coarse_factor of its triangles.
        name: an optional label.  color: (r, g, b) in [0, 1].
        rotation: degrees counter-clockwise (seen from above) about ``origin`` (xtgeo's convention):
            ``z[j, i]`` sits at ``origin + R(rotation) @ (i*dx, j*dy)``.  yflip: True for xtgeo's
            ``yflip=-1``: rows run towards -y in the grid's frame (``(i*dx, -j*dy)`` before the
            rotation); a bool, so xtgeo's 1 / -1 must be translated (``yflip=surf.yflip == -1``, or use
            :func:`geocull.io.from_xtgeo_surface`). Every culling mode works on rotated grids as on
            axis-aligned ones (horizon culling included).
        progress: None (a bar in notebooks for builds over a second, silence in scripts), True (a
            bar), False, or ``f(fraction, message)`` called with the fraction of tiles built
            (see :mod:`geocull._progress`).
        Returns the object id.
        """
        nv = None if null_value is None else cv.number(null_value, "null_value")
        za = cv.heights(z, nv)
        o = cv.vec2(origin, "origin")
        sp = cv.vec2(spacing, "spacing")
        t = cv.int_array(tiles, "tiles", 1, 2)
        tt = (cv.integer(t[0], "tiles[0]"), cv.integer(t[1], "tiles[1]"))
        with _progress.task(progress, tt[0] * tt[1], "add_heightfield: tiles"):  # read by the core
            return self._s.add_heightfield(
                za, o, sp, tt, cv.number(coarse_factor, "coarse_factor"), cv.name(name), cv.color(color), nv,
                cv.number(rotation, "rotation"), cv.boolean(yflip, "yflip", hint="xtgeo's yflip=-1 is yflip=True"),
            )

    def add_mesh(
        self,
        vertices: ArrayLike | MeshLike,
        faces: ArrayLike | None = None,
        kind: str = "mesh",
        tiles: int | None = None,
        coarse_factor: float = 1.0,
        name: str | None = None,
        color: ArrayLike | None = None,
        progress: ProgressLike = None,
    ) -> int:
        """Add a triangle mesh (a fault, an isosurface, any surface).

        vertices: (n, 3) world coordinates (metres, finite; a masked element of a
        ``numpy.ma.MaskedArray`` is an InputError).  faces: (m, 3) integer indices in [0, n),
        one row per triangle.  kind: a label ("fault", "mesh", ...).  tiles: None = one tile, k = about
        k spatially coherent clusters.  coarse_factor, name, color: as for :meth:`add_heightfield`.

        Instead of (vertices, faces), ``vertices`` may be a mesh object, with ``faces`` omitted: a
        ``trimesh.Trimesh`` (its vertices and faces), or a ``pyvista.PolyData`` (any PyVista dataset is
        reduced to its surface): polygons and triangle strips are triangulated, line and vertex cells
        are ignored with a :class:`geocull.GeocullWarning`; ``name`` and ``color`` default to the
        ``field_data`` written by :func:`geocull.io.to_pyvista`. Recognised by their attributes, so
        neither package is imported unless such an object is passed.
        progress: as for :meth:`add_heightfield` (the fraction of clusters built).
        Returns the object id.
        """
        mesh = cv.mesh_arrays(vertices)
        if mesh is not None:
            if faces is not None:
                raise InputError(f"faces: must be omitted when vertices is a {type(vertices).__name__}")
            vertices, faces = mesh.vertices, mesh.faces
            name = mesh.name if name is None else name
            color = mesh.color if color is None else color
        elif faces is None:
            raise InputError("faces: required with a vertex array (or pass a trimesh.Trimesh / pyvista.PolyData)")
        v = cv.vertices(vertices)
        f = cv.int_array(faces, "faces", 2, 3)
        if f.dtype.kind == "u" and f.size and f.max() > np.iinfo(np.int64).max:
            raise InputError("faces: index too large")
        f = np.ascontiguousarray(f, dtype=np.int64)
        if not isinstance(kind, str):
            raise InputError(f"kind: {kind!r} is not a string")
        k = None if tiles is None else cv.integer(tiles, "tiles")
        with _progress.task(progress, k or 1, "add_mesh: tiles"):  # read by the core
            return self._s.add_mesh(
                v, f, kind, k, cv.number(coarse_factor, "coarse_factor"), cv.name(name), cv.color(color)
            )

    def remove(self, id: int) -> None:
        """Remove object ``id``."""
        self._s.remove(cv.integer(id, "id"))

    def set_visible(self, id: int, visible: bool) -> None:
        """Show or hide object ``id`` (no re-upload)."""
        self._s.set_visible(cv.integer(id, "id"), bool(visible))

    def translate(self, id: int, offset: ArrayLike) -> None:
        """Move object ``id`` by offset = (dx, dy, dz) metres, added to earlier offsets (no re-upload)."""
        self._s.translate(cv.integer(id, "id"), cv.vec3(offset, "offset"))

    def set_color(self, id: int, color: ArrayLike) -> None:
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
        """A reference f64 origin (x, y, z) in metres: the first object's own origin (each object
        stores its positions relative to its own; renders use an origin near the camera)."""
        return self._s.origin

    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]] | None:
        """``((xmin, ymin, zmin), (xmax, ymax, zmax))`` world coordinates (metres) of every object's
        triangles, visible and hidden alike, offsets (:meth:`translate`) applied, no vertical
        exaggeration; ``None`` when the scene has no triangle (no object yet, or only height fields made
        wholly of holes). Computed in the core from the tiles' boxes (exact to float32 precision of the
        positions relative to each object's origin)."""
        return self._s.bounds

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
        tris_fine, tris_coarse, proxy_error (metres: how far the coarse proxy may lie from the fine
        triangles; height-field lattice proxies: the exact largest vertical distance, other proxies:
        meshoptimizer's estimate), bbox_min (3,), bbox_max (3,) (world coordinates, metres; NaN if
        empty), level_triangles (6,) and level_error (6,): the LOD levels 0..5 of the tile (level 0
        = fine, error 0; each further level about a quarter of the triangles; error in metres, NaN
        past the tile's last level) that ``lod="screen_error"`` chooses from."""
        c: Mapping[str, Any] = self._s.tile_table()
        t = np.zeros(len(c["object"]), dtype=_TILE_DTYPE)
        for k in _TILE_DTYPE.names or ():
            t[k] = c[k]
        return t

    def __repr__(self) -> str:
        return f"<geocull.Scene objects={len(self.object_ids())} tiles={self.n_tiles} triangles={self.n_triangles}>"
