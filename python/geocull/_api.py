"""The Python face of geocull's Rust core: argument coercion and checking, numpy in and out.

Every public call validates its arguments here (shape, dtype) and in Rust (values, ranges), and
raises :class:`geocull.InputError` naming the argument on bad input.
"""

from __future__ import annotations

import numbers
import struct
import zlib
from typing import Any, Iterable, Sequence

import numpy as np

from . import _geocull
from ._errors import InputError

_FLOAT_KINDS = "fiu"  # float, signed int, unsigned int


def _array(x: Any, name: str, ndim: int, last: int | None = None, kinds: str = _FLOAT_KINDS) -> np.ndarray:
    """numpy view of ``x`` with the expected rank (and last axis length), or InputError."""
    try:
        a = np.asarray(x)
    except Exception as e:  # ragged lists, objects that refuse conversion
        raise InputError(f"{name}: cannot be read as an array ({e})") from None
    if a.dtype.kind not in kinds:
        want = "integers" if kinds == "iu" else "real numbers (float or int)"
        raise InputError(f"{name}: dtype {a.dtype} is not supported; expected {want}")
    if a.ndim != ndim or (last is not None and a.shape[-1] != last):
        want = f"({', '.join(['n'] * (ndim - 1) + [str(last)])})" if last is not None else f"{ndim}-D"
        raise InputError(f"{name}: shape {a.shape} is not {want}")
    return a


def _floats(x: Any, name: str, ndim: int, last: int | None = None) -> np.ndarray:
    a = _array(x, name, ndim, last)
    return np.ascontiguousarray(a, dtype=np.float64)


def _vec(x: Any, name: str, n: int) -> tuple[float, ...]:
    a = _array(x, name, 1, n)
    return tuple(float(v) for v in a)


def _number(x: Any, name: str) -> float:
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise InputError(f"{name}: {x!r} is not a real number")
    return float(x)


def _int(x: Any, name: str, lo: int = 0, hi: int = 2**31 - 1) -> int:
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise InputError(f"{name}: {x!r} is not an integer")
    v = int(x)
    if not lo <= v <= hi:
        raise InputError(f"{name}: {v} is outside {lo}..{hi}")
    return v


def _expect(x: Any, cls: type, name: str) -> Any:
    """``x`` if it is a ``cls``, else InputError naming the argument."""
    if not isinstance(x, cls):
        raise InputError(f"{name}: expected a geocull.{cls.__name__}, got {type(x).__name__}")
    return x


def _color(c: Any) -> tuple[float, float, float] | None:
    return None if c is None else _vec(c, "color", 3)  # range checked in Rust


def _name(n: Any) -> str | None:
    if n is not None and not isinstance(n, str):
        raise InputError(f"name: {n!r} is not a string")
    return n


