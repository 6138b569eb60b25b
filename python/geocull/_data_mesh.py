"""Pure-numpy triangles for :mod:`geocull.data` (which re-exports them): ``grid_faces`` (the faces of
any structured surface), ``heightfield_mesh`` (a height field's triangles, as the core makes them)
and ``MeshScene``, a stand-in for ``geocull.Scene`` that needs no extension."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._errors import InputError

__all__ = ["grid_faces", "heightfield_mesh", "MeshScene"]


def grid_faces(nu: int, nv: int) -> np.ndarray:
    """Faces of a structured surface: two triangles per cell of an ``nv`` rows × ``nu`` columns grid
    of vertices numbered row-major (vertex ``j*nu + i`` is column i of row j), e.g. a fault plane
    sampled as an (nv, nu, 3) array of points: ``scene.add_mesh(points.reshape(-1, 3),
    gc.data.grid_faces(nu, nv), kind="fault")``.

    Returns (2 * (nu-1) * (nv-1), 3) int64: for the cell with corner a = (j, i), b = (j, i+1),
    c = (j+1, i), d = (j+1, i+1), the triangles (a, b, d) then (a, d, c) (split along the a-d
    diagonal, counter-clockwise when i runs along +x and j along +y), cells in row-major order.
    The height-field triangulation of geocull and :func:`heightfield_mesh` is this one. A smooth mesh
    added with these faces (in any order or winding) over all ``nu * nv`` vertices shades every
    level of detail from its fine grid's normals, as height fields do.
    """
    nu, nv = int(nu), int(nv)
    if nu < 2 or nv < 2:
        raise InputError(f"nu, nv: a grid of {nu} x {nv} vertices has no cell; expected at least 2 x 2")
    j, i = np.meshgrid(np.arange(nv - 1), np.arange(nu - 1), indexing="ij")
    a = (j * nu + i).ravel()
    b = a + 1
    c = a + nu
    d = c + 1
    faces = np.empty((a.size * 2, 3), dtype=np.int64)
    faces[0::2] = np.stack([a, b, d], axis=1)
    faces[1::2] = np.stack([a, d, c], axis=1)
    return faces


def heightfield_mesh(
    z: ArrayLike,
    origin: ArrayLike = (0.0, 0.0),
    spacing: ArrayLike = (1.0, 1.0),
    rotation: float = 0.0,
    yflip: bool = False,
    drop_holes: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate a height field: every grid cell gives two triangles (split along the diagonal
    from sample (j, i) to (j+1, i+1)); triangles touching a NaN sample are dropped.

    Returns ``(vertices (ny*nx, 3) float64, faces (m, 3) int64)``; vertex ``j*nx + i`` is sample
    ``z[j, i]`` at ``(x0 + i*dx, y0 + j*dy)``, or with ``rotation`` / ``yflip`` (as for
    ``Scene.add_heightfield``) at ``(x0, y0) + R(rotation) @ (i*dx, ±j*dy)``, computed as the core
    does (exact at multiples of 90°). NaN samples stay in the vertex array, unreferenced, unless
    ``drop_holes``: then unreferenced vertices are dropped and the faces renumbered, so the result
    goes to ``Scene.add_mesh`` (which takes finite vertices only) as it is.
    """
    z = np.asarray(z, dtype=np.float64)
    if z.ndim != 2 or z.shape[0] < 2 or z.shape[1] < 2:
        raise InputError(f"z: expected a (ny, nx) array with ny, nx >= 2, got shape {z.shape}")
    ny, nx = z.shape
    o = np.asarray(origin, dtype=np.float64)
    sp = np.asarray(spacing, dtype=np.float64)
    r = float(rotation) % 360.0
    if r == 0.0 and not yflip:
        xs = o[0] + sp[0] * np.arange(nx)
        ys = o[1] + sp[1] * np.arange(ny)
        X, Y = np.meshgrid(xs, ys)
    else:
        exact = {0.0: (1.0, 0.0), 90.0: (0.0, 1.0), 180.0: (-1.0, 0.0), 270.0: (0.0, -1.0)}
        c, s = exact.get(r, (math.cos(math.radians(rotation)), math.sin(math.radians(rotation))))
        U, W = np.meshgrid(np.arange(nx) * sp[0], np.arange(ny) * (-sp[1] if yflip else sp[1]))
        X, Y = o[0] + (c * U - s * W), o[1] + (s * U + c * W)
    v = np.stack([X.ravel(), Y.ravel(), z.ravel()], axis=1)
    f = grid_faces(nx, ny)
    ok = np.isfinite(z.ravel())
    keep = ok[f].all(axis=1)
    f = f if keep.all() else f[keep]
    if drop_holes and not ok.all():
        used = np.unique(f)
        remap = np.full(len(v), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        return v[used], remap[f]
    return v, f


class MeshScene:
    """A minimal pure-numpy stand-in for ``geocull.Scene``: enough for :mod:`geocull.pyvista`
    (``geometry``, ``object_ids``, ``object_info``) and for building test scenes without the
    extension. Height fields are triangulated with :func:`heightfield_mesh`."""

    def __init__(self) -> None:
        self._objects: dict[int, tuple[np.ndarray, np.ndarray, dict[str, Any]]] = {}
        self._next = 0

    def add_mesh(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        kind: str = "fault",
        tiles: int | None = None,
        coarse_factor: float = 1.0,
        name: str | None = None,
        color: ArrayLike | None = None,
    ) -> int:
        """Add a mesh: vertices (n, 3) world coordinates (metres), faces (m, 3) indices in [0, n); color
        (r, g, b) in [0, 1]. ``tiles`` and ``coarse_factor`` are accepted for ``geocull.Scene.add_mesh``
        compatibility and ignored. Returns the id."""
        v = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64).reshape(-1, 3))
        f = np.ascontiguousarray(np.asarray(faces, dtype=np.int64).reshape(-1, 3))
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            raise InputError("faces: index out of range")
        oid = self._next
        self._next += 1
        rgb = (0.8, 0.8, 0.8) if color is None else tuple(float(c) for c in np.asarray(color).ravel())
        info = dict(name=name if name is not None else f"object_{oid}", kind=kind, color=rgb)
        self._objects[oid] = (v, f, info)
        return oid

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
    ) -> int:
        """Add a height field: z (ny, nx) heights (metres; NaN or ``null_value`` = holes), origin (x0, y0),
        spacing (dx, dy) in metres, rotation and yflip as for ``geocull.Scene.add_heightfield``;
        triangulated with :func:`heightfield_mesh`. ``tiles`` and ``coarse_factor`` are ignored.
        Returns the id."""
        zz = np.array(z, dtype=np.float64)
        if null_value is not None:
            zz[zz == null_value] = np.nan
        v, f = heightfield_mesh(zz, origin, spacing, rotation=rotation, yflip=yflip)
        return self.add_mesh(v, f, kind="horizon", name=name, color=color)

    def geometry(self, object_id: int) -> tuple[np.ndarray, np.ndarray]:
        """vertices (n, 3) float64 world coordinates (metres) and faces (m, 3) int64 of an object."""
        v, f, _ = self._objects[object_id]
        return v, f

    def object_ids(self) -> list[int]:
        """Ids of the objects, in the order they were added."""
        return list(self._objects)

    def object_info(self, object_id: int) -> dict[str, Any]:
        """name, kind and color (r, g, b) of an object."""
        return dict(self._objects[object_id][2])

    @property
    def n_triangles(self) -> int:
        """Triangles over all objects."""
        return int(sum(len(f) for _, f, _ in self._objects.values()))
