"""Scene generators and offline sample data.

Everything here is pure numpy (vectorised, seeded) and works without the compiled extension;
only :meth:`SceneSpec.build` imports :mod:`geocull` (lazily) to turn a spec into a ``Scene``.

Generators
----------
``gullfaks_like``        a Gullfaks-like stack of horizons crossed by steep faults (the benchmark scene)
``stacked_test_scene``   the same, small enough for unit tests
``standard_views``       a fixed set of camera arguments around a scene's bounds
``pesco_synthetic``      the analytic volume of Pesco et al. (isosurface tests)
``jacksboro_dem``        a real DEM shipped with matplotlib (metres)
``topobathy``            a real topography/bathymetry grid shipped with matplotlib (metres)
``faulted_grid``         a corner-point reservoir grid: a normal fault, a pinch-out, erosion, regions

Helpers: ``heightfield_mesh`` (a height field's triangles), ``grid_faces`` (the faces of any
structured surface, e.g. a fault plane), ``depth_colormap``.

Conventions: a height field ``z`` has shape ``(ny, nx)``; column ``i`` is at ``x = x0 + i*dx``, row
``j`` at ``y = y0 + j*dy`` (row 0 is the southern edge); NaN marks a hole. Colours are RGB floats
in [0, 1]. Bounds are ``(xmin, xmax, ymin, ymax, zmin, zmax)`` as in PyVista.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ._data_mesh import MeshScene, grid_faces, heightfield_mesh
from ._errors import InputError
from ._progress import ProgressLike

if TYPE_CHECKING:
    from .scene import Scene

__all__ = [
    "SceneSpec",
    "gullfaks_like",
    "stacked_test_scene",
    "standard_views",
    "pesco_synthetic",
    "jacksboro_dem",
    "topobathy",
    "depth_colormap",
    "heightfield_mesh",
    "grid_faces",
    "MeshScene",
    "faulted_grid",
]

# Anchor colours (depth fraction 0 = shallowest, 1 = deepest) of a "geological" colormap:
# yellow sands → orange → red-brown → purple → deep blue. Interpolated linearly in RGB.
_DEPTH_CMAP = np.array(
    [
        [0.00, 0.99, 0.91, 0.55],
        [0.25, 0.96, 0.63, 0.27],
        [0.50, 0.80, 0.33, 0.22],
        [0.75, 0.52, 0.22, 0.47],
        [1.00, 0.18, 0.25, 0.60],
    ]
)

_FAULT_COLORS = np.array(
    [
        [0.85, 0.10, 0.10],
        [0.95, 0.35, 0.20],
        [0.70, 0.05, 0.25],
        [0.90, 0.20, 0.45],
    ]
)


def depth_colormap(t: float | np.ndarray) -> np.ndarray:
    """RGB colour(s) in [0, 1] for depth fraction(s) ``t`` in [0, 1] (0 = shallowest)."""
    t = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0)
    rgb = np.stack([np.interp(t, _DEPTH_CMAP[:, 0], _DEPTH_CMAP[:, c]) for c in (1, 2, 3)], axis=-1)
    return rgb


@dataclass
class SceneSpec:
    """A scene as plain numpy data: height-field horizons and triangle-mesh faults.

    ``horizons``: list of dicts ``z`` ((ny, nx) float64, NaN = hole), ``origin`` (x0, y0),
    ``spacing`` (dx, dy), ``name``, ``color``.
    ``faults``: list of dicts ``vertices`` ((n, 3) float64), ``faces`` ((m, 3) int64), ``name``, ``color``.
    ``bounds``: (xmin, xmax, ymin, ymax, zmin, zmax) over all finite geometry.
    """

    horizons: list[dict[str, Any]] = field(default_factory=list)
    faults: list[dict[str, Any]] = field(default_factory=list)
    bounds: tuple[float, float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def n_horizon_triangles(self) -> int:
        """Triangles of the horizons: two per grid cell, split along the (j, i)–(j+1, i+1) diagonal,
        less those touching a NaN sample (the rule of :func:`heightfield_mesh`; geocull's
        ``Scene.n_triangles`` gives the same count)."""
        total = 0
        for h in self.horizons:
            f = np.isfinite(h["z"])
            a, b, c, d = f[:-1, :-1], f[:-1, 1:], f[1:, :-1], f[1:, 1:]
            total += int(np.count_nonzero(a & b & d)) + int(np.count_nonzero(a & d & c))
        return total

    @property
    def n_fault_triangles(self) -> int:
        """Total triangles of the faults."""
        return int(sum(len(f["faces"]) for f in self.faults))

    @property
    def n_triangles(self) -> int:
        """Total triangles (see :attr:`n_horizon_triangles` for how holes are counted)."""
        return self.n_horizon_triangles + self.n_fault_triangles

    def mesh_scene(self) -> MeshScene:
        """The spec as a :class:`MeshScene` (pure numpy, no extension), e.g. for PyVista renders."""
        ms = MeshScene()
        for h in self.horizons:
            ms.add_heightfield(h["z"], origin=h["origin"], spacing=h["spacing"], name=h["name"], color=h["color"])
        for f in self.faults:
            ms.add_mesh(f["vertices"], f["faces"], kind="fault", name=f["name"], color=f["color"])
        return ms

    def build(
        self,
        tiles: tuple[int, int] = (10, 10),
        coarse_factor: float = 25,
        fault_tiles: int | None = None,
        fault_coarse_factor: float = 10,
        progress: ProgressLike = None,
    ) -> Scene:
        """Create a :class:`geocull.Scene` holding every horizon and fault of this spec.

        Horizons go in with ``add_heightfield(tiles=tiles, coarse_factor=coarse_factor)``, faults with
        ``add_mesh(kind="fault", tiles=fault_tiles, coarse_factor=fault_coarse_factor)``; object ids
        follow the order horizons first, then faults. progress: as for
        :meth:`geocull.Scene.add_heightfield`, over the whole build (objects weighted by their
        triangles, each reporting its tiles as they are built).
        """
        import geocull  # lazy: the spec itself needs no extension

        from . import _progress

        weights = [2.0 * np.asarray(h["z"]).size for h in self.horizons] + [float(len(f["faces"])) for f in self.faults]
        scene = geocull.Scene()
        with _progress.task(progress, sum(weights), "SceneSpec.build") as task:

            def part(k: int, done: float) -> _progress.ProgressLike:
                """The progress of object k, mapped into the build's (False when nothing shows)."""
                if not task.enabled:
                    return False
                msg = f"SceneSpec.build: object {k + 1}/{len(weights)}"
                return lambda f, _m: task.update(done + f * weights[k], msg)

            done = 0.0
            for k, h in enumerate(self.horizons):
                scene.add_heightfield(
                    h["z"],
                    origin=tuple(h["origin"]),
                    spacing=tuple(h["spacing"]),
                    tiles=tuple(tiles),
                    coarse_factor=coarse_factor,
                    name=h["name"],
                    color=tuple(h["color"]),
                    progress=part(k, done),
                )
                done += weights[k]
            for k, f in enumerate(self.faults, start=len(self.horizons)):
                scene.add_mesh(
                    f["vertices"],
                    f["faces"],
                    kind="fault",
                    tiles=fault_tiles,
                    coarse_factor=fault_coarse_factor,
                    name=f["name"],
                    color=tuple(f["color"]),
                    progress=part(k, done),
                )
                done += weights[k]
        return scene


