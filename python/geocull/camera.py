"""The camera: a look-at view in world coordinates (f64), perspective or orthographic."""

from __future__ import annotations

from typing import Any, Literal, cast

import numpy as np
from numpy.typing import ArrayLike

from . import _convert as cv
from . import _geocull
from ._errors import InputError

__all__ = ["Camera", "Projection"]

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
