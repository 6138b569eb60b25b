"""The off-screen renderer: scenes (:meth:`Renderer.render`) and isosurfaces of volumes
(:meth:`Renderer.render_isosurface`), and the names of the culling modes each accepts."""

from __future__ import annotations

import ctypes
import os
import warnings
import weakref
from typing import Literal, TypeAlias, get_args

import numpy as np
from numpy.typing import ArrayLike

from . import _convert as cv
from . import _geocull
from ._errors import DeviceError, GeocullWarning, InputError
from .camera import Camera
from .results import IsoResult, RenderResult, RenderStats
from .scene import Scene
from .volume import Volume

__all__ = ["Renderer", "CULLING_MODES", "CullingMode", "ISO_CULLING_MODES", "IsoCullingMode", "IsoWalk", "LodMode",
           "GridLodMode", "Background", "BACKGROUNDS"]

#: Culling modes of :meth:`Renderer.render`, for type checkers. The runtime list is
#: :data:`CULLING_MODES`, which comes from the core.
CullingMode = Literal["none", "three_pass", "oracle", "horizon", "frustum", "temporal", "implicit"]

#: Culling modes :meth:`Renderer.render` accepts, in the core's order (its registry).
CULLING_MODES: tuple[str, ...] = tuple(_geocull.culling_modes())

#: Culling modes of :meth:`Renderer.render_isosurface` ("implicit": implicit occluders; "none": the reference;
#: "oracle": the visible cells of the reference, the lower bound for benchmarks).
IsoCullingMode = Literal["implicit", "none", "oracle"]

#: The same names at runtime, in that order.
ISO_CULLING_MODES: tuple[str, ...] = get_args(IsoCullingMode)

#: Where :meth:`Renderer.render_isosurface`'s implicit walk runs ("auto": on the host's cores when the
#: adapter is a CPU itself, such as lavapipe or llvmpipe, else on the GPU).
IsoWalk = Literal["auto", "gpu", "cpu"]

#: Level-of-detail choice of :meth:`Renderer.render` (``lod=``).
LodMode = Literal["full", "screen_error"]
#: Level choices of reservoir grids' blocks (:meth:`Renderer.render`'s ``grid_lod``).
GridLodMode = Literal["full", "distance", "screen_error"]


RGB: TypeAlias = tuple[float, float, float]

#: The named backgrounds of :class:`Renderer` (``background=``): (top, bottom) RGB in [0, 1], blended
#: row by row. "gradient" (the default) is a neutral light grey, lighter at the top.
BACKGROUNDS: dict[str, tuple[RGB, RGB]] = {
    "gradient": ((0.94, 0.94, 0.95), (0.72, 0.72, 0.73)),
    "white": ((1.0, 1.0, 1.0), (1.0, 1.0, 1.0)),
    "black": ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
}

#: What ``Renderer(background=...)`` takes: a name of :data:`BACKGROUNDS`, one (r, g, b) colour, or
#: a (top, bottom) pair of them for a vertical gradient; RGB in [0, 1].
Background: TypeAlias = Literal["gradient", "white", "black"] | RGB | tuple[RGB, RGB]


def _background(value: object) -> tuple[RGB, RGB]:
    """(top, bottom) RGB of a ``background`` argument; None: ``$GEOCULL_BACKGROUND`` (a name or
    "r,g,b"), else "gradient". InputError naming the argument (or the variable)."""
    arg = "background"
    if value is None:
        env = os.environ.get("GEOCULL_BACKGROUND", "").strip()
        if not env:
            return BACKGROUNDS["gradient"]
        arg = "GEOCULL_BACKGROUND"
        value = env if env in BACKGROUNDS or "," not in env else env.split(",")
        if isinstance(value, list):
            try:
                value = [float(x) for x in value]
            except ValueError:
                raise InputError(f"{arg}: {env!r} is not a name ({', '.join(BACKGROUNDS)}) or r,g,b") from None
    if isinstance(value, str):
        if value not in BACKGROUNDS:
            raise InputError(f"{arg}: {value!r} is not one of {', '.join(BACKGROUNDS)} or an (r, g, b) colour")
        return BACKGROUNDS[value]
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{arg}: {value!r} is not a name, an (r, g, b) colour or a (top, bottom) pair") from None
    if a.shape == (3,):
        a = np.stack([a, a])
    if a.shape != (2, 3):
        raise InputError(f"{arg}: shape {a.shape} is not (3,) (r, g, b) or (2, 3) (top, bottom)")
    if not (np.isfinite(a).all() and (a >= 0).all() and (a <= 1).all()):
        raise InputError(f"{arg}: colours must lie in [0, 1], got {a.tolist()}")
    return ((float(a[0, 0]), float(a[0, 1]), float(a[0, 2])), (float(a[1, 0]), float(a[1, 1]), float(a[1, 2])))