def _smooth_field(rng: np.random.Generator, X: np.ndarray, Y: np.ndarray, extent: float, amplitude: float):
    """A smooth random surface: a few long-wavelength sinusoids plus gaussian domes and basins."""
    f = np.zeros_like(X)
    for _ in range(3):
        wavelength = extent * rng.uniform(0.4, 1.5)
        theta = rng.uniform(0, np.pi)
        phase = rng.uniform(0, 2 * np.pi)
        k = 2 * np.pi / wavelength
        f += rng.uniform(0.2, 0.5) * amplitude * np.sin(k * (X * np.cos(theta) + Y * np.sin(theta)) + phase)
    for _ in range(4):
        cx, cy = rng.uniform(0.1, 0.9, size=2) * extent
        r = extent * rng.uniform(0.08, 0.25)
        f += rng.uniform(-1.0, 1.0) * amplitude * np.exp(-((X - cx) ** 2 + (Y - cy) ** 2) / (2 * r * r))
    return f


def gullfaks_like(
    nx: int = 418,
    ny: int = 418,
    n_horizons: int = 11,
    n_faults: int = 16,
    spacing: float = 25.0,
    separation: float = 40.0,
    fault_triangles: tuple[int, int] = (2000, 20000),
    seed: int = 0,
    origin: tuple[float, float] = (451000.0, 6780000.0),
    depth: float = -1800.0,
    holes: bool = True,
) -> SceneSpec:
    """A Gullfaks-like subsurface model: stacked horizons crossed by steep faults.

    Horizons are ``ny × nx`` height fields at UTM-sized coordinates (``origin``, ``spacing`` metres);
    the top one undulates about ``depth`` (±≈100 m) and each next one lies ``separation`` metres
    deeper with its own small (< separation/4) variation, so horizons never cross. When ``holes`` is
    true, every third horizon (starting with the second) has 1–3 elliptical NaN holes. Colours run
    along :func:`depth_colormap`.

    Faults are regular grid meshes with steep dip (60–80°), random strike and position, slightly
    listric (dip decreasing with depth) and gently warped along strike; each spans the whole horizon
    stack vertically (poking ``separation/2`` above and below it), is shortened along strike until it
    lies inside the horizons' footprint, and has between ``fault_triangles[0]`` and ``fault_triangles[1]`` triangles
    (drawn log-uniformly).

    With the defaults (11 horizons of 418×418, 16 faults) the scene has about 3.9 M triangles, as
    the Gullfaks scene of the seeds: 11·2·417² = 3.83 M horizon triangles less ≈ 0.02–0.03 M in
    holes, plus ≈ 0.1–0.15 M fault triangles (seed 0: 3 913 412 in all; ``spec.n_triangles`` gives
    the exact number). Building it takes about 0.5 s on 2 cores.
    """
    if nx < 2 or ny < 2:
        raise InputError(f"nx, ny: need at least 2 samples each, got nx={nx}, ny={ny}")
    if n_horizons < 0 or n_faults < 0:
        raise InputError("n_horizons, n_faults: must be >= 0")
    lo, hi = int(fault_triangles[0]), int(fault_triangles[1])
    if lo < 2 or hi < lo:
        raise InputError(f"fault_triangles: expected (lo, hi) with 2 <= lo <= hi, got {fault_triangles}")

    rng = np.random.default_rng(seed)
    x0, y0 = float(origin[0]), float(origin[1])
    dx = dy = float(spacing)
    Lx, Ly = (nx - 1) * dx, (ny - 1) * dy
    extent = max(Lx, Ly)
    xs = np.arange(nx) * dx
    ys = np.arange(ny) * dy
    X, Y = np.meshgrid(xs, ys)  # (ny, nx), local coordinates

    base = depth + _smooth_field(rng, X, Y, extent, amplitude=100.0)
    horizons: list[dict[str, Any]] = []
    for k in range(n_horizons):
        var = _smooth_field(rng, X, Y, extent, amplitude=separation * 0.12)
        var = np.clip(var, -separation * 0.24, separation * 0.24)
        z = base - k * separation + var
        if holes and k % 3 == 1:
            for _ in range(int(rng.integers(1, 4))):
                cx, cy = rng.uniform(0.15, 0.85) * Lx, rng.uniform(0.15, 0.85) * Ly
                a, b = rng.uniform(0.03, 0.08) * extent, rng.uniform(0.02, 0.06) * extent
                th = rng.uniform(0, np.pi)
                u = (X - cx) * np.cos(th) + (Y - cy) * np.sin(th)
                v = -(X - cx) * np.sin(th) + (Y - cy) * np.cos(th)
                z[(u / a) ** 2 + (v / b) ** 2 < 1.0] = np.nan
        t = k / max(n_horizons - 1, 1)
        horizons.append(
            dict(
                z=z,
                origin=(x0, y0),
                spacing=(dx, dy),
                name=f"horizon_{k:02d}",
                color=tuple(float(c) for c in depth_colormap(t)),
            )
        )

    # Vertical range the faults must cross: the whole stack plus a margin.
    if n_horizons:
        ztop = max(float(np.nanmax(h["z"])) for h in horizons) + 0.5 * separation
        zbot = min(float(np.nanmin(h["z"])) for h in horizons) - 0.5 * separation
    else:
        ztop, zbot = depth + 100.0, depth - 100.0
    zspan = ztop - zbot

    faults: list[dict[str, Any]] = []
    for m in range(n_faults):
        strike = rng.uniform(0, 2 * np.pi)  # azimuth clockwise from north (+y)
        dip = np.radians(rng.uniform(60.0, 80.0))
        length = extent * rng.uniform(0.25, 0.7)
        cx = x0 + rng.uniform(0.2, 0.8) * Lx
        cy = y0 + rng.uniform(0.2, 0.8) * Ly
        width = zspan / np.sin(dip)  # down-dip extent
        target = math.exp(rng.uniform(math.log(lo), math.log(hi)))
        aspect = length / width
        nv1 = max(1, int(round(math.sqrt(target / 2.0 / aspect))))
        nu1 = max(1, int(round(target / 2.0 / nv1)))
        while 2 * nu1 * nv1 < lo:
            nu1 += 1
        while 2 * nu1 * nv1 > hi and nu1 > 1:
            nu1 -= 1
        while 2 * nu1 * nv1 > hi and nv1 > 1:
            nv1 -= 1
        nu, nv = nu1 + 1, nv1 + 1

        s = np.array([np.sin(strike), np.cos(strike), 0.0])  # along strike
        h = np.array([np.cos(strike), -np.sin(strike), 0.0])  # horizontal, towards the dip direction
        w = np.linspace(0.0, 1.0, nv)  # 0 = top, 1 = bottom
        wave_k, wave_phase = rng.uniform(1.0, 2.5), rng.uniform(0, np.pi)

        # shorten the fault until it lies inside the horizons' footprint
        for _ in range(40):
            # the fault's (nv, nu) grid of vertices at this length
            U, Wf = np.meshgrid(np.linspace(-0.5, 0.5, nu) * length, w)  # (nv, nu)
            # listric: the dip flattens by up to 8° towards the bottom (offset ~ ∫cot(dip) dz)
            dip_local = dip - np.radians(8.0) * Wf**2
            horiz = (zspan * Wf) / np.tan(0.5 * (dip + dip_local))
            horiz = horiz - (zspan * 0.5) / np.tan(dip)  # centred on (cx, cy) at mid depth
            warp = 0.02 * length * np.sin(np.pi * (U / length + 0.5) * wave_k + wave_phase)
            off = horiz + warp * (1.0 - (2.0 * U / length) ** 2)  # warp vanishes at the tips
            grid = np.empty((nv, nu, 3))
            grid[..., 0] = cx + U * s[0] + off * h[0]
            grid[..., 1] = cy + U * s[1] + off * h[1]
            grid[..., 2] = ztop - Wf * zspan
            V = grid.reshape(-1, 3)
            inside = (
                (V[:, 0] >= x0) & (V[:, 0] <= x0 + Lx) & (V[:, 1] >= y0) & (V[:, 1] <= y0 + Ly)
            ).all()
            if inside:
                break
            length *= 0.9
        faults.append(
            dict(
                vertices=V,
                faces=grid_faces(nu, nv),
                name=f"fault_{m:02d}",
                color=tuple(float(c) for c in _FAULT_COLORS[m % len(_FAULT_COLORS)]),
            )
        )
    return SceneSpec(horizons=horizons, faults=faults, bounds=_spec_bounds(horizons, faults))


