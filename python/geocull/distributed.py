"""Many views on many machines: :func:`render_views` on a Dask distributed cluster.

Each worker builds the scene once from a picklable spec and keeps it, with one
:class:`geocull.Renderer` per image size, in a per-process cache keyed by the spec's hash, so a
second call with the same spec builds nothing. The spec goes to the cluster once
(``client.scatter(..., broadcast=True)``), the cameras one task each.

Needs ``distributed`` (``pip install distributed``; Dask's scheduler) and, for ``store=``, ``zarr``;
both are imported only here, inside the functions.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ._errors import InputError
from .camera import Camera

if TYPE_CHECKING:
    from ._scene_slices import SliceAxis
    from .renderer import Renderer
    from .scene import Scene

__all__ = ["render_views", "RenderedView", "SceneSource", "VolumeStoreScene", "worker_cache_info", "benchmark"]

@dataclass(frozen=True)
class VolumeStoreScene:
    """A scene source for :func:`render_views` that each worker builds from a volume store itself:
    only this description travels (a few hundred bytes of pickle), never the cube. ``store``: the
    path or URL of a zarr array (n_i, n_j, n_k) that every worker can open (a shared file system,
    an object store); ``spacing`` / ``origin``: as for :class:`geocull.Volume` (metres);
    ``slices``: ``(axis, index)`` pairs, each a seismic slice (:meth:`geocull.Scene.add_slice`);
    ``isovalue``: an isosurface of it (:meth:`geocull.Scene.add_isosurface`) when not None;
    ``cache_bytes``: each worker's brick cache. The volume is lazy (``gc.Volume(zarr_array)``):
    a worker reads the samples its scene needs, through its cache."""

    store: str
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    slices: tuple[tuple[SliceAxis | int, int], ...] = ()
    isovalue: float | None = None
    cache_bytes: int | None = None

    def build(self) -> Scene:
        """The scene: the store's volume (lazy), its slices and isosurface."""
        import zarr

        from .scene import Scene
        from .volume import Volume

        try:
            arr = zarr.open_array(self.store, mode="r")
        except Exception as e:  # zarr's own errors for a missing or foreign store
            raise InputError(f"store: {self.store!r} is not a zarr array that can be opened ({e})") from None
        vol = Volume(arr, spacing=self.spacing, origin=self.origin, cache_bytes=self.cache_bytes)
        scene = Scene()
        for axis, index in self.slices:
            scene.add_slice(vol, axis, index)
        if self.isovalue is not None:
            scene.add_isosurface(vol, self.isovalue)
        return scene


#: What :func:`render_views` accepts as the scene: a :class:`geocull.Scene` (pickled as its bytes),
#: an object with a ``build()`` method (a :class:`geocull.data.SceneSpec`), or a picklable callable
#: with no arguments that returns a Scene (``functools.partial(spec.build, tiles=(10, 10))``).
SceneSource = Any


@dataclass
class RenderedView:
    """One view's frame as plain arrays (what comes back from a worker): ``image`` (H, W, 4) uint8
    RGBA, row 0 at the top; ``depth`` (H, W) float32, distance along the view axis, inf where
    empty; ``stats``: the frame's :class:`geocull.RenderStats` dict; ``worker``: which process
    rendered it (host:pid)."""

    image: np.ndarray
    depth: np.ndarray
    stats: dict[str, Any] = field(default_factory=dict)
    culling: str = ""
    worker: str = ""

    def _repr_png_(self) -> bytes:
        from .results import encode_png

        return encode_png(self.image)


# Per worker process: spec hash -> scene, (width, height, backend) -> renderer, builds made.
_CACHE: dict[str, Scene] = {}
_RENDERERS: dict[tuple[int, int, str], Renderer] = {}
_BUILDS: dict[str, int] = {}
_LOCK = threading.Lock()
_MAX_SCENES = 2  # scenes kept per process (the least recently used go first)


def _pickled(spec: SceneSource) -> tuple[bytes, str]:
    """The spec as pickle bytes (protocol 4: every array travels in-band and is unpickled into
    fresh, aligned memory; Dask's out-of-band buffers can arrive misaligned, which the core's
    array checks reject) and their hash, the workers' cache key."""
    try:
        data = pickle.dumps(spec, protocol=4)
    except Exception as e:
        raise InputError(f"scene_spec: cannot be pickled for the workers ({e})") from None
    return data, hashlib.sha256(data).hexdigest()