#: The least near plane of a frame (the core's ``camera::MIN_NEAR``, also its least orthographic
#: view height), render units: scenes whose largest side is under it get a GeocullWarning
#: (:func:`_warn_if_tiny`).
MIN_NEAR = 1e-6


def _warn_if_tiny(
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]] | None, camera: Camera
) -> bool:
    """GeocullWarning (and True) when a scene's box ``bounds`` (world metres) is under
    :data:`MIN_NEAR` along every axis in render units (z exaggerated by the camera's z_scale):
    the eye can come no closer than the near plane, nor an orthographic view be smaller, so such
    a scene renders a few pixels wide, clipped or empty (a scene in micrometres given as metres,
    say)."""
    if bounds is None:
        return False
    lo, hi = (np.asarray(b, dtype=np.float64) for b in bounds)
    ext = (hi - lo) * np.array([1.0, 1.0, camera.z_scale])
    if not np.isfinite(ext).all() or float(ext.max()) >= MIN_NEAR:
        return False
    warnings.warn(
        f"the scene spans only {float(ext.max()):g} (its largest side, render units): a frame's near plane is never "
        f"nearer than {MIN_NEAR:g} to the eye, nor an orthographic view under {MIN_NEAR:g} high, so scenes smaller "
        "than that render small, clipped or empty. Scale the coordinates up (metres are expected).",
        GeocullWarning,
        stacklevel=3,
    )
    return True


def _warn_if_nearer_than_near(lo: np.ndarray, hi: np.ndarray, camera: Camera, near: float) -> None:
    """GeocullWarning when boxes (k, 3) ``lo``..``hi`` (world, metres) lie in front of the eye but
    wholly nearer than the frame's ``near`` plane (render units): nothing can be drawn.

    Why here and from the result: the frame already says whether anything was drawn (no tile has a
    pixel), so the wrapper only looks at the boxes in that rare case and the frame pipeline in the
    core stays as it is; the boxes are the scene's tile table, the same boxes the core frames near
    and far from. A box counts as "in the view direction" when its far end is in front of the eye.
    """
    if lo.size == 0:
        return
    zs = np.array([1.0, 1.0, camera.z_scale])
    eye, tgt = np.asarray(camera.eye) * zs, np.asarray(camera.target) * zs
    fwd = (tgt - eye) / np.linalg.norm(tgt - eye)
    ok = np.isfinite(lo).all(axis=1) & np.isfinite(hi).all(axis=1)
    lo, hi = lo[ok] * zs, hi[ok] * zs
    if lo.size == 0:
        return
    # The farthest corner of each box along the view axis; "in front" beyond rounding (a scene
    # level with the eye plane is behind it for this purpose, not nearer than the near plane).
    far_end = np.where(fwd >= 0, hi, lo) @ fwd - eye @ fwd
    tol = 8 * np.finfo(np.float64).eps * max(float(np.abs(eye).max()), float(np.abs(lo).max()), float(np.abs(hi).max()))
    if far_end.max() > tol and far_end.max() < near:
        warnings.warn(
            f"nothing drawn: the scene lies wholly nearer than the near plane (near = {near:g} along the view axis, "
            f"the scene's far end at {far_end.max():g}; the automatic near plane never goes below 1e-6). "
            + ("Move the eye back (the near plane is at its least)." if near <= MIN_NEAR * (1 + 1e-9) else
               "Move the eye back or pass a smaller near."),
            GeocullWarning,
            stacklevel=3,
        )