def _spec_bounds(horizons, faults) -> tuple[float, float, float, float, float, float]:
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for h in horizons:
        z = h["z"]
        if not np.isfinite(z).any():
            continue
        ny, nx = z.shape
        x0, y0 = h["origin"]
        dx, dy = h["spacing"]
        xe = (x0, x0 + (nx - 1) * dx)
        ye = (y0, y0 + (ny - 1) * dy)
        lo = np.minimum(lo, [min(xe), min(ye), np.nanmin(z)])
        hi = np.maximum(hi, [max(xe), max(ye), np.nanmax(z)])
    for f in faults:
        v = f["vertices"]
        if len(v):
            lo = np.minimum(lo, v.min(axis=0))
            hi = np.maximum(hi, v.max(axis=0))
    if not np.all(np.isfinite(lo)):
        return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    return (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]), float(lo[2]), float(hi[2]))


def stacked_test_scene(n: int = 64, n_horizons: int = 3, with_faults: bool = True, seed: int = 0) -> SceneSpec:
    """A small Gullfaks-like spec for tests: ``n × n`` horizons (25 m spacing, 40 m apart, one with
    a hole when ``n_horizons >= 2``) and, if ``with_faults``, two faults of 50–200 triangles."""
    return gullfaks_like(
        nx=n,
        ny=n,
        n_horizons=n_horizons,
        n_faults=2 if with_faults else 0,
        fault_triangles=(50, 200),
        seed=seed,
    )