class Scene:
    """A sub-surface scene: height fields and triangle meshes, each cut into tiles with a fine and
    a coarse level of detail. Coordinates are world units (metres); inputs are kept in f64 and
    stored relative to one scene origin, so UTM-sized coordinates keep full precision."""

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
        origin: (x0, y0) world position of ``z[0, 0]``.  spacing: (dx, dy) > 0 sample spacing.
        tiles: (tx, ty) tiles along x and y (each at least one cell wide); tiles share border samples.
        coarse_factor: >= 1; the coarse proxy of each tile has about 1/coarse_factor of its triangles.
        color: (r, g, b) in [0, 1].  Returns the object id.
        """
        za = _floats(z, "z", 2)
        o = _vec(origin, "origin", 2)
        sp = _vec(spacing, "spacing", 2)
        t = _array(tiles, "tiles", 1, 2, kinds="iu")
        tt = (_int(t[0], "tiles[0]", 1), _int(t[1], "tiles[1]", 1))
        nv = None if null_value is None else _number(null_value, "null_value")
        return self._s.add_heightfield(
            za, o, sp, tt, _number(coarse_factor, "coarse_factor"), _name(name), _color(color), nv
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

        vertices: (n, 3) world coordinates (finite).  faces: (m, 3) integer indices in [0, n).
        kind: a label ("fault", "mesh", ...).  tiles: None = one tile, k = about k spatially
        coherent clusters.  coarse_factor, color: as for :meth:`add_heightfield`. Returns the id.
        """
        v = _floats(vertices, "vertices", 2, 3)
        f = _array(faces, "faces", 2, 3, kinds="iu")
        if f.dtype.kind == "u" and f.size and f.max() > np.iinfo(np.int64).max:
            raise InputError("faces: index too large")
        f = np.ascontiguousarray(f, dtype=np.int64)
        if not isinstance(kind, str):
            raise InputError(f"kind: {kind!r} is not a string")
        k = None if tiles is None else _int(tiles, "tiles", 1)
        return self._s.add_mesh(v, f, kind, k, _number(coarse_factor, "coarse_factor"), _name(name), _color(color))

    def remove(self, id: int) -> None:
        """Remove an object."""
        self._s.remove(_int(id, "id"))

    def set_visible(self, id: int, visible: bool) -> None:
        """Show or hide an object (no re-upload)."""
        self._s.set_visible(_int(id, "id"), bool(visible))

    def translate(self, id: int, offset: Sequence[float]) -> None:
        """Move an object by (dx, dy, dz) world units (no re-upload)."""
        self._s.translate(_int(id, "id"), _vec(offset, "offset", 3))

    def set_color(self, id: int, color: Sequence[float]) -> None:
        self._s.set_color(_int(id, "id"), _vec(color, "color", 3))

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
        """The f64 origin positions are stored relative to (set by the first object)."""
        return self._s.origin

    @property
    def host_bytes(self) -> int:
        """Bytes of geometry held in host memory."""
        return self._s.host_bytes

    def object_ids(self) -> list[int]:
        return self._s.object_ids()

    def object_info(self, id: int) -> dict:
        """name, kind, color, visible, offset, n_tiles, n_triangles of an object."""
        return self._s.object_info(_int(id, "id"))

    def geometry(self, id: int) -> tuple[np.ndarray, np.ndarray]:
        """The fine triangles of an object: (vertices (n, 3) float64 world coords, faces (m, 3) int64)."""
        return self._s.geometry(_int(id, "id"))

    def tile_table(self) -> np.ndarray:
        """One row per tile, in the renderer's tile order (the index of ``tile_pixels``):
        object, ix, iy, tris_fine, tris_coarse, bbox_min (3,), bbox_max (3,) (world coords; NaN if empty)."""
        c = self._s.tile_table()
        dt = np.dtype([("object", "u4"), ("ix", "u4"), ("iy", "u4"), ("tris_fine", "u4"),
                       ("tris_coarse", "u4"), ("bbox_min", "f8", (3,)), ("bbox_max", "f8", (3,))])
        t = np.zeros(len(c["object"]), dtype=dt)
        for k in dt.names:
            t[k] = c[k]
        return t

    def __repr__(self) -> str:
        return f"<geocull.Scene objects={len(self.object_ids())} tiles={self.n_tiles} triangles={self.n_triangles}>"


class Camera:
    """A look-at camera in world coordinates (f64). Build it with :meth:`look_at`."""

    def __init__(self, inner: Any) -> None:
        self._c = inner

    @staticmethod
    def look_at(
        eye: Sequence[float],
        target: Sequence[float],
        up: Sequence[float] = (0.0, 0.0, 1.0),
        fov_y: float = 45.0,
        near: float | None = None,
        far: float | None = None,
        projection: str = "perspective",
        ortho_height: float | None = None,
        z_scale: float = 1.0,
    ) -> "Camera":
        """eye, target: world points (metres); up: approximate up vector (if parallel to the view
        direction, e.g. looking straight down with up=z, another axis is used). fov_y: vertical
        field of view in degrees, (0, 180). near/far: distances along the view axis (None = from
        the scene bounds). projection: "perspective" or "orthographic"; ortho_height: height of the
        orthographic view in world units (None = what fov_y sees at the target). z_scale: vertical
        exaggeration, applied to the scene and to eye/target alike (z -> z * z_scale)."""
        if not isinstance(projection, str):
            raise InputError(f"projection: {projection!r} is not a string")
        inner = _geocull.Camera.look_at(
            _vec(eye, "eye", 3), _vec(target, "target", 3), _vec(up, "up", 3), _number(fov_y, "fov_y"),
            None if near is None else _number(near, "near"), None if far is None else _number(far, "far"),
            projection, None if ortho_height is None else _number(ortho_height, "ortho_height"),
            _number(z_scale, "z_scale"),
        )
        return Camera(inner)

    eye = property(lambda self: self._c.eye)
    target = property(lambda self: self._c.target)
    up = property(lambda self: self._c.up)
    fov_y = property(lambda self: self._c.fov_y)
    near = property(lambda self: self._c.near)
    far = property(lambda self: self._c.far)
    projection = property(lambda self: self._c.projection)
    ortho_height = property(lambda self: self._c.ortho_height)
    z_scale = property(lambda self: self._c.z_scale)

    def view_matrix(self) -> np.ndarray:
        """(4, 4) world (exaggerated) -> view matrix; the camera looks down -z, y up."""
        return self._c.view_matrix()

    def __repr__(self) -> str:
        return f"<geocull.Camera {self.projection} eye={self.eye} target={self.target} fov_y={self.fov_y}>"


