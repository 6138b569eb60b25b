"""The camera: a look-at view in world coordinates (f64), perspective or orthographic.

Besides :meth:`Camera.look_at`, cameras are made by :meth:`Camera.orbit` (a target, a compass
azimuth, an elevation and a distance), :meth:`Camera.fit` (the closest view of a scene's bounds from
given angles) and :meth:`Camera.from_pyvista`; :meth:`Camera.zoomed` and :meth:`Camera.rotated`
return moved copies, :meth:`Camera.to_pyvista` gives PyVista's ``camera_position``.

Angles are degrees. ``azimuth`` is the compass bearing of the eye seen from the target, clockwise
from north (+y) seen from above: 0 puts the eye north of the target (+y) looking south, 90 east (+x)
looking west. ``elevation`` is the eye's angle above the horizontal plane through the target, in
[-90, 90] (90 = looking straight down). Orbits are laid out in render space (z multiplied by
``z_scale``), so the elevation and the distance are those seen in the exaggerated image.
"""

from __future__ import annotations

from typing import Any, Literal, Protocol, cast

import numpy as np
from numpy.typing import ArrayLike

from . import _convert as cv
from . import _geocull
from ._errors import InputError

__all__ = ["Camera", "Projection", "Bounds", "HasBounds"]

#: ``((xmin, ymin, zmin), (xmax, ymax, zmax))`` world coordinates (metres), as :attr:`Scene.bounds`.
Bounds = tuple[tuple[float, float, float], tuple[float, float, float]]


class HasBounds(Protocol):
    """What :meth:`Camera.fit` frames besides a box: an object with ``bounds`` as
    :attr:`Scene.bounds` (a :class:`Scene`; None when it has no triangle)."""

    @property
    def bounds(self) -> Bounds | None: ...


#: The projections of :meth:`Camera.look_at`.
Projection = Literal["perspective", "orthographic"]