def _bounds_of(spec_or_bounds) -> np.ndarray:
    b = getattr(spec_or_bounds, "bounds", spec_or_bounds)
    b = np.asarray(b, dtype=np.float64).ravel()
    if b.shape != (6,) or not np.all(np.isfinite(b)):
        raise InputError(
            "spec_or_bounds: expected a SceneSpec or finite bounds (xmin, xmax, ymin, ymax, zmin, zmax), "
            f"got {spec_or_bounds!r}"
        )
    return b


def standard_views(
    spec_or_bounds: SceneSpec | Sequence[float],
    fov_y: float = 45.0,
    z_scale: float = 1.0,
    aspect: float = 1.25,
) -> list[tuple[str, dict[str, Any]]]:
    """Camera arguments (for ``Camera.look_at(**kwargs)``) for a fixed set of views of a scene.

    Every view looks at the centre of the bounds from the nearest distance at which all eight
    corners of the bounding box fit a ``fov_y`` × (``aspect``-wide) perspective view, plus 5 %.
    Azimuth is measured clockwise from north (+y), elevation above the horizontal. The views:

    ``oblique_az045``, ``oblique_az135``, ``oblique_az225``, ``oblique_az315`` (elevation 30°),
    ``steep_az045`` (60°), ``low_az200`` (5°, from outside the scene), ``top_down`` (90°, north up).

    With ``z_scale`` ≠ 1 the views are framed for the exaggerated scene; eye and target are still
    given in world coordinates (the renderer scales them with the scene) and ``z_scale`` is passed
    through in the kwargs.
    """
    b = _bounds_of(spec_or_bounds)
    lo, hi = b[0::2].copy(), b[1::2].copy()
    s = float(z_scale)
    zs = sorted((lo[2] * s, hi[2] * s))
    lo[2], hi[2] = zs
    centre = 0.5 * (lo + hi)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) - centre
    ty = math.tan(math.radians(fov_y) / 2.0)
    tx = ty * float(aspect)

    def view(az: float, el: float) -> dict[str, Any]:
        a, e = math.radians(az), math.radians(el)
        d = np.array([math.sin(a) * math.cos(e), math.cos(a) * math.cos(e), math.sin(e)])  # target → eye
        if el >= 89.999:
            up = np.array([0.0, 1.0, 0.0])
        else:
            up = np.array([0.0, 0.0, 1.0])
        fwd = -d
        right = np.cross(fwd, up)
        right /= np.linalg.norm(right)
        cam_up = np.cross(right, fwd)
        # corner c at view depth dist - c·d must satisfy |c·right| <= depth·tx, |c·up| <= depth·ty
        along = corners @ d
        need = np.maximum(np.abs(corners @ right) / tx, np.abs(corners @ cam_up) / ty) + along
        dist = 1.05 * max(float(need.max()), 1e-6)
        eye = centre + dist * d
        kw: dict[str, Any] = dict(
            eye=(float(eye[0]), float(eye[1]), float(eye[2]) / s),
            target=(float(centre[0]), float(centre[1]), float(centre[2]) / s),
            up=tuple(float(u) for u in up),
            fov_y=float(fov_y),
        )
        if s != 1.0:
            kw["z_scale"] = s
        return kw

    views = [(f"oblique_az{az:03d}", view(az, 30.0)) for az in (45, 135, 225, 315)]
    views.append(("steep_az045", view(45, 60.0)))
    views.append(("low_az200", view(200, 5.0)))
    views.append(("top_down", view(0, 90.0)))
    return views


