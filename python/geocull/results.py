"""Rendered frames: :class:`RenderResult` (scenes), :class:`IsoResult` (isosurfaces), their typed
``stats`` dicts :class:`RenderStats` / :class:`IsoStats`, and a dependency-free PNG encoder.

Image conventions shared by every frame: arrays are (H, W, ...) with row 0 at the top of the image
and column 0 at its left; depths are distances along the camera's view axis in world units
(metres, exaggerated by the camera's ``z_scale``), +inf where nothing was drawn; images are RGBA
with alpha 255, the renderer's background (:attr:`geocull.Renderer.background`) where nothing was
drawn.
"""

import math
import struct
import zlib
from typing import TYPE_CHECKING, Any, Generic, Literal, NotRequired, TypedDict, TypeVar, cast

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ._geocull import IsoOutput, RenderOutput
    from .camera import Camera

__all__ = ["RenderStats", "IsoStats", "GridLevel", "ObjectColoring", "RenderResult", "IsoResult", "encode_png"]


class RenderStats(TypedDict):
    """``RenderResult.stats`` of a scene frame (:meth:`geocull.Renderer.render`). The keys without
    ``NotRequired`` are present for every strategy; the others belong to one strategy (or need GPU
    timestamps) and are absent elsewhere. Times are milliseconds, counts whole numbers."""

    triangles_fine_total: int  # fine (level 0) triangles over every tile of the scene (hidden objects included)
    triangles_drawn: int  # fine triangles drawn in the final pass
    tiles_total: int  # tiles in the scene (= len(tile_pixels))
    tiles_drawn: int  # tiles drawn in the final pass (= tile_drawn.sum())
    cull_ms: float  # ms, CPU time of the strategy's decision (CPU culling, or recording its GPU passes)
    draw_ms: float  # ms, GPU time of the final lit pass (0 without GPU timestamps)
    total_ms: float  # ms, wall time from the call to the GPU finishing the frame, read-back excluded
    readback_ms: float  # ms, wall time to copy image, depth and counts back and convert them
    gpu_timestamps: bool  # whether the adapter gave GPU timestamps (draw_ms is 0 without)
    upload_ms: float  # ms, wall time of the frame's geometry upload (part of total_ms; ~0 when unchanged)
    objects_patched: int  # objects whose replaced geometry was rewritten in place (a moved slice); 0 otherwise
    draw_passes: int  # render passes of the final lit draw (Renderer.pass_triangles; 1 when unbounded)
    triangles_prepass: NotRequired[int]  # three_pass: coarse-proxy triangles drawn in the depth prepass
    prepass_ms: NotRequired[float]  # three_pass with GPU timestamps: ms, GPU time of the depth prepass
    count_ms: NotRequired[float]  # three_pass with GPU timestamps: ms, GPU time of the count + select passes
    nodes_visited: NotRequired[int]  # horizon: quadtree nodes visited, all height fields together
    nodes_culled: NotRequired[int]  # horizon: quadtree nodes culled, all height fields together
    fields_unculled: NotRequired[int]  # horizon: height fields the view left unculled (e.g. within 30 deg of vertical)
    trees_built: NotRequired[int]  # horizon: quadtrees built this frame (0 when all were cached)
    cache_bytes: NotRequired[int]  # horizon: bytes of quadtrees cached after this frame (<= Renderer.cache_budget)
    tiles_outside: NotRequired[int]  # frustum: tiles whose boxes lie outside the view
    tiles_box_tested: NotRequired[int]  # three_pass conservative / predict_errors, temporal: boxes tested
    tiles_slab_tested: NotRequired[int]  # of those, height-field tiles tested with their slabs
    triangles_slab_test: NotRequired[int]  # the tested slabs' triangles (those behind an open gate are rasterised)
    triangles_slab_gates: NotRequired[int]  # their gates' triangles (coarser slabs; not drawn for first-set tiles)
    tiles_reused: NotRequired[int]  # temporal: tiles drawn first because they were visible in the last frame
    frame_repeated: NotRequired[int]  # temporal: 1 when it repeated the last frame (its visible tiles, untested)
    tiles_proven_hidden: NotRequired[int]  # three_pass conservative, temporal: hidden by a height field (CPU proof)
    implicit_occluder_boxes: NotRequired[int]  # implicit: isosurface occluder boxes drawn into the box test's depth
    implicit_objects: NotRequired[int]  # implicit: isosurfaces whose occluders were used this frame
    tiles_drawn_first: NotRequired[int]  # three_pass conservative / predict_errors: tiles the prepass chose
    tiles_drawn_second: NotRequired[int]  # three_pass conservative: tiles added by the box test
    test_ms: NotRequired[float]  # three_pass conservative / predict_errors, temporal with GPU timestamps: ms, box test
    tiles_at_risk: NotRequired[int]  # three_pass predict_errors: culled tiles whose box shows in front
    predicted_max_missing_pixels: NotRequired[int]  # three_pass predict_errors: upper bound of missed pixels
    triangles_level0: NotRequired[int]  # lod="screen_error": triangles drawn at level 0 (fine)
    triangles_level1: NotRequired[int]  # lod="screen_error": ... at level 1 (about 1/4 of level 0)
    triangles_level2: NotRequired[int]
    triangles_level3: NotRequired[int]
    triangles_level4: NotRequired[int]
    triangles_level5: NotRequired[int]
    lod_max_error_px: NotRequired[float]  # lod="screen_error": largest projected error drawn, pixels
    lod_max_error_m: NotRequired[float]  # lod="screen_error": largest geometric error drawn, world units
    tiles_fine_depth: NotRequired[int]  # lod: height-field tiles writing the fine depth (an object within their error)
    tiles_grouped: NotRequired[int]  # lod: height-field tiles drawing sides shared coarse with neighbours (lod::groups)
    lens_slices_tested: NotRequired[int]  # scenes with a visible lens or translucent slice: slices whose box was tested
    lens_slices_drawn: NotRequired[int]  # ... of which in front of the opaque image somewhere (drawn)
    lenses_hidden: NotRequired[int]  # ... lenses wholly hidden (nothing drawn)
    grid_cells_level0: NotRequired[int]  # scenes with a grid: merged cells drawn at level 0 (drawn blocks)
    grid_faces_level0: NotRequired[int]  # scenes with a grid: faces (polygons) drawn at level 0
    grid_cells_level1: NotRequired[int]  # ... at cell-merging level 1 (2 x 2 columns merged)
    grid_faces_level1: NotRequired[int]
    grid_cells_level2: NotRequired[int]
    grid_faces_level2: NotRequired[int]
    grid_cells_level3: NotRequired[int]
    grid_faces_level3: NotRequired[int]
    grid_cells_level4: NotRequired[int]
    grid_faces_level4: NotRequired[int]
    grid_cells_level5: NotRequired[int]
    grid_faces_level5: NotRequired[int]
    # scenes with a grid: interior triangles of the drawn blocks left out (faces between regions and of
    # cavities, hidden from outside the grid's cells; left out while the grid's box lies wholly beyond
    # the near plane)
    grid_interior_triangles_skipped: NotRequired[int]