class Camera:
    """A look-at camera in world coordinates (metres, f64). Build it with :meth:`look_at`; its
    attributes (eye, target, up, fov_y, near, far, projection, ortho_height, z_scale) are read-only.
    Cameras are immutable (copies are the camera itself) and pickle as their attributes."""

    def __init__(self, inner: _geocull.Camera) -> None:
        self._c = inner

    @staticmethod
    def look_at(
        eye: ArrayLike,
        target: ArrayLike,
        up: ArrayLike = (0.0, 0.0, 1.0),
        fov_y: float = 45.0,
        near: float | None = None,
        far: float | None = None,
        projection: Projection = "perspective",
        ortho_height: float | None = None,
        z_scale: float = 1.0,
    ) -> Camera:
        """eye, target: (x, y, z) world points (metres); up: approximate up vector (if parallel to the
        view direction, e.g. looking straight down with up=z, another axis is used). fov_y: vertical
        field of view in degrees, (0, 180). near/far: clip distances along the view axis in world units
        (metres, exaggerated by z_scale; None = from the scene bounds). projection: "perspective" or
        "orthographic"; ortho_height: height of the orthographic view in world units (metres; None =
        what fov_y sees at the target). z_scale: vertical exaggeration, applied to the scene and to
        eye/target alike (z -> z * z_scale)."""
        if not isinstance(projection, str):
            raise InputError(f"projection: {projection!r} is not a string")
        inner = _geocull.Camera.look_at(
            cv.vec3(eye, "eye"), cv.vec3(target, "target"), cv.vec3(up, "up"), cv.number(fov_y, "fov_y"),
            None if near is None else cv.number(near, "near"), None if far is None else cv.number(far, "far"),
            projection, None if ortho_height is None else cv.number(ortho_height, "ortho_height"),
            cv.number(z_scale, "z_scale"),
        )
        return Camera(inner)

    @staticmethod
    def orbit(
        target: ArrayLike,
        azimuth: float = 0.0,
        elevation: float = 30.0,
        distance: float = 1.0,
        up: ArrayLike = (0.0, 0.0, 1.0),
        fov_y: float = 45.0,
        near: float | None = None,
        far: float | None = None,
        projection: Projection = "perspective",
        ortho_height: float | None = None,
        z_scale: float = 1.0,
    ) -> Camera:
        """A camera looking at ``target`` ((x, y, z), metres) from ``distance`` (> 0, render-space
        metres: z exaggerated by ``z_scale``) at compass bearing ``azimuth`` (degrees clockwise from
        north = +y: 0 = eye north of the target, 90 = east) and ``elevation`` (degrees above the
        horizontal, [-90, 90]; 90 = straight down, where an ``up`` along z gives way to +y as
        :meth:`look_at` says). In render space the eye is ``target + distance * (sin az cos el,
        cos az cos el, sin el)``. The other arguments are :meth:`look_at`'s."""
        if not isinstance(projection, str):
            raise InputError(f"projection: {projection!r} is not a string")
        return Camera(_geocull.Camera.orbit(
            cv.vec3(target, "target"), cv.number(azimuth, "azimuth"), cv.number(elevation, "elevation"),
            cv.number(distance, "distance"), cv.vec3(up, "up"), cv.number(fov_y, "fov_y"),
            None if near is None else cv.number(near, "near"), None if far is None else cv.number(far, "far"),
            projection, None if ortho_height is None else cv.number(ortho_height, "ortho_height"),
            cv.number(z_scale, "z_scale"),
        ))

    @staticmethod
    def fit(
        scene_or_bounds: HasBounds | Bounds | ArrayLike,
        azimuth: float = 30.0,
        elevation: float = 30.0,
        fov_y: float = 45.0,
        margin: float = 0.05,
        aspect: float = 1.0,
        up: ArrayLike = (0.0, 0.0, 1.0),
        projection: Projection = "perspective",
        z_scale: float = 1.0,
    ) -> Camera:
        """A camera looking at the centre of a box from ``azimuth`` / ``elevation`` (as in
        :meth:`orbit`), as close as it can stand with every corner of the box inside the view.

        scene_or_bounds: a :class:`Scene` (its :attr:`Scene.bounds`; InputError when it has no
        triangle) or ``((xmin, ymin, zmin), (xmax, ymax, zmax))`` (metres; any (2, 3) array).
        margin: in [0, 1), the fraction of the image's half-width and half-height left free around
        the box (0: the outermost corner touches the border). aspect: the image's width / height
        (> 0; ``renderer.width / renderer.height``), so that the box fits across too. Perspective:
        the eye stands at the smallest distance with all 8 corners inside the frustum shrunk by
        the margin; orthographic: ``ortho_height`` is the smallest that holds them and the eye
        stands twice the box's radius away. Laid out in render space (z exaggerated by ``z_scale``).
        near and far are left to the renderer (from the scene bounds)."""
        b = getattr(scene_or_bounds, "bounds", scene_or_bounds)
        if b is None:
            raise InputError("scene_or_bounds: the scene has no triangle, so there is nothing to frame")
        a = cv.float_array(b, "scene_or_bounds", 2, 3)
        if a.shape[0] != 2:
            raise InputError(
                f"scene_or_bounds: expected a Scene or ((xmin, ymin, zmin), (xmax, ymax, zmax)), got shape {a.shape}"
            )
        if not isinstance(projection, str):
            raise InputError(f"projection: {projection!r} is not a string")
        return Camera(_geocull.Camera.fit(
            cv.vec3(a[0], "scene_or_bounds[0]"), cv.vec3(a[1], "scene_or_bounds[1]"), cv.number(azimuth, "azimuth"),
            cv.number(elevation, "elevation"), cv.number(margin, "margin"), cv.number(aspect, "aspect"),
            cv.vec3(up, "up"), cv.number(fov_y, "fov_y"), projection, cv.number(z_scale, "z_scale"),
        ))

    @staticmethod
    def from_pyvista(
        camera_position: Any,
        fov_y: float = 30.0,
        projection: Projection = "perspective",
        ortho_height: float | None = None,
        z_scale: float = 1.0,
    ) -> Camera:
        """A camera from PyVista's ``plotter.camera_position``: ``[(eye), (focal point), (view up)]``
        (three 3-vectors, or a ``pyvista.CameraPosition``). PyVista's points are in its render space:
        for a plotter scaled with ``set_scale(zscale=z_scale)`` their z is divided by ``z_scale``.
        fov_y: the plotter's ``camera.view_angle`` (degrees; VTK's default is 30). For
        ``camera.parallel_projection``: ``projection="orthographic"``,
        ``ortho_height=2 * camera.parallel_scale``."""
        a = cv.float_array(list(camera_position), "camera_position", 2, 3)
        if a.shape[0] != 3:
            raise InputError(f"camera_position: expected [(eye), (focal point), (view up)], got shape {a.shape}")
        s = cv.number(z_scale, "z_scale")
        ex = np.array([1.0, 1.0, s if s > 0 else 1.0])  # z_scale's value is checked by look_at
        return Camera.look_at(a[0] / ex, a[1] / ex, a[2], fov_y, projection=projection,
                              ortho_height=ortho_height, z_scale=s)

    def to_pyvista(self) -> list[tuple[float, float, float]]:
        """``[(eye), (focal point), (view up)]`` for ``plotter.camera_position``, z multiplied by
        ``z_scale`` (for a plotter scaled with ``set_scale(zscale=z_scale)``), the view up made
        orthogonal to the view direction as VTK keeps it (the axis the image's up follows, including
        the straight-down case). Set ``plotter.camera.view_angle = camera.fov_y`` too (VTK's default
        is 30 degrees). ``Camera.from_pyvista(c.to_pyvista(), fov_y=c.fov_y)`` renders as ``c``."""
        v = self.view_matrix()  # rows 0..2: right, up, -forward in exaggerated world coordinates
        ex = np.array([1.0, 1.0, self.z_scale])
        eye, target = np.asarray(self.eye) * ex, np.asarray(self.target) * ex
        return [_t3(eye), _t3(target), _t3(v[1, :3])]

    def orbit_angles(self) -> tuple[float, float, float]:
        """``(azimuth, elevation, distance)`` of the eye about the target, as :meth:`orbit` takes them
        (degrees in [0, 360), degrees, render-space metres); azimuth 0 when the eye is straight
        above or below the target."""
        return self._c.orbit_angles()

    def rotated(self, d_azimuth: float = 0.0, d_elevation: float = 0.0) -> Camera:
        """This camera orbited about its target: azimuth + ``d_azimuth`` (degrees, clockwise seen from
        above), elevation + ``d_elevation`` (degrees, the result clamped to [-90, 90]); distance and
        every other setting kept. (At elevation +-90 the azimuth is lost: keep it yourself, as
        :class:`geocull.Viewer` does, and use :meth:`orbit`.)"""
        return Camera(self._c.rotated(cv.number(d_azimuth, "d_azimuth"), cv.number(d_elevation, "d_elevation")))

    def zoomed(self, factor: float) -> Camera:
        """This camera with ``factor`` times the magnification (> 0; 2 = twice as large): perspective
        views move the eye towards the target (distance / factor); orthographic ones divide the view
        height (``ortho_height``, or what fov_y sees at the target when None) and keep the eye."""
        return Camera(self._c.zoomed(cv.number(factor, "factor")))

    @property
    def eye(self) -> tuple[float, float, float]:
        """Eye position (x, y, z), metres (not exaggerated)."""
        return self._c.eye

    @property
    def target(self) -> tuple[float, float, float]:
        """Target point (x, y, z), metres (not exaggerated)."""
        return self._c.target

    @property
    def up(self) -> tuple[float, float, float]:
        """The approximate up vector (x, y, z) of :meth:`look_at`."""
        return self._c.up

    @property
    def fov_y(self) -> float:
        """Vertical field of view, degrees."""
        return self._c.fov_y

    @property
    def near(self) -> float | None:
        """Near clip distance along the view axis (exaggerated metres); None = from the scene bounds."""
        return self._c.near

    @property
    def far(self) -> float | None:
        """Far clip distance along the view axis (exaggerated metres); None = from the scene bounds."""
        return self._c.far

    @property
    def projection(self) -> Projection:
        """"perspective" or "orthographic"."""
        return cast(Projection, self._c.projection)

    @property
    def ortho_height(self) -> float | None:
        """Height of the orthographic view (metres), None = what fov_y sees at the target."""
        return self._c.ortho_height

    @property
    def z_scale(self) -> float:
        """Vertical exaggeration (z -> z * z_scale)."""
        return self._c.z_scale

    def view_matrix(self) -> np.ndarray:
        """(4, 4) float64 world (exaggerated) -> view matrix, row-major, acting on column vectors
        (x, y, z, 1); the camera looks down -z, y up."""
        return self._c.view_matrix()

    def _fields(self) -> tuple:
        c = self._c
        return (c.eye, c.target, c.up, c.fov_y, c.near, c.far, c.projection, c.ortho_height, c.z_scale)

    def __reduce__(self) -> tuple[Any, tuple]:
        # Pickled as its fields, which are exactly look_at's arguments (checked again on loading).
        return (Camera.look_at, self._fields())

    def __copy__(self) -> Camera:
        return self  # immutable

    def __deepcopy__(self, memo: dict[int, Any]) -> Camera:
        return self

    def __repr__(self) -> str:
        return f"<geocull.Camera {self.projection} eye={self.eye} target={self.target} fov_y={self.fov_y}>"


def _t3(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))