def pesco_synthetic(n: int = 64) -> tuple[np.ndarray, tuple[float, float, float], tuple[float, float, float]]:
    """The synthetic volume of Pesco et al.: f(x, y, z) = sin(xyz/8) + cos((x-2)(y-2)(z-2)).

    Sampled on an ``n³`` grid over [-5, 5]³. Returns ``(values, origin, spacing)`` with
    ``values[k, j, i] = f(x_i, y_j, z_k)`` (float32), ``x_i = origin[0] + i*spacing[0]`` etc.
    """
    if n < 2:
        raise InputError(f"n: need at least 2 samples per axis, got {n}")
    h = 10.0 / (n - 1)
    c = -5.0 + h * np.arange(n)
    z = c[:, None, None]
    y = c[None, :, None]
    x = c[None, None, :]
    vals = np.sin(x * y * z / 8.0) + np.cos((x - 2.0) * (y - 2.0) * (z - 2.0))
    return vals.astype(np.float32), (-5.0, -5.0, -5.0), (h, h, h)


_M_PER_DEG = math.pi * 6371008.8 / 180.0  # metres per degree of latitude on the mean sphere


def jacksboro_dem() -> tuple[np.ndarray, tuple[float, float], tuple[float, float]]:
    """matplotlib's Jacksboro fault DEM (Tennessee, 3-arc-second SRTM) as a height field in metres.

    Returns ``(z, origin, spacing)``: ``z`` (344, 403) float64 elevations in metres with row 0 the
    southern edge, ``origin = (0, 0)`` at the south-west corner, ``spacing`` = (dx, dy) in metres
    from the degree spacing with a local equirectangular approximation (dx scaled by the cosine
    of the mean latitude).
    """
    from matplotlib import cbook

    d: Any = cbook.get_sample_data("jacksboro_fault_dem.npz")  # an NpzFile; matplotlib types it ndarray | IO
    elev = np.asarray(d["elevation"], dtype=np.float64)
    # The raster is stored north-up (row 0 = northern edge; the file's 'ymin' key holds that row's
    # latitude): flip so rows run south → north.
    lat0 = 0.5 * (float(d["ymin"]) + float(d["ymax"]))
    dx = float(d["dx"]) * _M_PER_DEG * math.cos(math.radians(lat0))
    dy = float(d["dy"]) * _M_PER_DEG
    return np.ascontiguousarray(elev[::-1]), (0.0, 0.0), (dx, dy)