def _spec_key(spec: SceneSource) -> str:
    """The cache key of ``spec`` (the hash of its pickle)."""
    return _pickled(spec)[1]


def _build(spec: SceneSource) -> Scene:
    from .scene import Scene

    if isinstance(spec, Scene):
        return spec
    if hasattr(spec, "build") and callable(spec.build):
        scene = spec.build()
    elif callable(spec):
        scene = spec()
    else:
        raise InputError(
            f"scene_spec: expected a Scene, an object with build() or a callable, got {type(spec).__name__}"
        )
    if not isinstance(scene, Scene):
        raise InputError(f"scene_spec: building it gave a {type(scene).__name__}, not a geocull.Scene")
    return scene


def _scene_for(key: str, spec: bytes) -> Scene:
    with _LOCK:
        scene = _CACHE.pop(key, None)
        if scene is None:
            scene = _build(pickle.loads(spec))
            _BUILDS[key] = _BUILDS.get(key, 0) + 1
        _CACHE[key] = scene  # most recently used last
        while len(_CACHE) > _MAX_SCENES:
            _CACHE.pop(next(iter(_CACHE)))
        return scene


def _renderer_for(width: int, height: int, backend: str) -> Renderer:
    from .renderer import Renderer

    with _LOCK:
        r = _RENDERERS.get((width, height, backend))
        if r is None:
            r = _RENDERERS[(width, height, backend)] = Renderer(width, height, backend)
        return r


def _worker_name() -> str:
    return f"{os.uname().nodename}:{os.getpid()}"


def _render_one(
    spec: bytes, key: str, camera: Camera, width: int, height: int, backend: str,
    options: dict[str, Any], store: Any = None, index: int = -1,
) -> RenderedView:
    """One view on this process (a worker, or the caller when no cluster is used)."""
    scene = _scene_for(key, spec)
    r = _renderer_for(width, height, backend)
    res = r.render(scene, camera, **options)
    view = RenderedView(np.array(res.image), np.array(res.depth), dict(res.stats), res.culling, _worker_name())
    if store is not None:
        import zarr

        g = zarr.open_group(store, mode="r+")
        for name, values in (("image", view.image), ("depth", view.depth)):
            arr = g[name]
            if not isinstance(arr, zarr.Array):
                raise InputError(f"store: {name!r} is not an array")
            arr[index] = values
        return RenderedView(np.zeros((0, 0, 4), np.uint8), np.zeros((0, 0), np.float32), view.stats,
                            view.culling, view.worker)
    return view


def worker_cache_info() -> dict[str, Any]:
    """This process's cache: ``scenes`` (spec hashes held), ``builds`` (spec hash -> scenes built,
    1 when a spec was built once), ``renderers`` ((width, height, backend) held). On a cluster:
    ``client.run(geocull.distributed.worker_cache_info)``."""
    with _LOCK:
        return dict(scenes=list(_CACHE), builds=dict(_BUILDS), renderers=list(_RENDERERS))


def _camera(c: Any, i: int) -> Camera:
    if isinstance(c, Camera):
        return c
    if isinstance(c, Mapping):
        return Camera.look_at(**c)
    raise InputError(f"cameras[{i}]: expected a geocull.Camera or a dict of Camera.look_at arguments, "
                     f"got {type(c).__name__}")


def _client(client: Any) -> Any:
    if client is not None:
        return client
    try:
        from distributed import get_client
    except ImportError:
        return None
    try:
        return get_client()
    except ValueError:  # no client running: render here
        return None


