"""PyVista/VTK interop and reference renders.

``to_polydata``           one scene object → ``pyvista.PolyData`` (name, kind, colour in field data)
``from_polydata``         any PyVista/VTK surface → ``scene.add_mesh`` (triangulated); returns the id
``scene_to_multiblock``   every object → ``pyvista.MultiBlock`` keyed by name
``reference_image``       the scene rendered off-screen by VTK with the same camera: image, linear
                          depth (same units as ``RenderResult.depth``) and render time
``timed_render``          best-of-N VTK render time for benchmarks

Works on any object with ``geometry(id)``, ``object_ids()`` and ``object_info(id)`` (a
``geocull.Scene`` or a stand-in), and on a ``geocull.Camera`` or a dict of ``Camera.look_at``
arguments. pyvista is imported lazily, after ``VTK_DEFAULT_OPENGL_WINDOW`` defaults to
``vtkEGLRenderWindow`` so VTK renders off-screen through EGL (llvmpipe without a GPU) and never
tries X11.

Depth: VTK's z-buffer (24-bit, standard OpenGL depth in [0, 1], 1 = cleared) is read with
``vtkRenderWindow.GetZbufferData`` and converted in float64 with the clipping range actually used:
perspective ``d = 2nf / ((f + n) - (2 zb - 1)(f - n))``, orthographic ``d = n + zb (f - n)``;
cleared pixels (``zb == 1``) become ``inf``. (``Plotter.get_image_depth`` computes the same thing in
float32, negated, with NaN for the background, and by default resets the clipping range first.)
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol, TypeAlias

import numpy as np
from numpy.typing import ArrayLike

from ._convert import surface_of
from ._errors import GeocullError

if TYPE_CHECKING:
    import pyvista

    from .camera import Camera

# VTK reads this when it creates a render window: EGL renders off-screen (llvmpipe without a GPU).
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

__all__ = [
    "SceneLike",
    "CameraLike",
    "to_polydata",
    "from_polydata",
    "scene_to_multiblock",
    "reference_image",
    "timed_render",
    "camera_params",
]


class SceneLike(Protocol):
    """What these functions read of a scene: a ``geocull.Scene`` or a stand-in such as
    :class:`geocull.data.MeshScene`."""

    def geometry(self, id: int, /) -> tuple[np.ndarray, np.ndarray]: ...
    def object_ids(self) -> list[int]: ...
    def object_info(self, id: int, /) -> Mapping[str, Any]: ...


#: A ``geocull.Camera``, or a mapping of ``Camera.look_at`` arguments (eye, target, ...).
CameraLike: TypeAlias = "Camera | Mapping[str, Any]"


def _pv() -> Any:
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista

    return pyvista


def _input_error(msg: str) -> ValueError:
    import sys

    cls = getattr(sys.modules.get("geocull"), "InputError", None)
    if not (isinstance(cls, type) and issubclass(cls, ValueError)):
        cls = ValueError
    return cls(msg)


def _rgb01(color) -> tuple[float, float, float]:
    """Colour as floats in [0, 1]; values above 1 are taken as 0–255."""
    if color is None:
        return (0.8, 0.8, 0.8)
    c = np.asarray(color, dtype=np.float64).ravel()[:3]
    if c.size != 3 or not np.all(np.isfinite(c)):
        return (0.8, 0.8, 0.8)
    if c.max() > 1.0:
        c = c / 255.0
    c = np.clip(c, 0.0, 1.0)
    return (float(c[0]), float(c[1]), float(c[2]))


def _info(scene, oid) -> dict[str, Any]:
    try:
        info = scene.object_info(oid)
    except AttributeError:
        info = {}
    return dict(info) if info is not None else {}


def _geometry(scene, oid) -> tuple[np.ndarray, np.ndarray]:
    v, f = scene.geometry(oid)
    v = np.ascontiguousarray(np.asarray(v, dtype=np.float64).reshape(-1, 3))
    f = np.ascontiguousarray(np.asarray(f, dtype=np.int64).reshape(-1, 3))
    return v, f


def to_polydata(scene: SceneLike, object_id: int) -> pyvista.PolyData:
    """The fine geometry of one scene object as a ``pyvista.PolyData`` (world coordinates).

    ``field_data`` holds ``name``, ``kind``, ``color`` (RGB floats in [0, 1]) and ``object_id``.
    """
    pv = _pv()
    v, f = _geometry(scene, object_id)
    if len(f):
        pd = pv.PolyData.from_regular_faces(v, f)
    else:
        pd = pv.PolyData(v) if len(v) else pv.PolyData()
        if len(v):
            pd.verts = np.empty(0, dtype=np.int64)  # points only, no vertex cells
    info = _info(scene, object_id)
    pd.field_data["name"] = [str(info.get("name", f"object_{object_id}"))]
    pd.field_data["kind"] = [str(info.get("kind", "mesh"))]
    pd.field_data["color"] = np.asarray(_rgb01(info.get("color")), dtype=np.float64)
    pd.field_data["object_id"] = np.asarray([int(object_id)], dtype=np.int64)
    return pd


def _field_str(pd, key):
    if key in pd.field_data.keys():
        val = pd.field_data[key]
        try:
            return str(np.asarray(val).ravel()[0])
        except IndexError:
            return None
    return None


def from_polydata(
    scene: Any,
    polydata: Any,
    kind: str | None = None,
    tiles: int | None = None,
    coarse_factor: float = 1.0,
    name: str | None = None,
    color: ArrayLike | None = None,
) -> int:
    """Add a PyVista/VTK surface to ``scene`` with ``scene.add_mesh`` and return the new object id.

    Non-PolyData datasets are reduced to their outer surface; polygons and strips are triangulated
    (lines and vertex cells are dropped). ``name``, ``color`` and ``kind`` default to the
    ``field_data`` entries written by :func:`to_polydata` when present (kind else "mesh");
    ``tiles`` and ``coarse_factor`` go to ``add_mesh`` unchanged. (``geocull.Scene.add_mesh`` also
    takes a PolyData directly.)
    """
    pv = _pv()
    pd = polydata if isinstance(polydata, pv.DataSet) else pv.wrap(polydata)
    if pd is None:
        raise _input_error(f"polydata: cannot interpret {type(polydata).__name__} as a PyVista dataset")
    if not isinstance(pd, pv.PolyData):
        pd = surface_of(pd)
    if not pd.is_all_triangles:
        pd = pd.triangulate()
    faces = np.asarray(pd.faces, dtype=np.int64)
    if faces.size == 0:
        raise _input_error("polydata: has no polygon cells to add")
    faces = faces.reshape(-1, 4)
    if not np.all(faces[:, 0] == 3):
        raise _input_error("polydata: triangulation left non-triangle cells")
    if name is None:
        name = _field_str(pd, "name")
    if kind is None:
        kind = _field_str(pd, "kind") or "mesh"
    if color is None and "color" in pd.field_data.keys():
        color = _rgb01(pd.field_data["color"])
    verts = np.ascontiguousarray(np.asarray(pd.points, dtype=np.float64))
    return int(scene.add_mesh(verts, np.ascontiguousarray(faces[:, 1:]), kind=kind, tiles=tiles,
                              coarse_factor=coarse_factor, name=name, color=color))


def scene_to_multiblock(scene: SceneLike) -> pyvista.MultiBlock:
    """All scene objects as a ``pyvista.MultiBlock``, one block per object named after it
    (``name`` or ``name#id`` when names repeat)."""
    pv = _pv()
    mb = pv.MultiBlock()
    seen: set[str] = set()
    for oid in scene.object_ids():
        pd = to_polydata(scene, oid)
        name = str(pd.field_data["name"][0])
        if name in seen:
            name = f"{name}#{oid}"
        seen.add(name)
        mb[name] = pd
    return mb


# --------------------------------------------------------------------------- camera


def camera_params(camera: CameraLike | Any) -> dict[str, Any]:
    """Normalise a ``geocull.Camera`` (or a dict of ``Camera.look_at`` arguments, or any object
    with those attributes) to a dict with every field: eye, target, up, fov_y, near, far,
    projection, ortho_height, z_scale."""
    defaults = dict(
        up=(0.0, 0.0, 1.0),
        fov_y=45.0,
        near=None,
        far=None,
        projection="perspective",
        ortho_height=None,
        z_scale=1.0,
    )
    out: dict[str, Any] = {}
    for key in ("eye", "target", "up", "fov_y", "near", "far", "projection", "ortho_height", "z_scale"):
        if isinstance(camera, dict):
            val = camera.get(key, defaults.get(key))
        else:
            val = getattr(camera, key, defaults.get(key))
        if val is None and key in ("eye", "target"):
            raise _input_error(f"camera: has no {key}")
        out[key] = val
    for key in ("eye", "target", "up"):
        out[key] = np.asarray(out[key], dtype=np.float64).reshape(3)
    out["fov_y"] = float(out["fov_y"])
    out["z_scale"] = float(out["z_scale"] if out["z_scale"] is not None else 1.0)
    proj = str(out["projection"] or "perspective").lower()
    if proj not in ("perspective", "orthographic"):
        raise _input_error(f"camera: unknown projection {out['projection']!r}")
    out["projection"] = proj
    return out


def _effective_up(up: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """``up`` unless (nearly) parallel to the view direction; then the world axis least aligned with
    it, tried in the order Y, X, Z (the rule geocull's camera uses)."""
    n = np.linalg.norm(up)
    if n > 0:
        u = up / n
        if np.linalg.norm(np.cross(forward, u)) > 1e-9:
            return u
    axes = [np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])]
    return min(axes, key=lambda a: abs(float(a @ forward)))


