"""The scene: height fields and triangle meshes, tiled, with a fine and a coarse level of detail.

Every method checks its arguments' shapes and dtypes here (see :mod:`geocull._convert`) and their
values in Rust, and raises :class:`geocull.InputError` naming the argument on bad input.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from . import _convert as cv
from . import _geocull, _progress
from ._convert import MeshLike
from ._errors import InputError
from ._progress import ProgressLike
from ._scene_colors import FAR_APART, SceneColorings, SharedZ, label_arg, pair
from ._scene_inputs import grid_inputs, heightfield_inputs, mesh_inputs, well_inputs
from ._scene_slices import SliceAxis, slice_position, stored_range
from .results import GridLevel

if TYPE_CHECKING:
    from ._geocull import ObjectInfo
    from .volume import Volume

__all__ = ["Scene", "ColorBy", "SliceAxis", "FAR_APART"]

#: What an object can be coloured by: its own z (world units, before vertical exaggeration and
#: without later translations) or the ``values`` it was added with.
ColorBy = Literal["z", "values"]

_COLOR_DOC = """
        Colour by data: ``values`` {values}; ``color_by`` "z" (the object's world z) or "values"
        (the default when ``values`` is given); ``cmap`` a colour map: a matplotlib name when
        matplotlib is installed (else one of the built-ins viridis, seismic, gray, terrain, plasma,
        RdBu_r, sampled from matplotlib's tables), a matplotlib ``Colormap``, or an (n, 3) / (n, 4)
        array of RGB(A) rows in [0, 1]; default viridis. ``clim`` (lo, hi): the scalars mapped to the
        colour map's two ends (below and above clamp; matplotlib's mapping of a 256-entry map, as
        PyVista draws it); default for values the drawn data's finite range, for z the scene's depth
        range: the lowest and highest z of every object coloured by z without a ``clim`` of its own
        (hidden ones too), updated as such objects are added, removed or recoloured, so that equal
        depths get equal colours across horizons. ``nan_color`` (r, g, b): the colour of NaN values
        (default mid grey, 0.5; +-inf values are refused, an InputError naming the first). A flat
        ``color`` and a colouring cannot be combined. ``label``: the
        name on the colour bar of :meth:`geocull.RenderResult.figure` (default the values' own name
        where they carry one: an xarray / pandas ``name``, an xtgeo log or property; else "values";
        colour by z is labelled "depth (m)")."""


# dtype of the rows of Scene.tile_table().
_TILE_DTYPE = np.dtype([("object", "u4"), ("ix", "u4"), ("iy", "u4"), ("tris_fine", "u4"),
                        ("tris_coarse", "u4"), ("proxy_error", "f8"), ("bbox_min", "f8", (3,)),
                        ("bbox_max", "f8", (3,)), ("level_triangles", "u4", (6,)), ("level_error", "f8", (6,)),
                        ("level_error_z", "f8", (6,)), ("level_shading_error", "f8", (6,))])


def _doc(values: str) -> str:
    return _COLOR_DOC.format(values=values).strip("\n").lstrip()


class Scene(SceneColorings):
    """A sub-surface scene: height fields and triangle meshes, each cut into tiles with a fine and
    a coarse level of detail. Coordinates are world units (metres), x and y horizontal, z up; inputs
    are kept in f64 and each object is stored relative to its own f64 origin (frames render relative
    to an origin near the camera), so UTM-sized coordinates keep full precision whatever the order
    objects are added in or how far they are translated. Building tiles runs in parallel; Ctrl-C
    during an ``add_*`` call raises KeyboardInterrupt within a fraction of a second and leaves the
    scene as it was."""

    def __init__(self) -> None:
        self._s = _geocull.Scene()
        # Slices' sources, for set_slice_index: id -> (volume, axis, name, colouring).
        self._slices: dict[int, tuple[Any, int, str | None, cv.Coloring, float]] = {}
        # Objects coloured by z over the scene's shared depth range (no clim of their own).
        self._zshared: dict[int, SharedZ] = {}
        # Colour bar labels (RenderResult.figure) and colour tables of the objects coloured by data.
        self._labels: dict[int, str] = {}
        self._tables: dict[int, np.ndarray] = {}

    @classmethod
    def _wrap(cls, inner: _geocull.Scene) -> Scene:
        s = cls.__new__(cls)
        s._s = inner
        s._slices = {}
        s._zshared = {}
        s._labels = {}
        s._tables = {}
        return s

    def copy(self) -> Scene:
        """An independent copy: the same objects (ids, names, tiles, colours, visibility, offsets)
        in a new scene; editing either leaves the other as it is. ``copy.copy`` and
        ``copy.deepcopy`` do the same."""
        s = Scene._wrap(self._s.copy())
        s._slices = dict(self._slices)
        s._zshared = dict(self._zshared)
        s._labels = dict(self._labels)
        s._tables = dict(self._tables)
        return s

    def __copy__(self) -> Scene:
        return self.copy()

    def __deepcopy__(self, memo: dict[int, Any]) -> Scene:
        return self.copy()

    def to_bytes(self) -> bytes:
        """The scene as bytes (a versioned little-endian layout of its objects and their tiles, as
        stored), for files and other processes; :meth:`from_bytes` reads them. Pickling uses it.
        The bytes hold every object's colours as they are (the shared depth range included), but
        not which objects follow the shared depth range nor the colour bar labels: a scene from
        :meth:`from_bytes` renders the same, and objects added to it later share a depth range of
        their own. Pickles (and :meth:`copy`) keep both."""
        return self._s.to_bytes()

    @staticmethod
    def from_bytes(data: bytes) -> Scene:
        """A scene from :meth:`to_bytes`' bytes: it renders exactly the same images (InputError
        naming ``data`` if they are damaged or not a geocull scene)."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InputError(f"data: expected bytes, got {type(data).__name__}")
        return Scene._wrap(_geocull.Scene.from_bytes(bytes(data)))

    def __reduce__(self) -> tuple[Any, tuple[bytes, dict[str, Any]]]:
        return (Scene._unpickle, (self.to_bytes(), self._python_state()))

    def _python_state(self) -> dict[str, Any]:
        """What the Python wrapper keeps beside the core's bytes (pickles carry it)."""
        return dict(zshared={k: tuple(v) for k, v in self._zshared.items()}, labels=dict(self._labels),
                    tables=dict(self._tables))

    @staticmethod
    def _unpickle(data: bytes, state: dict[str, Any] | None = None) -> Scene:
        s = Scene.from_bytes(data)
        if state:
            ids = set(s.object_ids())
            try:  # a damaged pickle's state is an InputError naming data, like its bytes
                z = {int(k): SharedZ(*v) for k, v in state.get("zshared", {}).items()}
                z = {k: v._replace(own=pair(v.own), applied=None if v.applied is None else pair(v.applied))
                     for k, v in z.items()}
                labels = {int(k): str(v) for k, v in state.get("labels", {}).items()}
                tables = {int(k): np.asarray(v, np.float64) for k, v in state.get("tables", {}).items()}
                if not set(z) | set(labels) | set(tables) <= ids or any(t.ndim != 2 or t.shape[1:] != (3,)
                                                                        for t in tables.values()):
                    raise ValueError("entries of objects the scene does not have, or tables not (n, 3)")
            except (TypeError, ValueError, AttributeError) as e:
                raise InputError(f"data: the pickle's Python state is damaged ({e})") from None
            s._zshared, s._labels, s._tables = z, labels, tables
        return s

    def add_heightfield(
        self,
        z: ArrayLike | Any,
        origin: ArrayLike | None = None,
        spacing: ArrayLike | None = None,
        tiles: ArrayLike = (1, 1),
        coarse_factor: float = 1.0,
        name: str | None = None,
        color: ArrayLike | None = None,
        null_value: float | None = None,
        rotation: float | None = None,
        yflip: bool | None = None,
        values: ArrayLike | None = None,
        color_by: ColorBy | None = None,
        cmap: Any = None,
        clim: ArrayLike | None = None,
        nan_color: ArrayLike | None = None,
        progress: ProgressLike = None,
        z_positive: Literal["up", "down"] | None = None,
        label: str | None = None,
        priority: int | None = None,
    ) -> int:
        """Add a height field (a horizon or a terrain).

        z: (ny, nx) array of heights (metres), or an ``xtgeo.RegularSurface`` (recognised by its
            attributes; read by :func:`geocull.io.from_xtgeo_surface`: its origin, spacing,
            rotation, yflip, undefined nodes as holes, its name; any of these given here wins).
            x runs along columns, y along rows. NaN, masked samples
            of a ``numpy.ma.MaskedArray`` (e.g. xtgeo's ``surf.values``), and samples equal to
            ``null_value`` (e.g. -999.25, compared in z's own dtype, so float32 data matches
            ``float32(null_value)``) are holes: triangles touching them are dropped; +-inf is
            refused (InputError naming ``z[j, i]``), as in volumes and colouring values.
        origin: (x0, y0) world position of ``z[0, 0]`` (metres, default (0, 0)).  spacing: (dx, dy) > 0
            sample spacing (metres, default (1, 1)), so ``z[j, i]`` sits at (x0 + i*dx, y0 + j*dy) when
            not rotated.
        tiles: (tx, ty) tiles along x and y (each at least one cell wide); tiles share border samples.
        coarse_factor: >= 1; the coarse proxy of each tile has about 1/coarse_factor of its triangles.
        name: an optional label.  color: (r, g, b) in [0, 1]; without it (and without a colouring)
            a height field is coloured by its z through viridis over the scene's depth range.
        rotation: degrees counter-clockwise (seen from above, default 0) about ``origin`` (xtgeo's convention):
            ``z[j, i]`` sits at ``origin + R(rotation) @ (i*dx, j*dy)``.  yflip: True for xtgeo's
            ``yflip=-1``: rows run towards -y in the grid's frame (``(i*dx, -j*dy)`` before the
            rotation); a bool, so xtgeo's 1 / -1 must be translated (``yflip=surf.yflip == -1``, or use
            :func:`geocull.io.from_xtgeo_surface`). Every culling mode works on rotated grids as on
            axis-aligned ones (horizon culling included).
        {color}
        progress: None (a bar in notebooks for builds over a second, silence in scripts), True (a
            bar), False, or ``f(fraction, message)`` called with the fraction of tiles built
            (see :mod:`geocull._progress`).
        z_positive: "up" (z holds elevations, metres up) or "down" (z holds depths or times positive
            down: drawn at -z); default "up" for arrays, "down" for xtgeo surfaces.
        priority: 0..=15, who wins a depth tie (higher is seen); default by kind (:meth:`set_priority`).
        Returns the object id.
        """
        za, o, sp, rotation, yflip, nv, name = heightfield_inputs(z, origin, spacing, rotation, yflip, null_value,
                                                                  name, z_positive)
        t = cv.int_array(tiles, "tiles", 1, 2)
        tt = (cv.integer(t[0], "tiles[0]"), cv.integer(t[1], "tiles[1]"))
        lab = label_arg(label, values)
        c = cv.coloring(color_by, values, cmap, clim, nan_color, 2)
        with _progress.task(progress, tt[0] * tt[1], "add_heightfield: tiles"):  # read by the core
            return self._added(self._s.add_heightfield(
                za, o, sp, tt, cv.number(coarse_factor, "coarse_factor"), cv.name(name), cv.color(color), nv,
                cv.number(rotation, "rotation"), cv.boolean(yflip, "yflip", hint="xtgeo's yflip=-1 is yflip=True"), c,
            ), c, lab, priority)

    def add_mesh(
        self,
        vertices: ArrayLike | MeshLike,
        faces: ArrayLike | None = None,
        kind: str = "mesh",
        tiles: int | None = None,
        coarse_factor: float = 1.0,
        name: str | None = None,
        color: ArrayLike | None = None,
        values: ArrayLike | None = None,
        color_by: ColorBy | None = None,
        cmap: Any = None,
        clim: ArrayLike | None = None,
        nan_color: ArrayLike | None = None,
        progress: ProgressLike = None,
        z_positive: Literal["up", "down"] | None = None,
        label: str | None = None,
        priority: int | None = None,
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
        ``field_data`` written by :func:`geocull.io.to_pyvista`. An ``xtgeo.TriangulatedSurface`` (its
        ``vertices`` and ``triangles``, its name) is taken too. Recognised by their attributes, so
        none of these packages is imported unless such an object is passed.
        z_positive: "up" (vertex z is elevation, metres up) or "down" (z is depth positive down, e.g.
        a TSurf fault in TVDSS: drawn at -z, each face's vertex order reversed so that its normal
        keeps its side of the surface); default "up", "down" for xtgeo objects (xtgeo's convention).
        {color}
        progress: as for :meth:`add_heightfield` (the fraction of clusters built).
        priority: 0..=15, who wins a depth tie (higher is seen); default by kind (:meth:`set_priority`).
        Returns the object id.
        """
        v, f, name, color = mesh_inputs(vertices, faces, name, color, z_positive)
        if not isinstance(kind, str):
            raise InputError(f"kind: {kind!r} is not a string")
        k = None if tiles is None else cv.integer(tiles, "tiles")
        lab = label_arg(label, values)
        c = cv.coloring(color_by, values, cmap, clim, nan_color, 1)
        with _progress.task(progress, k or 1, "add_mesh: tiles"):  # read by the core
            return self._added(self._s.add_mesh(
                v, f, kind, k, cv.number(coarse_factor, "coarse_factor"), cv.name(name), cv.color(color), c,
            ), c, lab, priority)

    def add_well(
        self,
        path: ArrayLike | Any,
        radius: float = 10.0,
        sides: int = 8,
        name: str | None = None,
        color: ArrayLike | None = None,
        values: ArrayLike | None = None,
        cmap: Any = None,
        clim: ArrayLike | None = None,
        nan_color: ArrayLike | None = None,
        log: str | None = None,
        max_stations: int | None = None,
        z_positive: Literal["up", "down"] | None = None,
        label: str | None = None,
        priority: int | None = None,
    ) -> int:
        """Add a well: ``path`` (n, 3) world stations (x, y, z metres, z up: pass z = -depth for
        depths) along a deviated well, drawn as a closed tube of ``radius`` metres with ``sides``
        (3..64) flat sides and flat end caps: an occluder like any mesh (object kind "well"), cut
        into tiles of 128 segments so that culling drops hidden or off-screen parts. Vertical
        exaggeration (``z_scale`` > 1) stretches the path, not the tube: its rings keep their
        ``radius`` (flattening, ``z_scale`` < 1, flattens the tube whole). Stations that
        repeat the previous one are dropped. ``values`` (n,): a log, one value per station,
        interpolated along the tube and coloured through ``cmap`` / ``clim`` / ``nan_color`` (as for
        :meth:`add_heightfield`); without values and ``color`` the well gets the palette colour.
        Each tile has levels of detail for ``lod="screen_error"``: the fine rings at fewer stations
        (a station is dropped where the tube there moves and turns its normals by little against
        the kept stations' rings), each level's error in metres in ``tile_table()["level_error"]``;
        every level shows the log's colours where the fine tube shows them (each pixel looks the
        log up at its station). The first level with at most 1/25 of the fine triangles (else the
        coarsest) is the prepass proxy.

        ``path`` may be an ``xtgeo.Well`` (recognised by its attributes): its stations and, with
        ``log`` (a log name, e.g. "Poro"), that log as ``values`` (undefined samples NaN), its name;
        ``max_stations`` keeps at most that many stations (RMS files hold one every ~0.15 m); see
        :func:`geocull.io.from_xtgeo_well`. ``values`` and ``name`` given here win.
        z_positive: "up" (path z is elevation, metres up) or "down" (z is depth positive down, e.g.
        TVDSS: drawn at -z); default "up" for arrays, "down" for xtgeo wells.
        label: the log's name on colour bars (default ``log``, or the values' own name; see
        :meth:`add_heightfield`).
        priority: 0..=15, who wins a depth tie (higher is seen); default by kind (:meth:`set_priority`).
        Returns the object id."""
        p, values, lab, name = well_inputs(path, values, label, log, max_stations, name, z_positive)
        c = cv.coloring(None, values, cmap, clim, nan_color, 1)
        return self._added(self._s.add_well(
            p, cv.number(radius, "radius"), cv.integer(sides, "sides"), cv.name(name), cv.color(color), c,
        ), c, lab, priority)

    def add_slice(
        self,
        volume: Volume,
        axis: SliceAxis | int | None = None,
        index: int | None = None,
        cmap: Any = "seismic",
        clim: ArrayLike | None = None,
        opacity: float = 1.0,
        name: str | None = None,
        nan_color: ArrayLike | None = None,
        *,
        inline: float | None = None,
        crossline: float | None = None,
        time: float | None = None,
        depth: float | None = None,
        label: str | None = None,
        priority: int | None = None,
    ) -> int:
        """Add a seismic slice of ``volume``: ``axis`` "inline" (or 0: the plane of constant i, the
        volume's first axis), "crossline" (1: constant j) or "sample" (2: constant k, a time or depth
        slice), at sample ``index`` along that axis, counted in the order of the volume's values as
        given (the file's order): sample 0 is the first sample (the shallowest for
        z_positive="down" volumes: SEG-Y, xtgeo), crossline 0 the first crossline (also on
        left-handed surveys). Or, instead of ``axis`` and ``index``, one survey number (volumes with
        :attr:`Volume.inlines` / :attr:`Volume.crosslines` / :attr:`Volume.samples`, from SEG-Y or
        xtgeo): ``inline=10800``, ``crossline=2650``, ``time=1200.0`` (ms) or ``depth=1650.0`` (m; both
        read the sample numbers, in the file's units): the nearest line or sample; a number outside
        the survey's range (beyond half a step) is an InputError naming the keyword and listing the
        range.

        It is drawn as the lattice of the volume's samples on the plane (world positions from the
        volume's origin, spacing and rotation), each sample's value coloured through ``cmap``
        (default "seismic") over ``clim`` (default the whole volume's finite range, so every slice of
        a volume shares its colours) and interpolated across each triangle; NaN samples get
        ``nan_color``. Slices are opaque occluders (object kind "slice") culled like any object;
        :meth:`set_slice_index` moves one. ``opacity`` in (0, 1]: below 1 the slice is translucent,
        drawn as volume lenses are (blended after the opaque image, unlit, never occluding, skipped
        where hidden). ``label``: the colour bar's (as for :meth:`add_heightfield`).
        priority: 0..=15, who wins a depth tie (higher is seen); default by kind (:meth:`set_priority`). Returns the
        object id."""
        from .volume import Volume

        cv.expect_instance(volume, Volume, "volume")
        lab = label_arg(label)
        op = cv.number(opacity, "opacity")
        ax, idx = slice_position(volume, axis, index, inline, crossline, time, depth)
        c = cv.coloring("values", None, cmap, clim, nan_color, 1)
        assert c is not None
        id = self._s.add_slice(volume._v, ax, idx, cv.name(name), c, op)
        self._slices[id] = (volume, ax, name, c, op)
        return self._added(id, c, lab, priority)

    def add_isosurface(
        self,
        volume: Volume,
        isovalue: float,
        tiles: int | None = None,
        coarse_factor: float = 25.0,
        name: str | None = None,
        color: ArrayLike | None = None,
        values: Volume | None = None,
        color_by: ColorBy | None = None,
        cmap: Any = None,
        clim: ArrayLike | None = None,
        nan_color: ArrayLike | None = None,
        progress: ProgressLike = None,
        label: str | None = None,
        priority: int | None = None,
    ) -> int:
        """Add the isosurface ``volume == isovalue`` (a salt body, in the volume's units) as an
        object of the scene (kind "isosurface"): the welded, crack-free marching-cubes surface of
        :func:`geocull.iso.extract_isosurface` (NaN samples are outside the domain), cut into
        ``tiles`` spatially coherent tiles (default one per ~4096 triangles) with coarse proxies, drawn
        with the other objects and culled by them like any mesh (three_pass hides a salt body under a
        horizon). :meth:`Renderer.render_isosurface` stays the single-object path with the volume's
        own implicit occluders. The scene keeps the isosurface's *enclosed occluder boxes* (cells
        wholly on one side of ``isovalue`` that no ray from outside the volume reaches without
        crossing the surface; none for rotated or lazy volumes, nor after :meth:`from_bytes`), with
        which ``culling="implicit"`` also culls what the salt body itself hides.

        values: a second :class:`Volume` on the same grid (the same samples per axis, origin,
        spacing and rotation: built as ``volume`` was, e.g. the amplitude cube of a salt-probability
        cube), shown on the surface: each vertex takes the value interpolated between the two
        samples of its cell edge, with the weights that placed it (NaN where either is NaN, drawn in
        ``nan_color``; the rare vertex inside a cell, at the centre of a fanned loop, takes the
        trilinear value there); ``clim`` defaults to that volume's finite range, as for its slices.
        Without ``values`` or ``color``, ``cmap`` / ``clim`` colour the surface by z; with neither,
        it takes the palette colour.
        {color}
        progress: as for :meth:`add_heightfield` (the fraction of tiles built, once the surface is
            extracted).
        priority: 0..=15, who wins a depth tie (higher is seen); default by kind (:meth:`set_priority`).
        Returns the object id."""
        from .volume import Volume

        cv.expect_instance(volume, Volume, "volume")
        if values is not None:
            cv.expect_instance(values, Volume, "values")
        by = "values" if color_by is None and values is not None else color_by
        c = cv.coloring(by, None, cmap, clim, nan_color, 1)
        lab = label_arg(label)
        k = None if tiles is None else cv.integer(tiles, "tiles")
        with _progress.task(progress, k or 1, "add_isosurface: tiles"):  # total set by the core
            return self._added(self._s.add_isosurface(volume._v, cv.number(isovalue, "isovalue"), k,
                                                      cv.number(coarse_factor, "coarse_factor"), cv.name(name),
                                                      cv.color(color), c, None if values is None else values._v),
                               c, lab, priority)

    def add_lens(
        self,
        volume: Volume,
        box: ArrayLike,
        cmap: Any = "viridis",
        clim: ArrayLike | None = None,
        opacity: float = 0.3,
        name: str | None = None,
        nan_color: ArrayLike | None = None,
        label: str | None = None,
        priority: int | None = None,
    ) -> int:
        """Add a volume lens: the semi-transparent sub-volume of ``volume`` over ``box`` =
        ((i0, i1), (j0, j1), (k0, k1)), inclusive sample index ranges (at least 2 samples along each
        axis) counted in the order of the volume's values as given, as :meth:`add_slice`'s indices
        (sample 0 the shallowest of a z_positive="down" volume), coloured by its samples through
        ``cmap`` over ``clim`` (default the whole volume's range; NaN samples in ``nan_color``) with
        ``opacity`` in (0, 1) per slice. It is drawn as a stack of slices through the box, one per
        sample along the axis closest to the view direction, farthest first, alpha-blended over the
        opaque image, unlit and writing no depth (object kind "lens"). It never occludes; each frame
        its slices' boxes are tested against the opaque depth and hidden slices are not drawn (stats
        ``lens_slices_tested``, ``lens_slices_drawn``, ``lenses_hidden``). ``label``: the colour
        bar's (as for :meth:`add_heightfield`).
        priority: 0..=15, who wins a depth tie (higher is seen); default by kind (:meth:`set_priority`).
        Returns the object id."""
        from .volume import Volume

        cv.expect_instance(volume, Volume, "volume")
        lab = label_arg(label)
        b = cv.int_array(box, "box", 2, 2)
        if b.shape != (3, 2):
            raise InputError(f"box: shape {b.shape} is not (3, 2): ((i0, i1), (j0, j1), (k0, k1))")
        bx = tuple(stored_range(volume, a, cv.integer(b[a, 0], f"box[{a}]"), cv.integer(b[a, 1], f"box[{a}]"))
                   for a in range(3))
        c = cv.coloring("values", None, cmap, clim, nan_color, 1)
        assert c is not None
        id = self._s.add_lens(volume._v, bx, cv.number(opacity, "opacity"), cv.name(name), c)  # type: ignore[arg-type]
        return self._added(id, c, lab, priority)

    def add_grid(
        self,
        corners: ArrayLike | Any,
        active: ArrayLike | None = None,
        region: ArrayLike | Any | None = None,
        values: ArrayLike | Any | None = None,
        cmap: Any = None,
        clim: ArrayLike | None = None,
        blocks: ArrayLike = (8, 8),
        name: str | None = None,
        color: ArrayLike | None = None,
        nan_color: ArrayLike | None = None,
        progress: ProgressLike = None,
        z_positive: Literal["up", "down"] | None = None,
        label: str | None = None,
        priority: int | None = None,
    ) -> int:
        """Add a reservoir grid (a truncated corner-point grid, Eclipse GRDECL / RESQML / xtgeo
        ``Grid``; :mod:`geocull.grid` converts those).

        corners: (nk, nj, ni, 8, 3) world coordinates (metres, z up) of each cell's corners, kept in
            f64 (stored relative to the grid's own origin); corner c of a cell has i-bit ``c & 1``,
            j-bit ``(c >> 1) & 1``, k-bit ``(c >> 2) & 1`` (k-bit 0 = the cell's top), k = 0 the top
            layer. Collapsed corners (pinch-outs, zero-thickness cells) are legal; a non-finite corner
            of an active cell is an InputError naming it (inactive cells may hold anything).
        active: (nk, nj, ni) bool, or integers as Eclipse's ACTNUM (0 inactive, any other value
            active; default all active): inactive cells are holes (one enclosed by
            active cells is a cavity, not drawn while the eye is outside the grid).
        region: (nk, nj, ni) int region ids (fault blocks, strata; default one region): cells never
            merge across regions; faces between regions are built for both (each region's surface
            is closed) and not drawn while the eye is outside the grid.
        values: (nk, nj, ni) float cell property, coloured through ``cmap`` / ``clim`` /
            ``nan_color`` as for :meth:`add_heightfield` (flat per cell; a merged face takes the mean
            of its cells' values). Without values or ``color`` the grid gets its palette colour.
        blocks: (bi, bj) cells per block along i and j, each in 1..32: a block is a tile (culled as
            one) with its own cell-merging levels (a quadtree over its columns, up to log2 of its
            size), chosen per frame by ``Renderer.render(grid_lod=...)``.
        Drawn: the boundary faces of the active cells of each region (interior faces never built;
            faces on faults split where the neighbours' corners differ, so each region's surface is
            watertight at every level). Built block by block in parallel with the GIL released;
            ``progress`` as for :meth:`add_heightfield` (the fraction of blocks built).
        xtgeo: ``corners`` may be an ``xtgeo.Grid`` (recognised by its attributes; read by
            :func:`geocull.io.from_xtgeo_grid`: corners, ACTNUM as ``active`` unless given, its name),
            and then ``values`` and ``region`` may be an ``xtgeo.GridProperty`` or the name of one of
            the grid's properties (a GridProperty is taken with array corners too); ``region``'s
            undefined / inactive cells become region -1.
        z_positive: "up" (corner z is elevation, metres up) or "down" (z is depth positive down, e.g.
            Eclipse / xtgeo TVDSS: drawn at -z); default "up" for arrays, "down" for xtgeo grids.
        label: the property's name on colour bars (default the property's name when ``values`` is
            one, or a name; see :meth:`add_heightfield`).
            priority: 0..=15, who wins a depth tie (higher is seen); default by kind (:meth:`set_priority`).
            Returns the object id."""
        c, act, reg, values, lab, name = grid_inputs(corners, active, region, values, label, name, z_positive)
        b = cv.int_array(blocks, "blocks", 1)
        if b.shape != (2,):
            raise InputError(f"blocks: shape {b.shape} is not (2,)")
        bb = (cv.integer(b[0], "blocks[0]"), cv.integer(b[1], "blocks[1]"))
        n_blocks = -(-c.shape[2] // max(bb[0], 1)) * -(-c.shape[1] // max(bb[1], 1))
        col = cv.coloring(None, values, cmap, clim, nan_color, 3)
        with _progress.task(progress, n_blocks, "add_grid: blocks"):  # read by the core
            gid = self._s.add_grid(c, act, reg, bb, cv.name(name), cv.color(color), col)
            return self._added(gid, col, lab, priority)

    def grid_levels(self, id: int) -> list[GridLevel]:
        """Per level of grid ``id`` (level 0 = every boundary face, then each cell-merging level):
        cells (merged cells holding a drawn cell), faces (polygons before triangulation),
        triangles (interior_triangles of them: faces between regions and of cavities, which frames
        leave out while the eye is outside the grid), vertices, volume (m^3 enclosed by the
        level's surface) and volume_change (relative to level 0; blocks with fewer levels count
        with their coarsest)."""
        levels = self._s.grid_levels(cv.integer(id, "id"))
        v0 = levels[0]["volume"] if levels else 0.0
        return [GridLevel(**lv, volume_change=(lv["volume"] - v0) / v0 if v0 else 0.0) for lv in levels]

    def set_slice_index(
        self,
        id: int,
        index: int | None = None,
        *,
        inline: float | None = None,
        crossline: float | None = None,
        time: float | None = None,
        depth: float | None = None,
    ) -> None:
        """Move slice ``id`` to sample ``index`` along its axis (counted in the file's order, as
        :meth:`add_slice`'s), or to the nearest survey number along its axis (``inline=`` for an
        inline slice, ``crossline=``, ``time=`` / ``depth=`` for a sample slice): its geometry is
        rebuilt from the volume (the other objects are untouched) and a renderer's next frame
        rewrites only it on the GPU (``stats["objects_patched"]``; the whole scene is uploaded again
        where objects were also added or removed). The slice keeps its id, name, colouring,
        visibility and offset."""
        i = cv.integer(id, "id")
        if i not in self._slices:
            raise InputError(f"id: object {i} is not a slice added to this scene object (copies and "
                             "unpickled scenes do not keep the volumes of their slices)")
        volume, ax, name, c, op = self._slices[i]
        _, idx = slice_position(volume, None, index, inline, crossline, time, depth, fixed_axis=ax)
        self._s.add_slice(volume._v, ax, idx, cv.name(name), c, op, i)

    def remove(self, id: int) -> None:
        """Remove object ``id`` (the shared depth range is then that of the objects left)."""
        i = cv.integer(id, "id")
        self._s.remove(i)
        self._slices.pop(i, None)
        self._labels.pop(i, None)
        self._tables.pop(i, None)
        if self._zshared.pop(i, None) is not None:
            self._share_depth_range()

    def set_priority(self, id: int, priority: int | None) -> None:
        """Which of two surfaces at the same depth is seen: object ``id``'s priority 0..=15 (higher
        wins), or None for its kind's: wells 5, height fields 4, meshes (faults, isosurfaces) 3,
        reservoir grids 2, slices 1, lenses 0 (no re-upload). Coincident surfaces (a grid's top
        built from the horizon beside it, a fault traced on a grid's fault faces) then draw without
        speckle and every exact culling mode gives the same image as ``culling="none"``. An object
        of priority p is drawn as if a fraction (p - 4) x 2^-21 of its distance nearer (0.5 mm at
        1 km per step; horizons exactly where they are): reported depths include it, and surfaces
        closer than that are ordered by priority."""
        self._s.set_priority(cv.integer(id, "id"), None if priority is None else cv.integer(priority, "priority"))

    def set_visible(self, id: int, visible: bool) -> None:
        """Show or hide object ``id`` (no re-upload)."""
        self._s.set_visible(cv.integer(id, "id"), bool(visible))

    def translate(self, id: int, offset: ArrayLike) -> None:
        """Move object ``id`` by offset = (dx, dy, dz) metres, added to earlier offsets (no re-upload)."""
        self._s.translate(cv.integer(id, "id"), cv.vec3(offset, "offset"))

    def set_color(self, id: int, color: ArrayLike) -> None:
        """Draw object ``id`` in one flat colour (r, g, b) in [0, 1], ending any colour by data (no
        re-upload)."""
        i = cv.integer(id, "id")
        self._s.set_color(i, cv.vec3(color, "color"))
        self._note_coloring(i, None, None)

    def set_color_by(
        self, id: int, color_by: ColorBy = "z", cmap: Any = None, clim: ArrayLike | None = None,
        nan_color: ArrayLike | None = None, label: str | None = None,
    ) -> None:
        """Colour object ``id`` through a colour map by its z or by the values it was added with
        (``cmap``, ``clim``, ``nan_color``, ``label`` as for :meth:`add_heightfield`: by z without
        ``clim``, over the scene's shared depth range; no re-upload)."""
        c = cv.coloring(color_by, None, cmap, clim, nan_color, 1)
        assert c is not None
        i = cv.integer(id, "id")
        if label is None and c[0] == "values":
            label = self._labels.get(i)  # the values keep their name
        self._s.set_color_by(i, c)
        self._note_coloring(i, c, label_arg(label))

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
        past the tile's last level) that ``lod="screen_error"`` chooses from, level_error_z (6,):
        the vertical part of that error (metres, at most level_error; vertical exaggeration
        stretches only this part: a vertical well's thinner polygon does not grow on screen), and
        level_shading_error
        (6,): how far the lit pass's normals on each level may turn from level 0's (the largest chord
        between unit normals, unitless, 0 to sqrt(2); 0 for height fields, which shade from their
        fine surface at every level, and grids; NaN past the last level): ``lod="screen_error"``
        takes a level only if it changes the lit colour by at most half an 8-bit level."""
        c: Mapping[str, Any] = self._s.tile_table()
        t = np.zeros(len(c["object"]), dtype=_TILE_DTYPE)
        for k in _TILE_DTYPE.names or ():
            t[k] = c[k]
        return t

    def __repr__(self) -> str:
        return f"<geocull.Scene objects={len(self.object_ids())} tiles={self.n_tiles} triangles={self.n_triangles}>"


# The colouring paragraph of the add functions' docstrings.
Scene.add_heightfield.__doc__ = (Scene.add_heightfield.__doc__ or "").replace(
    "{color}", _doc("(ny, nx) like z: one scalar per sample (masked samples are NaN)"))
Scene.add_mesh.__doc__ = (Scene.add_mesh.__doc__ or "").replace("{color}", _doc("(n,): one scalar per vertex"))
Scene.add_isosurface.__doc__ = (Scene.add_isosurface.__doc__ or "").replace(
    "{color}", _doc("a Volume on the isosurface's grid (above)"))