def render_views(
    scene_spec: SceneSource,
    cameras: Sequence[Camera | Mapping[str, Any]],
    client: Any = None,
    width: int = 1280,
    height: int = 1024,
    backend: str = "auto",
    store: Any = None,
    **render_options: Any,
) -> list[RenderedView] | Any:
    """Render one frame per camera of one scene on a Dask distributed cluster; the results come
    back in the cameras' order.

    scene_spec: a :data:`SceneSource`: a :class:`geocull.Scene`, a :class:`geocull.data.SceneSpec`
        (built with its defaults) or a picklable zero-argument callable returning a Scene. It is
        sent to every worker once; each worker builds the scene once and keeps it (with its
        renderers) for later calls with the same spec (keyed by the hash of its pickle).
    cameras: :class:`geocull.Camera` objects or dicts of :meth:`Camera.look_at` arguments.
    client: a ``distributed.Client``; None = the current one (``distributed.get_client()``), or,
        when none is running, the views are rendered here, one after the other, through the same
        cache (so results never depend on where they were made).
    width, height, backend: the renderers' (pixels; see :class:`geocull.Renderer`).
    store: None (return the arrays) or a zarr store / path: arrays ``image`` (n, H, W, 4) uint8 and
        ``depth`` (n, H, W) float32 (one chunk per view) are created there and each worker writes its
        views straight into them; the zarr group is returned, with the frames' stats as its
        attribute ``stats`` (a list). The store must be reachable from every worker (a shared
        file system or an object store).
    render_options: :meth:`Renderer.render`'s keyword arguments (culling, pixel_threshold, ...).

    Returns a list of :class:`RenderedView` (image, depth, stats, worker), or the zarr group.
    """
    cams = [_camera(c, i) for i, c in enumerate(cameras)]
    w, h = int(width), int(height)
    data, key = _pickled(scene_spec)
    if store is not None:
        import zarr

        g = zarr.open_group(store, mode="w")
        n = len(cams)
        g.create_array("image", shape=(n, h, w, 4), chunks=(1, h, w, 4), dtype="uint8")
        g.create_array("depth", shape=(n, h, w), chunks=(1, h, w), dtype="float32", fill_value=np.inf)
    c = _client(client)
    if c is None:
        out = [_render_one(data, key, cam, w, h, backend, render_options, store, i) for i, cam in enumerate(cams)]
    else:
        spec_f = c.scatter(data, broadcast=True, hash=False)
        futures = [
            c.submit(_render_one, spec_f, key, cam, w, h, backend, render_options, store, i, pure=False)
            for i, cam in enumerate(cams)
        ]
        out = c.gather(futures)
    if store is not None:
        g.attrs["stats"] = [dict(v.stats) for v in out]
        return g
    return out


def benchmark(
    n_workers: Sequence[int] = (1, 2),
    n_views: int = 16,
    size: int = 120,
    width: int = 320,
    height: int = 256,
    culling: str = "three_pass",
    say: Callable[[str], None] = print,
) -> list[dict[str, Any]]:
    """Frames per second of :func:`render_views` on a ``LocalCluster`` of 1, 2, ... worker
    processes (one thread each), the same scene and views for every cluster, side by side in one
    run: a warm-up call (the workers build the scene and their renderers), then a timed call.
    Returns one dict per cluster size: workers, views, seconds, frames_per_s, ratio_to_1 (against
    the first size)."""
    from distributed import Client, LocalCluster

    from .data import gullfaks_like, standard_views

    spec = gullfaks_like(nx=size, ny=size, n_faults=4, fault_triangles=(500, 5000))
    base = standard_views(spec, aspect=width / height)
    cams = [Camera.look_at(**base[i % len(base)][1]).rotated(7.0 * (i // len(base)), 0.0) for i in range(n_views)]
    rows: list[dict[str, Any]] = []
    for n in n_workers:
        with LocalCluster(n_workers=int(n), threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
                Client(cl) as client:
            render_views(spec, cams, client, width, height, culling=culling)  # warm-up: builds, pipelines
            t0 = time.perf_counter()
            render_views(spec, cams, client, width, height, culling=culling)
            dt = time.perf_counter() - t0
        rows.append(dict(workers=int(n), views=n_views, seconds=dt, frames_per_s=n_views / dt))
        say(f"distributed: {n} worker(s): {n_views} views of {width}x{height} in {dt:.2f} s, "
            f"{n_views / dt:.1f} frames/s")
    for r in rows:
        r["ratio_to_1"] = r["frames_per_s"] / rows[0]["frames_per_s"]
    return rows
