"""geocull: fast rendering of geoscience sub-surface scenes by culling what cannot be seen.

>>> import geocull as gc
>>> scene = gc.Scene()
>>> hid = scene.add_heightfield(z, origin=(x0, y0), spacing=(dx, dy), tiles=(10, 10), coarse_factor=25)
>>> cam = gc.Camera.look_at(eye, target)
>>> res = gc.Renderer(1280, 1024).render(scene, cam, culling="three_pass")
>>> res.image, res.depth, res.tile_pixels, res.stats

Modules: :mod:`~geocull.scene`, :mod:`~geocull.camera`, :mod:`~geocull.renderer`,
:mod:`~geocull.results`, :mod:`~geocull.volume`, :mod:`~geocull.iso` (re-exported here), and,
imported on first use, :mod:`~geocull.io` (xtgeo, segyio, trimesh, PyVista in and out),
:mod:`~geocull.compare`, :mod:`~geocull.data`, :mod:`~geocull.pyvista`, :mod:`~geocull.bench`
(the benchmarks, and :mod:`~geocull.bench.report`: sweeps, tables, plots), :mod:`~geocull.testing`
(image comparison and the pytest plugin),
:mod:`~geocull.distributed` (many views on a Dask cluster), and the notebook viewer ``Viewer``.
"""

import importlib as _importlib
from typing import TYPE_CHECKING as _TYPE_CHECKING
from typing import Any as _Any

from ._errors import DeviceError, GeocullError, GeocullWarning, InputError
from ._runtime import private_runtime_dir as _private_runtime_dir
from .camera import Camera, Projection
from .iso import extract_isosurface
from .renderer import (
    CULLING_MODES,
    ISO_CULLING_MODES,
    CullingMode,
    GridLodMode,
    IsoCullingMode,
    IsoWalk,
    LodMode,
    Renderer,
)
from .results import IsoResult, IsoStats, RenderResult, RenderStats
from .scene import Scene
from .volume import Volume, VolumeOrder, ZPositive

# Before any device opens (none does on import): a private XDG_RUNTIME_DIR where none is set, so
# that the drivers print no "XDG_RUNTIME_DIR is invalid or not set" lines.
_private_runtime_dir()

if _TYPE_CHECKING:  # type checkers see the lazy submodules; at runtime __getattr__ imports them on first use
    from . import bench as bench
    from . import compare as compare
    from . import data as data
    from . import distributed as distributed
    from . import grid as grid
    from . import io as io
    from . import iso as iso
    from . import pyvista as pyvista
    from . import testing as testing
    from .viewer import Viewer as Viewer

__version__ = "0.1.0"
__all__ = [
    "Scene",
    "Camera",
    "Renderer",
    "RenderResult",
    "IsoResult",
    "Volume",
    "VolumeOrder",
    "ZPositive",
    "Projection",
    "extract_isosurface",
    "GeocullError",
    "InputError",
    "DeviceError",
    "GeocullWarning",
    "CULLING_MODES",
    "ISO_CULLING_MODES",
    "CullingMode",
    "IsoCullingMode",
    "IsoWalk",
    "LodMode",
    "GridLodMode",
    "RenderStats",
    "IsoStats",
    "Viewer",
]

_SUBMODULES = ("compare", "data", "pyvista", "bench", "iso", "io", "testing", "distributed", "grid")


def __getattr__(name: str) -> _Any:
    """``gc.compare``, ``gc.data``, ``gc.pyvista``, ``gc.bench``, ``gc.io``: imported on
    first use (PyVista and VTK are only loaded when ``gc.pyvista`` is touched; ``gc.io`` imports
    xtgeo, segyio, trimesh only inside the functions that need them)."""
    if name in _SUBMODULES:
        return _importlib.import_module(f".{name}", __name__)
    if name == "Viewer":  # the notebook viewer (geocull.viewer): its widget libraries load when one is made
        return _importlib.import_module(".viewer", __name__).Viewer
    raise AttributeError(f"module 'geocull' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The module's attributes plus the lazily imported submodules, for tab completion."""
    return sorted(set(globals()) | set(_SUBMODULES) | {"Viewer"})