class GridLevel(TypedDict):
    """One level of :meth:`geocull.Scene.grid_levels` (over the whole grid)."""

    cells: int  # merged cells holding at least one drawn cell (level 0: drawn cells)
    faces: int  # polygons before triangulation
    triangles: int
    interior_triangles: int  # of which faces between regions and of cavities (not drawn from outside the grid)
    vertices: int  # distinct vertices (one per cell value: flat colours)
    volume: float  # m^3 enclosed by the level's surface, every region summed
    volume_change: float  # (volume - level 0's volume) / level 0's volume


class ObjectColoring(TypedDict):
    """One object's colouring by data (:meth:`geocull.Scene.colorings`, :attr:`RenderResult.colorings`)."""

    object: int  # the object's id
    name: str | None
    kind: str  # "heightfield", "mesh", "well", "slice", ...
    color_by: Literal["z", "values"]
    cmap: str | None  # the colour map's name ("custom" for a table without one)
    table: npt.NDArray[np.float64] | None  # (n, 3) RGB rows in [0, 1] as given (a table or a Colormap); else None
    clim: tuple[float, float]  # the scalars at the colour map's ends (z in metres for "z")
    label: str  # the colour bar's label: the attribute's name, "depth (m)" or "elevation (m)" for z


class IsoStats(TypedDict):
    """``IsoResult.stats`` of an isosurface frame (:func:`geocull.iso.render_isosurface`). Every key is
    always present; depths count octree levels from the root (0); times are milliseconds."""

    surface_triangles: int  # triangles of the drawn surface
    surface_vertices: int  # vertices of the drawn surface
    nodes_tested: int  # octree nodes tested against the occlusion map (the straddling nodes at cull_depth)
    nodes_tested_cull_depth: int  # = nodes_tested (one level since the map and the test are one walk)
    nodes_visible: int  # visible nodes at cull_depth (every straddling node for culling="none")
    nodes_straddling: int  # nodes at cull_depth that may hold surface (= len(nodes))
    occluder_boxes_below: int  # nodes at occluder_depth wholly below the isovalue (NaN-free), in the map's grid
    occluder_boxes_above: int  # nodes at occluder_depth wholly above the isovalue (NaN-free), in the map's grid
    occluder_nodes_nan: int  # nodes at occluder_depth with a NaN sample or touching one: they stop the map's walk
    occluder_depth: int  # octree depth of the occluder nodes used
    cull_depth: int  # octree depth of the nodes tested and extracted
    max_depth: int  # octree depth of the single-cell leaves
    patches_cached: int  # surface patches found in the renderer's cache
    patches_extracted: int  # surface patches extracted this frame
    occluder_ms: float  # ms, CPU: node classes (first frame of an isovalue/depth) + recording the map pass
    cull_ms: float  # ms, the occlusion map on the GPU + coarse-to-fine node tests, read-backs included
    extract_ms: float  # ms, marching cubes (cache look-ups included)
    draw_ms: float  # ms, upload of what is not on the GPU yet and the lit draw (GPU finished)
    surface_ms: float  # ms, extract_ms + draw_ms
    total_ms: float  # ms, wall time from the call to the GPU finishing the image, read-back and setup excluded
    setup_ms: float  # ms, one-time work before the clock (pipelines, case table, targets at a new size); else 0
    submissions: int  # queue submissions inside the frame
    readbacks: int  # GPU-to-host read-backs inside the frame (node-test counts; the image read-back excluded)
    readback_ms: float  # ms, wall time to copy image and depth back
    cache_bytes: int  # bytes the renderer's isosurface caches hold after the frame (<= its iso_cache_budget)
    gpu_cache_bytes: int  # bytes of the cached patches kept on the GPU between frames (<= about 2 x their own)
    contour_bytes: int  # bytes of the implicit walk's contour bricks, where it runs (surface bricks' samples; or 0)
    walk: Literal["gpu", "cpu", "none"]  # where the implicit walk ran ("none": culling="none", no walk)
    walk_rays: int  # host walk: pixel rays that entered the volume's box; 0 when walk != "cpu" (not counted)
    walk_steps: int  # host walk: their steps (a cell entered or a jump across empty bricks); 0 when walk != "cpu"
    bytes_read: int  # bytes this frame read from a lazy volume's source (brick-cache misses); 0 for one in memory
    brick_cache_bytes: int  # bytes a lazy volume's brick cache holds after the frame (<= its cache_bytes); else 0
    triangles_drawn: int  # = surface_triangles (name shared with RenderStats)
    tiles_drawn: int  # = nodes_visible (name shared with RenderStats)
    tiles_total: int  # = nodes_straddling (name shared with RenderStats)


