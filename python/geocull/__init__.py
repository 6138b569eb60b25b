"""geocull: fast rendering of geoscience sub-surface scenes by culling what cannot be seen.

>>> import geocull as gc
>>> scene = gc.Scene()
>>> hid = scene.add_heightfield(z, origin=(x0, y0), spacing=(dx, dy), tiles=(10, 10), coarse_factor=25)
>>> cam = gc.Camera.look_at(eye, target)
>>> res = gc.Renderer(1280, 1024).render(scene, cam, culling="three_pass")
>>> res.image, res.depth, res.tile_pixels, res.stats
"""

from ._errors import DeviceError, GeocullError, InputError
from ._api import Camera, Renderer, RenderResult, Scene
from .iso import Volume

__version__ = "0.1.0"
__all__ = ["Scene", "Camera", "Renderer", "RenderResult", "Volume", "GeocullError", "InputError", "DeviceError"]

_SUBMODULES = ("compare", "data", "pyvista", "report", "bench", "iso")


def __getattr__(name: str):
    """``gc.compare``, ``gc.data``, ``gc.pyvista``, ``gc.report``: imported on first use (PyVista
    and VTK are only loaded when ``gc.pyvista`` is touched)."""
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'geocull' has no attribute {name!r}")