def topobathy() -> tuple[np.ndarray, tuple[float, float], tuple[float, float]]:
    """matplotlib's topography/bathymetry sample (Pacific north-west, 91×120) in metres.

    Returns ``(z, origin, spacing)`` like :func:`jacksboro_dem` (row 0 = south, origin (0, 0) at
    the south-west corner, spacing in metres from the mean degree steps).
    """
    from matplotlib import cbook

    d: Any = cbook.get_sample_data("topobathy.npz")  # an NpzFile; matplotlib types it ndarray | IO
    z = np.asarray(d["topo"], dtype=np.float64)
    lon = np.asarray(d["longitude"], dtype=np.float64)
    lat = np.asarray(d["latitude"], dtype=np.float64)
    if lat[-1] < lat[0]:
        z, lat = z[::-1], lat[::-1]
    if lon[-1] < lon[0]:
        z, lon = z[:, ::-1], lon[::-1]
    lat0 = 0.5 * (lat[0] + lat[-1])
    dlon = (lon[-1] - lon[0]) / (len(lon) - 1)
    dlat = (lat[-1] - lat[0]) / (len(lat) - 1)
    dx = dlon * _M_PER_DEG * math.cos(math.radians(lat0))
    dy = dlat * _M_PER_DEG
    return np.ascontiguousarray(z), (0.0, 0.0), (float(dx), float(dy))