#: The renderers alive in this process (see :func:`_keep_in_forked_child`).
_LIVE: weakref.WeakSet[Renderer] = weakref.WeakSet()


def _keep_in_forked_child() -> None:
    """``os.register_at_fork(after_in_child=...)``: in a child forked from this process the
    renderers' core objects are kept forever (a reference no one releases). Their device's driver
    threads did not survive the fork, and freeing a device waits for them: a child that merely
    exited (its renderers freed with its globals) used to hang forever."""
    for r in list(_LIVE):
        dev = r.__dict__.get("_dev")
        if dev is not None:
            ctypes.pythonapi.Py_IncRef(ctypes.py_object(dev))


os.register_at_fork(after_in_child=_keep_in_forked_child)


class Renderer:
    """Off-screen wgpu renderer of width x height pixel images. backend: "auto" (a GPU if present,
    else Mesa's lavapipe on the CPU), "vulkan", "gl" (e.g. EGL + llvmpipe where there is no Vulkan),
    "metal", "dx12". Backends agree on coverage (which pixels show something), on each tile's
    visible pixels and on what every culling mode draws; their depths agree to a few 1e-5
    (relative) and their colours to a few 1/255 in a few pixels (each backend rounds interpolated
    colour-map coordinates and normals its own way: Vulkan and GL on Mesa measured at most 3/255
    in 17 of 76,800 pixels, depth within 1.6e-5; ``tests/test_backends.py``). "auto" honours the environment variable
    ``GEOCULL_BACKEND`` (one of those names; unset, empty or "auto": geocull chooses), which picks
    the backend for a whole program or test run, e.g. ``GEOCULL_BACKEND=gl pytest``; an explicit
    backend wins over it. Raises DeviceError if no adapter is found, InputError for an unknown
    name (in ``backend`` or in ``GEOCULL_BACKEND``).

    Renderers of one backend share the process's device and its compiled pipelines while any of
    them lives (on lavapipe ~250 MiB once it has drawn a large frame): a second renderer costs only
    its own images and caches. Each renderer keeps its own geometry, history and caches; they may
    render from different threads at once. Worker processes: start them with multiprocessing's
    "spawn" or "forkserver" method (scenes, cameras and volumes pickle); a process forked after
    its parent opened a renderer can build scenes but gets a DeviceError for a renderer (the
    driver's threads do not survive fork()); a renderer inherited by a forked process (e.g. a
    module-level one and a ``multiprocessing.Pool`` with "fork", Linux's default) raises that
    DeviceError on its first use there, instead of waiting forever. ``pass_triangles``: see :attr:`pass_triangles`
    (driver memory against frame time on CPU drivers; default unbounded). ``background``: see
    :attr:`background` (default a light grey gradient)."""

    def __init__(
        self, width: int = 1280, height: int = 1024, backend: str = "auto", pass_triangles: int | None = None,
        background: Background | None = None,
    ) -> None:
        if not isinstance(backend, str):
            raise InputError(f"backend: {backend!r} is not a string")
        self._bg = _background(background)  # checked before a device opens
        self._dev = _geocull.Renderer(cv.integer(width, "width"), cv.integer(height, "height"), backend)
        self._pid = os.getpid()  # the process whose device it holds
        _LIVE.add(self)
        self._set_rows()
        if pass_triangles is not None:
            self.pass_triangles = pass_triangles

    @property
    def _r(self) -> _geocull.Renderer:
        """The core's renderer, in the process that opened it; DeviceError in a process forked from
        it (its device's driver threads are not there: any call would wait forever)."""
        if self._pid != os.getpid():
            raise DeviceError(
                f"this renderer was opened by process {self._pid}, and this process ({os.getpid()}) was forked from "
                "it: the driver's threads do not survive fork(), so its device cannot be used here; create "
                "renderers in worker processes started with multiprocessing's \"spawn\" or \"forkserver\" method "
                "(scenes, cameras and volumes pickle)"
            )
        return self._dev

    @property
    def background(self) -> tuple[RGB, RGB]:
        """The background of the images, (top, bottom) RGB in [0, 1], blended linearly from the
        first image row to the last. Set it (also ``Renderer(background=...)``) to a name of
        :data:`BACKGROUNDS` ("gradient": neutral light grey, lighter at the top, the default;
        "white"; "black", the core's own), to one (r, g, b) colour, or to a (top, bottom) pair; None
        is the default, which the environment variable ``GEOCULL_BACKGROUND`` (a name or "r,g,b")
        can change for a whole program or test run. InputError naming ``background`` otherwise.

        The core draws over black; the background is put into the image by the core while it
        reads the image back (``stats["readback_ms"]`` counts it, ~1 ms at 1280 x 1024), at the
        pixels where nothing was drawn: ``depth`` is +inf (:attr:`RenderResult.coverage` is
        False) and the pixel is still black. Translucent lenses and slices drawn over nothing were
        blended with that black, and keep it (an image-wide coverage alpha from the core would
        let them blend with the background). Alpha stays 255 everywhere."""
        return self._bg

    @background.setter
    def background(self, value: Background | None) -> None:
        self._bg = _background(value)
        self._set_rows()

    def _set_rows(self) -> None:
        top, bottom = (np.asarray(c) for c in self._bg)
        if not (top.any() or bottom.any()):
            self._r.set_background(None)  # black: the core's clear colour already
            return
        t = np.linspace(0.0, 1.0, self.height)[:, None]
        rows = np.round(255.0 * ((1.0 - t) * top + t * bottom)).astype(np.uint8)
        self._r.set_background(rows.tobytes())

    @property
    def width(self) -> int:
        """Image width, pixels."""
        return self._r.width

    @property
    def height(self) -> int:
        """Image height, pixels."""
        return self._r.height

    @property
    def adapter_info(self) -> str:
        """The adapter in use, in words."""
        return self._r.adapter_info

    @property
    def max_texture_size(self) -> int:
        """The adapter's largest 2-D texture side, pixels."""
        return self._r.max_texture_size

    @property
    def gpu_bytes(self) -> int:
        """Bytes of scene geometry held on the GPU."""
        return self._r.gpu_bytes

    @property
    def iso_cache_budget(self) -> int:
        """Memory budget of the isosurface caches, bytes (default 256 MiB; settable, >= 0): beyond
        it the least recently used patches are dropped (see :func:`geocull.iso.set_cache_budget`)."""
        return _geocull.isosurface_cache_budget(self._r)

    @iso_cache_budget.setter
    def iso_cache_budget(self, value: int) -> None:
        _geocull.set_isosurface_cache_budget(self._r, cv.integer(value, "bytes"))

    @property
    def cache_budget(self) -> int:
        """Bytes each culling strategy may keep cached between frames (default 256 MiB; horizon:
        its quadtrees, one per height field and z_scale, least recently used dropped first; the
        frame's ``stats["cache_bytes"]`` is what it holds). Setting it shrinks caches at once; 0
        caches nothing."""
        return self._r.cache_budget

    @cache_budget.setter
    def cache_budget(self, nbytes: int) -> None:
        self._r.cache_budget = cv.integer(nbytes, "cache_budget")

    @property
    def pass_triangles(self) -> int | None:
        """At most this many triangles per render pass of a frame's lit draws (default None: one
        pass each; settable, >= 1). The image is the same; what changes is memory. A CPU driver
        (lavapipe, llvmpipe) keeps the triangles it bins for a pass until the pass ends (in 36 MB
        blocks, as many as its rasteriser threads lag behind), so a frame of millions of
        triangles holds hundreds of MiB: a bound caps that (the 3.9 M-triangle benchmark frame
        at 1280x1024: peak 420 -> 280 MiB at 300_000) for 20-40 % more frame time there. The
        bound counts the triangles of the chosen levels of the tiles a pass may draw, culled or
        not. On a GPU it saves nothing. It applies to :meth:`render`; :meth:`render_isosurface`
        draws its surface in one pass (there the driver's run-ahead is ~40 MiB at 512x512)."""
        return self._r.pass_triangles

    @pass_triangles.setter
    def pass_triangles(self, max_triangles: int | None) -> None:
        self._r.pass_triangles = None if max_triangles is None else cv.integer(max_triangles, "pass_triangles")

    def render(
        self,
        scene: Scene,
        camera: Camera,
        culling: CullingMode = "none",
        pixel_threshold: float = 10,
        prepass_scale: float | None = None,
        conservative: bool = True,
        predict_errors: bool = False,
        lod: LodMode = "full",
        max_pixel_error: float = 0.5,
        grid_lod: GridLodMode = "full",
        alpha: float = 10.0,
        lam: float = 2.5,
    ) -> RenderResult[RenderStats]:
        """Render ``scene`` seen by ``camera`` into a :class:`RenderResult` (see there for the arrays:
        image (H, W, 4), depth (H, W), per-tile counts).

        culling: one of :data:`CULLING_MODES`: "none" (every fine tile, the reference), "three_pass"
        (GPU depth prepass of coarse proxies, exact visible-pixel count per tile, fine draw of tiles
        with more than ``pixel_threshold`` pixels), "oracle" (exactly the tiles visible in the
        unculled image; a benchmark lower bound), "horizon" (CPU horizon culling of height fields),
        "frustum" (CPU view-frustum culling of the tiles' boxes), "temporal" (the tiles visible in
        this renderer's last frame of the same scene drawn first, then every other tile's box tested
        against that image at full resolution and drawn when it shows: about the oracle's cost for a
        coherent camera, exact like conservative three_pass; a scene's first frame starts from
        three_pass's prepass; stats ``tiles_reused``), "implicit" (conservative three_pass whose box
        test also sees the isosurfaces' implicit occluders: boxes of cells that no ray reaches
        without crossing the isosurface first, found when it was added; a salt body then culls what
        lies behind it; stats ``implicit_occluder_boxes``, ``implicit_objects``; scenes read from
        bytes have no occluders).
        pixel_threshold: >= 0, in full-image pixels: tiles with at most this many visible pixels
        are not drawn.  prepass_scale: (0, 1], prepass resolution as a fraction of the image's
        width and height; None (default): 0.5 with conservative=True (the image does not depend on
        it, the prepass only chooses which tiles are drawn first), 1 with conservative=False.
        Each tile's prepass draws its coarse proxy (``coarse_factor`` of the ``add_*`` call), or
        with conservative=True (and temporal) its coarsest level of detail where that is smaller.
        conservative (three_pass): True (default) never culls a tile with more than
        ``pixel_threshold`` visible pixels: after drawing the tiles the prepass found, every other
        tile's bounding box is tested against that image's depth at full resolution and drawn when
        it shows (stats ``tiles_drawn_first`` / ``tiles_drawn_second``). False is the paper's
        approximate method.
        predict_errors (three_pass with conservative=False): also run that box test without drawing,
        to report the tiles at risk of being wrongly culled (``stats["tiles_at_risk"]``,
        ``stats["predicted_max_missing_pixels"]``, :attr:`RenderResult.tile_at_risk`). Every tile the
        approximate mode misses is among them.
        lod: "full" (level 0, the fine triangles, everywhere: the reference) or "screen_error" (each
        drawn tile at the coarsest of its levels whose geometric error, ``tile_table()`` levels
        built with the scene, projects to at most ``max_pixel_error`` pixels at the tile's nearest
        point and whose shading error, ``tile_table()["level_shading_error"]``, changes the lit
        colour by at most half an 8-bit level: a mesh's coarser levels interpolate its normals over
        larger triangles, so a curved one keeps its finer levels, unless it is a structured grid
        (:func:`geocull.data.grid_faces`), which shades every level from its fine grid's normals as
        height fields do from their fine surface; neighbouring tiles at different
        levels meet without cracks: every level keeps its tile's border at full resolution).
        Works with every culling mode. Stats
        ``triangles_level0`` .. ``triangles_level5``, ``lod_max_error_px``, ``lod_max_error_m``.
        max_pixel_error: > 0, pixels (lod="screen_error" or grid_lod="screen_error").
        grid_lod: the level of reservoir grids' blocks (:meth:`Scene.add_grid`): "full" (level 0),
        "distance" (Jia et al.'s view-distance ranges: with L, W a block's mean cell size,
        S(h) = alpha 2^h max(L, W) and r(h) = lam 2^h sqrt(L^2 + W^2) / 2, leaves up to S(0) and
        merged level h from S(h) - r(h), the distance taken from the eye to the block's centre;
        gaps between the paper's ranges take the finer level) or "screen_error" (as lod).
        alpha: [8, 15]; lam: [2, 3] (grid_lod="distance"). Stats ``grid_cells_level0..5`` and
        ``grid_faces_level0..5`` count the merged cells and faces drawn per level.

        Warns (:class:`geocull.GeocullWarning`) when nothing is drawn because the whole scene lies
        nearer than the near plane, and when the scene is smaller than 1e-6 (:data:`MIN_NEAR`, render
        units) along every axis: no frame can show it well.

        Accuracy: "none", "oracle", "horizon" and "frustum" give the unculled image, and so does
        "three_pass" with conservative=True, "temporal" and "implicit", with pixel_threshold=0 (for any
        camera, proxies and history).
        With conservative=False "three_pass" is exact only with pixel_threshold=0, coarse_factor=1
        and prepass_scale=1; with coarser proxies it is approximate, as in the method's paper: a
        proxy that bulges above its fine tile can hide a tile that is visible, and a smaller
        prepass can miss tiles a few pixels wide. Measured: at most 0.03 % of pixels on the stacked
        Gullfaks-like scene, but up to 9 % for low, near-horizontal views over rough terrain at
        coarse_factor=25 (0.3 % at 4).

        Ctrl-C (SIGINT) during a frame raises KeyboardInterrupt within a fraction of a second (the
        core checks between the frame's stages and while it waits for the GPU); the renderer stays
        usable, and its next frame first lets the GPU finish the abandoned work.
        """
        cv.expect_instance(scene, Scene, "scene")
        cv.expect_instance(camera, Camera, "camera")
        if not isinstance(culling, str):
            raise InputError(f"culling: {culling!r} is not a string")
        d = self._r.render(scene._s, camera._c, culling, cv.number(pixel_threshold, "pixel_threshold"),
                           None if prepass_scale is None else cv.number(prepass_scale, "prepass_scale"),
                           bool(conservative), bool(predict_errors),
                           lod if isinstance(lod, str) else cv.fail_type(lod, "lod", "a string"),
                           cv.number(max_pixel_error, "max_pixel_error"),
                           grid_lod if isinstance(grid_lod, str) else cv.fail_type(grid_lod, "grid_lod", "a string"),
                           cv.number(alpha, "alpha"), cv.number(lam, "lam"))
        res: RenderResult[RenderStats] = RenderResult(d, culling, camera)
        # three_pass (and implicit) count their prepass, an estimate: there the objects drawn are those in the frame.
        by_pixels = culling not in ("three_pass", "implicit")
        res.colorings = scene.colorings(scene._frame_objects(res.tile_drawn, res.tile_pixels, by_pixels))
        tiny = _warn_if_tiny(scene.bounds, camera)
        if len(res.tile_pixels) and not res.tile_pixels.any() and not tiny:  # nothing drawn: near clipped all?
            t = scene.tile_table()
            shown = np.isin(t["object"], [i for i in scene.object_ids() if scene.object_info(i)["visible"]])
            _warn_if_nearer_than_near(t["bbox_min"][shown], t["bbox_max"][shown], camera, res.near)
        return res

    def render_isosurface(
        self,
        volume: Volume,
        isovalue: float,
        camera: Camera,
        culling: IsoCullingMode = "implicit",
        *,
        occluder_depth: int | None = None,
        cull_depth: int | None = None,
        color: ArrayLike = (0.85, 0.72, 0.45),
        cache: bool = True,
        return_map: bool = False,
        walk: IsoWalk = "auto",
    ) -> IsoResult:
        """Render the isosurface ``volume == isovalue`` seen by ``camera`` into an :class:`IsoResult`
        (image (H, W, 4), depth (H, W), per-node arrays; see there).

        isovalue: a finite number, in the volume's value units.
        culling: one of :data:`ISO_CULLING_MODES`: "implicit" (occlusion map of implicit occluders,
        extract only visible nodes), "none" (extract and draw every node that may hold surface:
        the reference) or "oracle" (for benchmarks: renders "none" first, untimed, and draws only
        the cells that hold a pixel's surface point in it, with those within 0.05 cells of it, and
        along the pixel's ray where the image would differ: about the least that a culling drawing
        whole cells, as "implicit" does, can draw; the same image).
        occluder_depth: octree depth of the occluder nodes (root = 0; default max_depth: single cells).
        cull_depth: octree depth of the nodes tested and extracted (default max_depth - 2).
        color: (r, g, b) in [0, 1].  cache: reuse patches extracted by earlier frames (per volume,
        isovalue and node); False extracts afresh (for timing).  return_map: also return the occlusion
        map as ``result.occlusion_map`` ((H, W) distance along the view axis, inf where nothing is
        proven).  walk: where the implicit walk (map and cells seen, one ray per pixel) runs: "gpu"
        (a compute pass), "cpu" (the host's cores, the same walk step for step) or "auto" (default:
        "cpu" when the adapter is a CPU itself, lavapipe or llvmpipe, whose compute passes run the
        walk's every branch on every SIMD lane; else "gpu"). Both give the same image (the host's
        walk also stops at the surface's contours on sparse surfaces, so it may draw fewer
        triangles); ``stats["walk"]`` says where it ran.

        The result's ``tile_pixels`` / ``tile_drawn`` are per *node*: one entry per node at
        ``cull_depth`` that may hold surface (``result.nodes``: (n, 4) [depth, ix, iy, iz]) — the
        cells of the node that may hold surface and that some pixel's ray entered before the occlusion
        map (0 when hidden, and for culling="none") and
        whether it was extracted and drawn. ``stats``: :class:`IsoStats`
        (surface_triangles, nodes_tested, nodes_visible, nodes_straddling,
        occluder_boxes_below/above, occluder_ms, cull_ms, extract_ms, draw_ms, surface_ms
        (= extract + draw), total_ms, patches_cached/extracted, cache_bytes, gpu_cache_bytes,
        walk_rays / walk_steps (the host's walk: rays entering the volume's box and their steps),
        bytes_read / brick_cache_bytes (a lazy volume: bytes the frame read from its source, bytes
        its brick cache holds), ...). A lazy volume's (``Volume(lazy=...)``) default occluder and
        cull depths are ``max_depth() - 3``, so a frame reads only the nodes it extracts.
        Patches are kept within :attr:`iso_cache_budget` bytes, and their vertices and triangles
        stay on the GPU between frames (``gpu_cache_bytes``, at most about twice theirs).

        Same as :func:`geocull.iso.render_isosurface` with this renderer as its first argument.
        """
        cv.expect_instance(volume, Volume, "volume")
        cv.expect_instance(camera, Camera, "camera")
        if not isinstance(culling, str):
            raise InputError(f"culling: {culling!r} is not a string")
        w = cv.number(isovalue, "isovalue")
        od = None if occluder_depth is None else cv.integer(occluder_depth, "occluder_depth")
        cd = None if cull_depth is None else cv.integer(cull_depth, "cull_depth")
        c = cv.vec3(color, "color")
        if not isinstance(walk, str):
            raise InputError(f"walk: {walk!r} is not a string")
        d = _geocull.render_isosurface(self._r, volume._v, w, camera._c, culling, od, cd, c,
                                       bool(cache), bool(return_map), walk)
        res = IsoResult(d, culling, camera)
        lo, hi = volume.bounds  # one box: cheap enough to test every frame
        if not _warn_if_tiny((lo, hi), camera):
            _warn_if_nearer_than_near(np.array([lo]), np.array([hi]), camera, res.near)
        return res

    def __repr__(self) -> str:
        if self._pid != os.getpid():
            return f"<geocull.Renderer of process {self._pid}, unusable in this forked process>"
        return f"<geocull.Renderer {self.width}x{self.height} on {self.adapter_info}>"