# --------------------------------------------------------------------------- rendering


class _Setup:
    """A configured off-screen plotter holding the scene in render space (shifted by ``origin``)."""

    def __init__(
        self,
        scene,
        camera,
        width: int,
        height: int,
        msaa: bool,
        lighting: bool,
        near: float | None,
        far: float | None,
        background,
        min_near_ratio: float,
    ):
        pv = _pv()
        width, height = int(width), int(height)
        if width < 1 or height < 1:
            raise _input_error(f"width, height: must be >= 1, got {width}x{height}")
        cam = camera_params(camera)
        s = cam["z_scale"]
        self.cam = cam

        # Geometry of every visible object; the shift keeps VTK's float32 buffers precise at
        # UTM-sized coordinates (depth is translation invariant).
        objs = []
        for oid in scene.object_ids():
            info = _info(scene, oid)
            if info.get("visible", True) is False:
                continue
            v, f = _geometry(scene, oid)
            if len(f) == 0:
                continue
            objs.append((v, f, _rgb01(info.get("color"))))
        if objs:
            # nan-aware: unreferenced NaN vertices (height-field holes) may be present
            lo = np.nanmin([np.nanmin(v, axis=0) for v, _, _ in objs], axis=0)
            hi = np.nanmax([np.nanmax(v, axis=0) for v, _, _ in objs], axis=0)
            origin = 0.5 * (lo + hi)
        else:
            lo = hi = origin = cam["target"].copy()
        self.origin = origin

        def to_render(p):
            r = np.asarray(p, dtype=np.float64) - origin
            return r * np.array([1.0, 1.0, s])

        eye = to_render(cam["eye"])
        target = to_render(cam["target"])
        fwd = target - eye
        dist = float(np.linalg.norm(fwd))
        if not dist > 0:
            raise _input_error("camera: eye and target coincide")
        fwd = fwd / dist
        up = _effective_up(cam["up"], fwd)

        # Clipping range: explicit > camera's > from the bounds (geocull's rule: box corners' range
        # along the view axis widened by 1 % of its span).
        n_ = near if near is not None else cam["near"]
        f_ = far if far is not None else cam["far"]
        given_near, given_far = n_ is not None, f_ is not None
        # A clipping range that can only give an empty image is an error, not a blank frame.
        ortho = cam["projection"] == "orthographic"
        for dist, arg in ((n_, "near"), (f_, "far")):
            ok = isinstance(dist, (int, float, np.integer, np.floating)) and math.isfinite(dist)
            if dist is not None and not (ok and (dist > 0 or (arg == "near" and ortho and dist == 0))):
                want = "a finite distance >= 0" if arg == "near" and ortho else "a finite distance > 0"
                raise _input_error(f"{arg}: {dist!r}; expected {want}")
        if given_near and given_far and not f_ > n_:
            raise _input_error(f"far ({f_}) must be greater than near ({n_})")
        if n_ is None or f_ is None:
            rlo, rhi = to_render(lo), to_render(hi)
            corners = np.array(
                [[x, y, z] for x in (rlo[0], rhi[0]) for y in (rlo[1], rhi[1]) for z in (rlo[2], rhi[2])]
            )
            d = (corners - eye) @ fwd
            dmin, dmax = float(d.min()), float(d.max())
            span = max(dmax - dmin, 1e-6)
            if f_ is None:
                f_ = max(dmax + 0.01 * span, 1e-3)
            if n_ is None:
                floor = 0.0 if cam["projection"] == "orthographic" else max(f_ * min_near_ratio, 1e-6)
                n_ = max(dmin - 0.01 * span, floor)
        n_, f_ = float(n_), float(f_)
        if given_near and not given_far and not f_ > n_:
            raise _input_error(f"near: {n_} is beyond the scene (its far end is at {f_:g} along the view axis); "
                               "nothing would be drawn")
        if cam["projection"] == "perspective":
            # VTK's depth buffer is 24-bit fixed point: keep far/near bounded.
            n_ = max(n_, f_ * min_near_ratio)
        if not f_ > n_:
            f_ = n_ + max(1e-3, abs(n_) * 1e-6)
        self.near, self.far = n_, f_

        pl = pv.Plotter(off_screen=True, window_size=(width, height))
        if not msaa:
            pl.disable_anti_aliasing()
            pl.render_window.SetMultiSamples(0)
        pl.set_background(_rgb01(background) if background is not None else (0.0, 0.0, 0.0))
        for v, f, color in objs:
            vs = v - origin
            bad = ~np.isfinite(vs)
            if bad.any():
                vs[bad.any(axis=1)] = 0.0  # unreferenced hole vertices: keep VTK's bounds finite
            mesh = pv.PolyData.from_regular_faces(vs, f)
            pl.add_mesh(mesh, color=color, lighting=lighting, smooth_shading=False, show_scalar_bar=False)
        if s != 1.0:
            pl.set_scale(zscale=s, reset_camera=False, render=False)
        c = pl.camera
        c.position = tuple(eye)
        c.focal_point = tuple(target)
        c.up = tuple(up)
        c.view_angle = cam["fov_y"]
        if cam["projection"] == "orthographic":
            h = cam["ortho_height"]
            if h is None:
                h = 2.0 * dist * math.tan(math.radians(cam["fov_y"]) / 2.0)
            c.parallel_projection = True
            c.parallel_scale = float(h) / 2.0
        c.clipping_range = (n_, f_)
        pl.camera_set = True
        self.plotter = pl
        self.width, self.height = width, height

    def render(self) -> float:
        """Render once; returns wall milliseconds (including the GPU/CPU rasteriser finishing)."""
        rw = self.plotter.render_window
        self.plotter.camera.clipping_range = (self.near, self.far)
        self.plotter.renderer.Modified()
        t0 = time.perf_counter()
        rw.Render()
        rw.WaitForCompletion()
        return (time.perf_counter() - t0) * 1e3

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        from vtkmodules.util.numpy_support import vtk_to_numpy
        from vtkmodules.vtkCommonCore import vtkFloatArray, vtkUnsignedCharArray

        rw = self.plotter.render_window
        w, h = self.width, self.height
        # A clipping range that VTK changed behind our back would make the depth conversion wrong.
        got = self.plotter.camera.clipping_range
        if not np.allclose(got, (self.near, self.far), rtol=1e-9, atol=0):
            raise GeocullError(f"VTK changed the clipping range to {got}")
        rgb = vtkUnsignedCharArray()
        rw.GetPixelData(0, 0, w - 1, h - 1, 0, rgb, 0)
        img = vtk_to_numpy(rgb).reshape(h, w, 3)[::-1].copy()
        zarr = vtkFloatArray()
        rw.GetZbufferData(0, 0, w - 1, h - 1, zarr)
        zb = vtk_to_numpy(zarr).astype(np.float64).reshape(h, w)[::-1]
        n, f = self.near, self.far
        if self.cam["projection"] == "orthographic":
            d = n + zb * (f - n)
        else:
            d = 2.0 * n * f / ((f + n) - (2.0 * zb - 1.0) * (f - n))
        d[zb >= 1.0] = np.inf
        return img, d.astype(np.float32)

    def close(self):
        self.plotter.close()