def encode_png(image: np.ndarray) -> bytes:
    """PNG file bytes of an (H, W, 4) uint8 RGBA image, row 0 at the top (no dependency beyond zlib)."""
    h, w = image.shape[:2]
    raw = b"".join(b"\x00" + image[r].tobytes() for r in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


# The stats dict type of a frame: RenderStats for scene frames, IsoStats for isosurface frames.
StatsT = TypeVar("StatsT", RenderStats, IsoStats)


class RenderResult(Generic[StatsT]):
    """One rendered frame (:meth:`geocull.Renderer.render` returns ``RenderResult[RenderStats]``).

    image: (H, W, 4) uint8 RGBA, row 0 at the top, alpha 255; where nothing was drawn (depth +inf)
    the renderer's :attr:`~geocull.Renderer.background` (black with ``background="black"``, the
    core's own image).  depth: (H, W) float32 distance along the view axis in (exaggerated) world
    units, +inf where empty.  tile_pixels: (n_tiles,) uint32 visible
    pixels per tile, in :meth:`geocull.Scene.tile_table` order (three_pass: the pass-2 counts of
    its prepass, scaled to full-image pixels: of the built coarse proxies with conservative=False,
    of each tile's cheapest proxy with conservative=True, so an estimate there; none/oracle/temporal:
    in the final image).  tile_drawn: (n_tiles,) bool.
    stats: :class:`RenderStats` (triangles, tiles and per-pass milliseconds).  near, far: the clip
    distances used (exaggerated world units).  culling: the mode rendered.  horizon: for
    culling="horizon", (W,) float32 per image column, the pixel rows from the bottom known hidden
    (-inf where none); else None.  box_pixels: for three_pass with conservative=True or
    predict_errors=True and for temporal, (n_tiles,) uint32 pixels where each tile's box shows in front of the
    first phase's image (0 for tiles drawn in that phase); else None.  proxy_error_px: for
    three_pass, (n_tiles,) float32 each tile's proxy error (``tile_table()["proxy_error"]``,
    exaggerated) projected to pixels at the tile's nearest point; else None.  tile_level,
    tile_error_px: for lod="screen_error", (n_tiles,) the level chosen for each tile (0 = fine;
    ``tile_table()["level_error"]``) and its error projected to pixels; else None.
    camera: the :class:`geocull.Camera` rendered (None for results built by hand).  colorings: the
    colourings by data of the objects in the frame (:class:`ObjectColoring`, as
    :meth:`geocull.Scene.colorings` gave them when the frame was rendered: objects with pixels in
    the image, or with a tile drawn where ``tile_pixels`` is an estimate (three_pass), and
    translucent ones drawn); :meth:`figure` draws their colour bars.
    """

    def __init__(
        self, d: "RenderOutput | IsoOutput", culling: str, camera: "Camera | None" = None,
        colorings: "list[ObjectColoring] | None" = None,
    ) -> None:
        self.camera = camera
        self.colorings: list[ObjectColoring] = list(colorings or [])
        self.image: npt.NDArray[np.uint8] = d["image"]
        self.depth: npt.NDArray[np.float32] = d["depth"]
        self.tile_pixels: npt.NDArray[np.uint32] = d["tile_pixels"]
        self.tile_drawn: npt.NDArray[np.bool_] = d["tile_drawn"]
        self.stats: StatsT = cast(StatsT, d["stats"])
        self.near: float = d["near"]
        self.far: float = d["far"]
        self.culling = culling
        # Only scene frames rendered with culling="horizon" carry "horizon" (IsoOutput never does).
        self.horizon = cast("npt.NDArray[np.float32] | None", d.get("horizon"))
        # three_pass with conservative=True or predict_errors=True: per-tile box-test counts.
        self.box_pixels = cast("npt.NDArray[np.uint32] | None", d.get("box_pixels"))
        # three_pass: each tile's proxy error (tile_table()["proxy_error"]) in pixels at its nearest point.
        self.proxy_error_px = cast("npt.NDArray[np.float32] | None", d.get("proxy_error_px"))
        # lod="screen_error": the level each tile was given and that level's error in pixels.
        self.tile_level = cast("npt.NDArray[np.uint32] | None", d.get("tile_level"))
        self.tile_error_px = cast("npt.NDArray[np.float32] | None", d.get("tile_error_px"))

    @property
    def tile_at_risk(self) -> npt.NDArray[np.bool_] | None:
        """(n_tiles,) bool for three_pass with predict_errors=True: tiles culled although their box
        shows in front of the image (every wrongly culled tile is among them); else None."""
        if self.box_pixels is None or self.stats.get("tiles_at_risk") is None:
            return None
        return (~self.tile_drawn) & (self.box_pixels > 0)

    @property
    def coverage(self) -> np.ndarray:
        """(H, W) bool: pixels where something was drawn."""
        return np.isfinite(self.depth)

    def png(self) -> bytes:
        """The image as PNG file bytes (RGBA, W x H pixels)."""
        return encode_png(self.image)

    def save_png(self, path: str) -> None:
        """Write the image to ``path`` as a PNG file."""
        with open(path, "wb") as f:
            f.write(self.png())

    def _repr_png_(self) -> bytes:
        return self.png()

    def figure(
        self, colorbar: bool = True, scale_bar: bool = True, north_arrow: bool = True, title: str | None = None,
    ) -> "Figure":
        """The image as a matplotlib ``Figure`` (matplotlib is imported here, not before; the figure
        is made without pyplot, so it is not shown twice in a notebook: make it a cell's last
        expression, or call ``fig.savefig(path)``).

        colorbar: one colour bar per distinct (colour map, clim, label) among :attr:`colorings` (the
        objects coloured by data in the frame), labelled with the attribute's name (``label=`` of
        the ``add_*`` call, or the values' own name) or, for colour by z, "depth (m)" with ticks in
        depth = -z (shallow at the top) where the range lies at or below z = 0, else "elevation
        (m)". Objects in flat colours have none.
        scale_bar: a bar of a round length (1, 2 or 5 x 10^k metres, about a fifth of the image's
        width) along the image's x axis, where one length per pixel holds for horizontal distances
        along it: an orthographic view whose image x axis is horizontal (any elevation; vertical
        exaggeration does not touch horizontal lengths), or a perspective view looking straight
        down (within 1 degree) at surfaces whose distances lie within 5 % of their median (the bar
        is true at that distance). Left out for other views (an oblique perspective view has no one
        scale), and for results without a :attr:`camera`.
        north_arrow: an arrow towards +y of the world (grid north of a projected CRS) where the
        projection draws north as one direction across the image: orthographic views, and
        perspective views whose axis is perpendicular to north (straight down, or horizontal
        towards east or west), unless north points nearly along the view axis (its image is then
        shorter than a quarter of its length). Left out otherwise.
        title: the axes' title (default none).

        The artists are tagged for scripts and tests (``Artist.get_gid()``): "image", "scale_bar"
        (its ``Rectangle``, in image pixels) and "scale_bar_label", "north_arrow" and
        "north_arrow_label"; each colour bar's axes is labelled "colorbar" (``Axes.get_label()``).
        """
        from matplotlib import colormaps, patheffects
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import ListedColormap, Normalize
        from matplotlib.figure import Figure
        from matplotlib.patches import Rectangle
        from matplotlib.ticker import FuncFormatter
        from matplotlib.transforms import offset_copy

        h, w = self.image.shape[:2]
        bars = _colour_bars(self.colorings) if colorbar else []
        img_h = max(h / 100.0, 3.0)
        img_w = img_h * w / h
        fig = Figure(figsize=(img_w + 1.3 * len(bars) + 0.3, img_h + (0.5 if title else 0.2)), dpi=100,
                     layout="constrained")
        ax = fig.add_subplot()
        ax.imshow(self.image[..., :3], interpolation="nearest", gid="image")
        ax.set_axis_off()
        if title:
            ax.set_title(title)
        for bar in bars:
            table = bar["table"]
            if table is not None:
                cmap: Any = ListedColormap(np.asarray(table, np.float64), name=bar["cmap"] or "custom")
            elif bar["cmap"] is not None and bar["cmap"] in colormaps:
                cmap = colormaps[bar["cmap"]]
            else:  # a name only the core knows: no table to draw it with
                continue
            lo, hi = bar["clim"]
            cb = fig.colorbar(ScalarMappable(Normalize(lo, hi), cmap), ax=ax, fraction=0.06, pad=0.02, aspect=25)
            cb.ax.set_label("colorbar")
            cb.set_label(bar["label"])
            if bar["color_by"] == "z" and bar["label"] == "depth (m)":
                cb.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{-v:g}"))
        halo = [patheffects.withStroke(linewidth=3, foreground="white")]  # readable on any background
        cam = self.camera
        if cam is not None and scale_bar:
            mpp = _metres_per_pixel(cam, self.depth)
            if mpp is not None:
                length = _round_length(0.2 * w * mpp)
                px = length / mpp
                x0, y0 = 0.05 * w, 0.93 * h
                bar_h = max(2.0, 0.012 * h)
                ax.add_patch(Rectangle((x0, y0 - bar_h), px, bar_h, facecolor="black", edgecolor="white",
                                       linewidth=0.8, gid="scale_bar"))
                text = f"{length:g} m" if length < 1000 else f"{length / 1000:g} km"
                ax.annotate(text, (x0 + px / 2, y0 - bar_h), xytext=(0, 3), textcoords="offset points", ha="center",
                            va="bottom", fontsize=9, gid="scale_bar_label", path_effects=halo)
        if cam is not None and north_arrow:
            d = _north_on_image(cam)
            if d is not None:
                dx, dy = d
                base = (0.92, 0.84)
                half = 16.0  # points
                tip = offset_copy(ax.transAxes, fig=fig, x=dx * half, y=dy * half, units="points")
                tail = offset_copy(ax.transAxes, fig=fig, x=-dx * half, y=-dy * half, units="points")
                ax.annotate("", xy=base, xycoords=tip, xytext=base, textcoords=tail, gid="north_arrow",
                            arrowprops=dict(arrowstyle="-|>", color="black", lw=1.8, mutation_scale=14,
                                            shrinkA=0, shrinkB=0, path_effects=halo))
                lab = offset_copy(ax.transAxes, fig=fig, x=dx * (half + 9), y=dy * (half + 9), units="points")
                ax.text(*base, "N", transform=lab, ha="center", va="center", fontsize=10, fontweight="bold",
                        gid="north_arrow_label", path_effects=halo)
        return fig

    def __repr__(self) -> str:
        s = self.stats
        return (f"<geocull.RenderResult {self.image.shape[1]}x{self.image.shape[0]} culling={self.culling} "
                f"triangles_drawn={s['triangles_drawn']} tiles_drawn={s['tiles_drawn']}/{s['tiles_total']} "
                f"total_ms={s['total_ms']:.1f}>")


def _colour_bars(colorings: "list[ObjectColoring]") -> list[ObjectColoring]:
    """One entry per distinct (colour by, colour map, table, clim, label), in the order first seen."""
    seen: dict[tuple[Any, ...], ObjectColoring] = {}
    for c in colorings:
        table = c["table"]
        key = (c["color_by"], c["cmap"], None if table is None else np.asarray(table).tobytes(),
               tuple(float(x) for x in c["clim"]), c["label"])
        seen.setdefault(key, c)
    return list(seen.values())


def _round_length(target: float) -> float:
    """The largest of 1, 2, 5 x 10^k not above ``target`` (> 0)."""
    k = math.floor(math.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0**k <= target:
            return m * 10.0**k
    return 10.0**k


def _view_axes(cam: "Camera") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(right, up, forward) unit vectors of the camera in render space (z exaggerated)."""
    v = cam.view_matrix()
    return v[0, :3], v[1, :3], -v[2, :3]


def _metres_per_pixel(cam: "Camera", depth: np.ndarray) -> float | None:
    """Metres of horizontal distance per pixel along the image's x axis where one such scale holds
    (see :meth:`RenderResult.figure`), else None."""
    h = depth.shape[0]
    right, _up, fwd = _view_axes(cam)
    zs = np.array([1.0, 1.0, cam.z_scale])
    tan = math.tan(math.radians(cam.fov_y) / 2)
    if cam.projection == "orthographic":
        if abs(right[2]) > 1e-6:  # the image's x axis is not horizontal: no one horizontal scale
            return None
        height = cam.ortho_height
        if height is None:  # what fov_y sees at the target
            height = 2.0 * float(np.linalg.norm((np.asarray(cam.target) - np.asarray(cam.eye)) * zs)) * tan
        return height / h
    if fwd[2] > -math.cos(math.radians(1.0)):  # a perspective view that does not look straight down
        return None
    d = depth[np.isfinite(depth)]
    if d.size == 0:
        return None
    med = float(np.median(d))
    if not med > 0 or float(np.abs(d - med).max()) > 0.05 * med:
        return None
    return 2.0 * med * tan / h


def _north_on_image(cam: "Camera") -> tuple[float, float] | None:
    """The image direction (x right, y up; unit length) of world +y where the projection draws it
    as one direction (see :meth:`RenderResult.figure`), else None."""
    right, up, fwd = _view_axes(cam)
    north = np.array([0.0, 1.0, 0.0])
    if cam.projection != "orthographic" and abs(float(fwd @ north)) > 0.01:
        return None
    d = np.array([float(right @ north), float(up @ north)])
    n = float(np.linalg.norm(d))
    if n < 0.25:
        return None
    return (float(d[0] / n), float(d[1] / n))


class IsoResult(RenderResult[IsoStats]):
    """One rendered isosurface frame (:func:`geocull.iso.render_isosurface`); a :class:`RenderResult`
    whose per-tile arrays are per octree *node*.

    nodes: (n, 4) uint32 [depth, ix, iy, iz], the nodes at ``cull_depth`` that may hold surface, in
    octree order (ix along x, iy along y, iz along z, in units of the node's size).  tile_pixels: (n,)
    uint32 cells of the node that may hold surface and that some pixel's ray entered before the
    occlusion map (0 when hidden, and for culling="none").  tile_drawn: (n,) bool, extracted and drawn.  stats:
    :class:`IsoStats`.  occlusion_map: (H, W) float32 distance along the view axis (exaggerated world
    units), +inf where nothing is proven, when ``return_map=True``; else None.  horizon: always None.
    """

    def __init__(self, d: "IsoOutput", culling: str, camera: "Camera | None" = None) -> None:
        super().__init__(d, culling, camera)
        self.nodes: npt.NDArray[np.uint32] = d["nodes"]
        self.occlusion_map: npt.NDArray[np.float32] | None = d.get("occlusion_map")