def _png(image: np.ndarray) -> bytes:
    """Encodes an (H, W, 4) uint8 image as PNG (no dependency beyond zlib)."""
    h, w = image.shape[:2]
    raw = b"".join(b"\x00" + image[r].tobytes() for r in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


class RenderResult:
    """One rendered frame.

    image: (H, W, 4) uint8 RGBA, row 0 at the top.  depth: (H, W) float32 distance along the view
    axis in (exaggerated) world units, +inf where empty.  tile_pixels: (n_tiles,) uint32 visible
    pixels per tile (three_pass: the pass-2 counts in full-image pixels; none/oracle: in the final
    image).  tile_drawn: (n_tiles,) bool.  stats: triangles and per-pass milliseconds.
    near, far: the clip distances used.
    """

    def __init__(self, d: dict, culling: str) -> None:
        self.image: np.ndarray = d["image"]
        self.depth: np.ndarray = d["depth"]
        self.tile_pixels: np.ndarray = d["tile_pixels"]
        self.tile_drawn: np.ndarray = d["tile_drawn"]
        self.stats: dict = d["stats"]
        self.near: float = d["near"]
        self.far: float = d["far"]
        self.culling = culling
        self.horizon: np.ndarray | None = d.get("horizon")

    @property
    def coverage(self) -> np.ndarray:
        """(H, W) bool: pixels where something was drawn."""
        return np.isfinite(self.depth)

    def png(self) -> bytes:
        return _png(self.image)

    def save_png(self, path: str) -> None:
        with open(path, "wb") as f:
            f.write(self.png())

    def _repr_png_(self) -> bytes:
        return self.png()

    def __repr__(self) -> str:
        s = self.stats
        return (f"<geocull.RenderResult {self.image.shape[1]}x{self.image.shape[0]} culling={self.culling} "
                f"triangles_drawn={s['triangles_drawn']} tiles_drawn={s['tiles_drawn']}/{s['tiles_total']} "
                f"total_ms={s['total_ms']:.1f}>")


CULLING = ("none", "three_pass", "oracle", "horizon")


class Renderer:
    """Off-screen wgpu renderer for width x height images. backend: "auto" (a GPU if present, else
    Mesa's lavapipe on the CPU), "vulkan", "gl", ... Raises DeviceError if no adapter is found."""

    def __init__(self, width: int = 1280, height: int = 1024, backend: str = "auto") -> None:
        if not isinstance(backend, str):
            raise InputError(f"backend: {backend!r} is not a string")
        self._r = _geocull.Renderer(_int(width, "width", 1), _int(height, "height", 1), backend)

    width = property(lambda self: self._r.width)
    height = property(lambda self: self._r.height)
    adapter_info = property(lambda self: self._r.adapter_info, doc="The adapter in use, in words.")
    max_texture_size = property(lambda self: self._r.max_texture_size)

    @property
    def gpu_bytes(self) -> int:
        """Bytes of scene geometry held on the GPU."""
        return self._r.gpu_bytes

    def render(
        self,
        scene: Scene,
        camera: Camera,
        culling: str = "none",
        pixel_threshold: float = 10,
        prepass_scale: float = 1.0,
    ) -> RenderResult:
        """Render ``scene`` seen by ``camera``.

        culling: "none" (every fine tile, the reference), "three_pass" (GPU depth prepass of coarse
        proxies, exact visible-pixel count per tile, fine draw of tiles with more than
        ``pixel_threshold`` pixels), "oracle" (exactly the tiles visible in the unculled image; a
        benchmark lower bound), "horizon" (CPU horizon culling of height fields).
        pixel_threshold: >= 0, in full-image pixels.  prepass_scale: (0, 1], prepass resolution.

        Accuracy: "none", "oracle" and "horizon" give the unculled image. "three_pass" is exact
        with pixel_threshold=0 and coarse_factor=1; with coarser proxies it is approximate, as in
        the method's paper: a proxy that bulges above its fine tile can hide a tile that is
        visible. Measured: at most 0.03 % of pixels on the stacked Gullfaks-like scene, but up
        to 9 % for low, near-horizontal views over rough terrain at coarse_factor=25 (0.3 % at 4);
        use culling="horizon" (exact) for such views.
        """
        _expect(scene, Scene, "scene")
        _expect(camera, Camera, "camera")
        if not isinstance(culling, str):
            raise InputError(f"culling: {culling!r} is not a string")
        d = self._r.render(scene._s, camera._c, culling, _number(pixel_threshold, "pixel_threshold"),
                           _number(prepass_scale, "prepass_scale"))
        return RenderResult(d, culling)

    def render_isosurface(self, volume: Any, isovalue: float, camera: Camera, culling: str = "implicit", **kwargs: Any) -> RenderResult:
        """Render the isosurface ``volume == isovalue``; see :func:`geocull.iso.render_isosurface`."""
        from .iso import render_isosurface

        return render_isosurface(self, volume, isovalue, camera, culling=culling, **kwargs)

    def __repr__(self) -> str:
        return f"<geocull.Renderer {self.width}x{self.height} on {self.adapter_info}>"