def reference_image(
    scene: SceneLike,
    camera: CameraLike,
    width: int,
    height: int,
    msaa: bool = False,
    lighting: bool = True,
    near: float | None = None,
    far: float | None = None,
    background: ArrayLike = (0.0, 0.0, 0.0),
    repeats: int = 1,
    min_near_ratio: float = 1e-4,
) -> dict[str, Any]:
    """Render ``scene`` off-screen with PyVista/VTK from ``camera`` (same conventions as geocull).

    Camera mapping: position/focal point/view up from eye/target/up (render space: z multiplied by
    ``z_scale`` for the scene via ``set_scale`` and for eye/target alike), view angle = ``fov_y``
    (vertical), parallel projection with ``parallel_scale = ortho_height / 2`` for orthographic (if
    ``ortho_height`` is None: the perspective view's height at the target). Clipping range =
    ``(near, far)`` if given (pass ``res.near, res.far`` to match a geocull render), else the
    camera's, else the scene bounds' range along the view axis ±1 %. For perspective the near plane
    is raised to at least ``far * min_near_ratio`` (VTK's depth buffer is 24-bit).

    Colours come from ``object_info(id)["color"]``; background black; objects whose info has
    ``visible=False`` are skipped. ``msaa=False`` disables all anti-aliasing (multi-samples 0);
    ``msaa=True`` keeps PyVista's defaults.

    Returns dict: ``image`` (H, W, 3) uint8, row 0 = top; ``depth`` (H, W) float32 distance along
    the view axis (render-space units, ``inf`` where empty); ``ms`` render time (the first render,
    which includes uploading the geometry, or with ``repeats > 1`` the best of the later ones);
    ``near``/``far`` the clipping range used.
    """
    setup = _Setup(scene, camera, width, height, msaa, lighting, near, far, background, min_near_ratio)
    try:
        times = [setup.render() for _ in range(max(1, int(repeats)))]
        img, depth = setup.read()
    finally:
        setup.close()
    ms = times[0] if len(times) == 1 else min(times[1:])
    return dict(image=img, depth=depth, ms=ms, near=setup.near, far=setup.far)


def timed_render(
    scene: SceneLike,
    camera: CameraLike,
    width: int,
    height: int,
    n: int = 5,
    msaa: bool = False,
    lighting: bool = True,
    near: float | None = None,
    far: float | None = None,
    min_near_ratio: float = 1e-4,
) -> float:
    """Best VTK render time in ms over ``n`` renders after one warm-up render (not counted)."""
    setup = _Setup(scene, camera, width, height, msaa, lighting, near, far, (0.0, 0.0, 0.0), min_near_ratio)
    try:
        setup.render()  # warm-up: context, shaders, geometry upload
        return min(setup.render() for _ in range(max(1, int(n))))
    finally:
        setup.close()