def faulted_grid(
    ni: int = 100,
    nj: int = 100,
    nk: int = 100,
    throw: float = 7.5,
    seed: int = 0,
    spacing: tuple[float, float] = (50.0, 50.0),
    thickness: float = 2.0,
) -> dict[str, np.ndarray]:
    """A layered corner-point reservoir grid (Jia et al.'s test case, synthetic): nk layers of
    mean ``thickness`` metres under a smooth top near z = -1500 m, on vertical pillars
    ``spacing`` metres apart, with

    - a normal fault: the columns i >= ni // 2 are thrown down by ``throw`` metres in the middle of
      the fault, tapering to 0.6 x ``throw`` at its ends (j = 0 and j = nj), so the layers of the
      two blocks cross each other along it (choose a throw that is not a multiple of the layer
      thickness to see partial overlaps);
    - a pinch-out zone: layer nk // 2 thins to zero thickness towards x = 0 (zero for x <= 20 % of
      the grid's length, full from 40 %): fully collapsed cells there, wedge cells with collapsed
      corners in between;
    - an erosional truncation: an unconformity cuts the top layers down by up to 3 layers towards
      +y (its corners are clamped to the erosion surface);
    - inactive cells: those collapsed by the pinch-out or the erosion, the deepest fifth of the
      layers in the quarter i < ni / 4 (below a contact), and 0.2 % at random;
    - four regions: 1 + (fault block, i >= ni // 2) + 2 (layers k >= nk // 2);
    - a porosity-like property (0.1 .. 0.3, NaN in inactive cells).

    Returns ``dict(corners=(nk, nj, ni, 8, 3) float64 world x, y, z (z up, metres),
    active=(nk, nj, ni) bool, region=(nk, nj, ni) int32, values=(nk, nj, ni) float64)`` in the
    corner order of :mod:`geocull.grid` (corner c: i-bit c & 1, j-bit (c >> 1) & 1, k-bit (c >> 2)
    & 1, k = 0 the top). Deterministic for a given ``seed``.
    """
    if ni < 2 or nj < 1 or nk < 2:
        raise InputError(f"ni, nj, nk: ({ni}, {nj}, {nk}); need ni >= 2, nj >= 1, nk >= 2")
    rng = np.random.default_rng(seed)
    dx, dy = float(spacing[0]), float(spacing[1])
    lx, ly = ni * dx, nj * dy
    X, Y = np.meshgrid(np.arange(ni + 1) * dx, np.arange(nj + 1) * dy)  # pillars, (nj+1, ni+1)
    extent = max(lx, ly)
    top = -1500.0 + _smooth_field(rng, X, Y, extent, amplitude=0.15 * nk * thickness)
    # Layer thicknesses at the pillars, (nk, nj+1, ni+1): a gentle lateral variation per layer.
    phase = rng.uniform(0, 2 * np.pi, size=(nk, 1, 1))
    th = thickness * (1.0 + 0.25 * np.sin(2 * np.pi * X[None] / extent + phase) * np.cos(2 * np.pi * Y[None] / extent))
    kp = nk // 2
    th[kp] *= np.clip((X - 0.2 * lx) / (0.2 * lx), 0.0, 1.0)
    H = top[None] - np.concatenate([np.zeros((1,) + X.shape), np.cumsum(th, axis=0)])  # (nk+1, nj+1, ni+1)
    cb = np.arange(8)
    K = np.arange(nk)[:, None, None, None] + ((cb >> 2) & 1)
    J = np.arange(nj)[None, :, None, None] + ((cb >> 1) & 1)
    ic = np.arange(ni)[None, None, :, None] + (cb & 1)
    z = H[K, J, ic]  # (nk, nj, ni, 8)
    i_f = ni // 2
    taper = 0.6 + 0.4 * np.sin(np.pi * np.arange(nj + 1) / max(nj, 1))  # per pillar row
    hanging = (np.arange(ni) >= i_f)[None, None, :, None]
    z = z - hanging * (throw * taper)[J]
    # Erosion after faulting: an unconformity down to 3 layers below the top towards +y.
    above = top.max() + 1.0
    erosion = above - (above - top + 3.0 * thickness) * np.clip((Y - 0.4 * ly) / (0.6 * ly), 0.0, 1.0)
    erosion = np.where(Y <= 0.4 * ly, np.inf, erosion)
    z = np.minimum(z, erosion[J, ic])
    corners = np.empty((nk, nj, ni, 8, 3))
    corners[..., 0] = X[J, ic]
    corners[..., 1] = Y[J, ic]
    corners[..., 2] = z
    collapsed = np.all(z[..., :4] == z[..., 4:], axis=-1)
    kk, jj, ii = np.meshgrid(np.arange(nk), np.arange(nj), np.arange(ni), indexing="ij")
    active = ~collapsed & ~((kk >= nk - max(1, nk // 5)) & (ii < ni / 4)) & (rng.random((nk, nj, ni)) >= 0.002)
    region = (1 + (ii >= i_f) + 2 * (kk >= kp)).astype(np.int32)
    xc, yc = corners[..., 0].mean(axis=-1), corners[..., 1].mean(axis=-1)
    values = 0.2 + 0.05 * np.sin(kk / 3.0) + 0.04 * np.sin(2 * np.pi * xc / extent) * np.cos(2 * np.pi * yc / extent)
    values = values + rng.normal(0.0, 0.01, size=values.shape)
    values = np.where(active, np.clip(values, 0.1, 0.3), np.nan)
    return {"corners": corners, "active": active, "region": region, "values": values}
