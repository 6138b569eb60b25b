"""Type stub of the Rust extension (src/python/). Users call the wrappers in geocull (scene.py,
camera.py, renderer.py, volume.py), which coerce and check arguments; these are the raw entry points
they call. Arrays must already have the dtype and layout given here (C-contiguous); the extension
raises TypeError otherwise.

The dict shapes below (``@type_check_only`` TypedDicts) exist only for type checkers: at runtime the
extension returns plain dicts with exactly these keys.
"""

from typing import Any, Final, Literal, NotRequired, Self, TypeAlias, TypedDict, final, type_check_only

import numpy as np
import numpy.typing as npt

from geocull.results import IsoStats, RenderStats

__version__: Final[str]

# (color_by "z" | "values", values (same shape as the samples / vertices), colour-map name,
# colour-map table (n, 3) float64, clim, nan_color): geocull._convert.coloring builds it.
_Coloring: TypeAlias = tuple[
    str,
    npt.NDArray[np.float64] | None,
    str | None,
    npt.NDArray[np.float64] | None,
    tuple[float, float] | None,
    tuple[float, float, float] | None,
]
__all__ = [
    "Scene",
    "Camera",
    "Renderer",
    "culling_modes",
    "Volume",
    "render_isosurface",
    "clear_isosurface_cache",
    "set_isosurface_cache_budget",
    "isosurface_cache_budget",
    "extract_isosurface",
    "__version__",
    "GeocullError",
    "InputError",
    "DeviceError",
    "GeocullWarning",
]

# geocull's exception hierarchy (src/python/errors.rs), re-exported as geocull.GeocullError etc.
class GeocullError(Exception):
    """Base class of every error geocull raises."""

class InputError(GeocullError, ValueError):
    """A bad argument: wrong shape, dtype, value or range. The message starts with the argument's
    name and points at the first offending element."""

class DeviceError(GeocullError, RuntimeError):
    """No usable graphics adapter, or the driver rejected the work. On a machine without a GPU,
    install Mesa's lavapipe: ``apt-get install libvulkan1 mesa-vulkan-drivers``."""

class GeocullWarning(UserWarning):
    """Something valid but almost certainly not what was meant, e.g. a frame that cannot show
    anything because the whole scene lies nearer than the near plane."""

@type_check_only
class ObjectInfo(TypedDict):
    """``Scene.object_info(id)``."""

    id: int
    name: str | None
    kind: str  # "heightfield", "mesh", "fault", ... (the label given to add_mesh)
    color: tuple[float, float, float]  # (r, g, b) in [0, 1]
    visible: bool
    priority: int  # 0..=15, the depth-tie priority (Scene.set_priority): its own or its kind's
    offset: tuple[float, float, float]  # (dx, dy, dz) metres, from translate()
    n_tiles: int
    n_triangles: int  # fine (level 0)
    color_by: Literal["z", "values"] | None  # None: the flat color
    cmap: str | None  # the colour map's name ("custom" for a table)
    clim: tuple[float, float] | None  # the scalars at the colour map's ends (z in metres for "z")

@type_check_only
class _GridLevelRaw(TypedDict):
    cells: int
    faces: int
    triangles: int
    interior_triangles: int
    vertices: int
    volume: float

@type_check_only
class TileTable(TypedDict):
    """``Scene.tile_table()``: one column per key, one row per tile in the renderer's tile order."""

    object: npt.NDArray[np.uint32]  # (n,) object id
    ix: npt.NDArray[np.uint32]  # (n,) tile column within its object
    iy: npt.NDArray[np.uint32]  # (n,) tile row within its object
    tris_fine: npt.NDArray[np.uint32]  # (n,)
    tris_coarse: npt.NDArray[np.uint32]  # (n,)
    proxy_error: npt.NDArray[np.float64]  # (n,) metres
    level_triangles: npt.NDArray[np.uint32]  # (n, 6)
    level_error: npt.NDArray[np.float64]  # (n, 6) metres, NaN past a tile's last level
    level_error_z: npt.NDArray[np.float64]  # (n, 6) metres, the vertical part of level_error
    level_shading_error: npt.NDArray[np.float64]  # (n, 6) normal chord (unitless), NaN past the last level
    bbox_min: npt.NDArray[np.float64]  # (n, 3) world coordinates (metres), NaN for empty tiles
    bbox_max: npt.NDArray[np.float64]  # (n, 3)

@type_check_only
class RenderOutput(TypedDict):
    """``Renderer.render(...)``."""

    image: npt.NDArray[np.uint8]  # (H, W, 4) RGBA, row 0 at the top
    depth: npt.NDArray[np.float32]  # (H, W) distance along the view axis, +inf where empty
    tile_pixels: npt.NDArray[np.uint32]  # (n_tiles,) visible pixels per tile
    tile_drawn: npt.NDArray[np.bool_]  # (n_tiles,)
    near: float
    far: float
    stats: RenderStats
    horizon: NotRequired[npt.NDArray[np.float32]]  # (W,), only for culling="horizon"
    box_pixels: NotRequired[npt.NDArray[np.uint32]]  # (n_tiles,), three_pass conservative / predict_errors
    proxy_error_px: NotRequired[npt.NDArray[np.float32]]  # (n_tiles,), three_pass: proxy error in pixels
    tile_level: NotRequired[npt.NDArray[np.uint32]]  # (n_tiles,), lod="screen_error": level drawn
    tile_error_px: NotRequired[npt.NDArray[np.float32]]  # (n_tiles,), lod="screen_error": its error, pixels

@type_check_only
class IsoOutput(TypedDict):
    """``render_isosurface(...)``."""

    image: npt.NDArray[np.uint8]  # (H, W, 4) RGBA, row 0 at the top
    depth: npt.NDArray[np.float32]  # (H, W) distance along the view axis, +inf where empty
    nodes: npt.NDArray[np.uint32]  # (n, 4) [depth, ix, iy, iz] of the straddling nodes at cull_depth
    tile_pixels: npt.NDArray[np.uint32]  # (n,) per node of `nodes`: its cells seen
    tile_drawn: npt.NDArray[np.bool_]  # (n,) per node of `nodes`
    occlusion_map: NotRequired[npt.NDArray[np.float32]]  # (H, W), only with return_map=True
    near: float
    far: float
    stats: IsoStats

@type_check_only
class OctreeNodes(TypedDict):
    """``Volume.nodes(depth)``."""

    index: npt.NDArray[np.uint32]  # (n, 3) [ix, iy, iz]
    bbox_min: npt.NDArray[np.float64]  # (n, 3) world coordinates
    bbox_max: npt.NDArray[np.float64]  # (n, 3)
    min: npt.NDArray[np.float64]  # (n,) in the values' units (offset + float32 residual)
    max: npt.NDArray[np.float64]  # (n,)

@final
class Scene:
    def __new__(cls) -> Self: ...
    def copy(self) -> Scene: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: bytes) -> Scene: ...
    def add_heightfield(
        self,
        z: npt.NDArray[np.float64],  # (ny, nx), C-contiguous
        origin: tuple[float, float],
        spacing: tuple[float, float],
        tiles: tuple[int, int],
        coarse_factor: float,
        name: str | None,
        color: tuple[float, float, float] | None,
        null_value: float | None,
        rotation: float,
        yflip: bool,
        coloring: _Coloring | None = None,
    ) -> int: ...
    def add_mesh(
        self,
        vertices: npt.NDArray[np.float64],  # (n, 3), C-contiguous
        faces: npt.NDArray[np.int64],  # (m, 3), C-contiguous
        kind: str,
        tiles: int | None,
        coarse_factor: float,
        name: str | None,
        color: tuple[float, float, float] | None,
        coloring: _Coloring | None = None,
    ) -> int: ...
    def add_well(
        self,
        path: npt.NDArray[np.float64],  # (n, 3), C-contiguous
        radius: float,
        sides: int,
        name: str | None,
        color: tuple[float, float, float] | None,
        coloring: _Coloring | None = None,
    ) -> int: ...
    def add_slice(
        self,
        volume: Volume,
        axis: int,
        index: int,
        name: str | None,
        coloring: _Coloring,
        opacity: float = 1.0,
        replace: int | None = None,
    ) -> int: ...
    def add_isosurface(
        self,
        volume: Volume,
        isovalue: float,
        tiles: int | None,
        coarse_factor: float,
        name: str | None,
        color: tuple[float, float, float] | None,
        coloring: _Coloring | None = None,
        values: Volume | None = None,
    ) -> int: ...
    def add_lens(
        self,
        volume: Volume,
        bx: tuple[tuple[int, int], tuple[int, int], tuple[int, int]],
        opacity: float,
        name: str | None,
        coloring: _Coloring,
    ) -> int: ...
    def add_grid(
        self,
        corners: npt.NDArray[np.float64],  # (nk, nj, ni, 8, 3), C-contiguous
        active: npt.NDArray[np.bool_] | None,  # (nk, nj, ni)
        region: npt.NDArray[np.int32] | None,  # (nk, nj, ni)
        blocks: tuple[int, int],
        name: str | None,
        color: tuple[float, float, float] | None,
        coloring: _Coloring | None = None,
    ) -> int: ...
    def grid_levels(self, id: int) -> list[_GridLevelRaw]: ...
    def remove(self, id: int) -> None: ...
    def set_priority(self, id: int, priority: int | None) -> None: ...
    def set_visible(self, id: int, visible: bool) -> None: ...
    def translate(self, id: int, offset: tuple[float, float, float]) -> None: ...
    def set_color_by(self, id: int, coloring: _Coloring) -> None: ...
    def set_color(self, id: int, color: tuple[float, float, float]) -> None: ...
    @property
    def n_tiles(self) -> int: ...
    @property
    def n_triangles(self) -> int: ...
    @property
    def origin(self) -> tuple[float, float, float]: ...
    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]] | None: ...
    @property
    def host_bytes(self) -> int: ...
    def object_ids(self) -> list[int]: ...
    def object_info(self, id: int) -> ObjectInfo: ...
    def tile_table(self) -> TileTable: ...
    def geometry(self, id: int) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...

@final
class Camera:
    # No constructor: Camera() raises TypeError; look_at builds one.
    @staticmethod
    def look_at(
        eye: tuple[float, float, float],
        target: tuple[float, float, float],
        up: tuple[float, float, float],
        fov_y: float,
        near: float | None,
        far: float | None,
        projection: str,
        ortho_height: float | None,
        z_scale: float,
    ) -> Camera: ...
    @staticmethod
    def orbit(
        target: tuple[float, float, float],
        azimuth: float,
        elevation: float,
        distance: float,
        up: tuple[float, float, float],
        fov_y: float,
        near: float | None,
        far: float | None,
        projection: str,
        ortho_height: float | None,
        z_scale: float,
    ) -> Camera: ...
    @staticmethod
    def fit(
        lo: tuple[float, float, float],
        hi: tuple[float, float, float],
        azimuth: float,
        elevation: float,
        margin: float,
        aspect: float,
        up: tuple[float, float, float],
        fov_y: float,
        projection: str,
        z_scale: float,
    ) -> Camera: ...
    def orbit_angles(self) -> tuple[float, float, float]: ...
    def rotated(self, d_azimuth: float, d_elevation: float) -> Camera: ...
    def zoomed(self, factor: float) -> Camera: ...
    @property
    def eye(self) -> tuple[float, float, float]: ...
    @property
    def target(self) -> tuple[float, float, float]: ...
    @property
    def up(self) -> tuple[float, float, float]: ...
    @property
    def fov_y(self) -> float: ...
    @property
    def near(self) -> float | None: ...
    @property
    def far(self) -> float | None: ...
    @property
    def projection(self) -> str: ...
    @property
    def ortho_height(self) -> float | None: ...
    @property
    def z_scale(self) -> float: ...
    def view_matrix(self) -> npt.NDArray[np.float64]: ...  # (4, 4), row-major

@final
class Renderer:
    def __new__(cls, width: int, height: int, backend: str) -> Self: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def adapter_info(self) -> str: ...
    @property
    def max_texture_size(self) -> int: ...
    @property
    def gpu_bytes(self) -> int: ...
    @property
    def cache_budget(self) -> int: ...
    @cache_budget.setter
    def cache_budget(self, bytes: int) -> None: ...
    def set_background(self, rgb: bytes | None) -> None: ...
    @property
    def pass_triangles(self) -> int | None: ...
    @pass_triangles.setter
    def pass_triangles(self, max: int | None) -> None: ...
    def render(
        self,
        scene: Scene,
        camera: Camera,
        culling: str,
        pixel_threshold: float,
        prepass_scale: float | None,
        conservative: bool,
        predict_errors: bool,
        lod: str,
        max_pixel_error: float,
        grid_lod: str,
        alpha: float,
        lam: float,
    ) -> RenderOutput: ...

def culling_modes() -> list[str]: ...

@final
class Volume:
    def __new__(
        cls,
        values: npt.NDArray[np.float32] | npt.NDArray[np.float64],  # 3-D, any strides, native byte order
        origin: tuple[float, float, float],
        spacing: tuple[float, float, float],
        order: str,  # "zyx" | "xyz"
        z_positive: str,  # "up" | "down"
        rotation: float,
    ) -> Self: ...
    @property
    def rotation(self) -> float: ...
    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]: ...
    @property
    def shape(self) -> tuple[int, int, int]: ...
    @property
    def origin(self) -> tuple[float, float, float]: ...
    @property
    def spacing(self) -> tuple[float, float, float]: ...
    @property
    def offset(self) -> float: ...
    @staticmethod
    def lazy(
        reader: Any,  # .read(lo, hi) -> float32 (z, y, x) array of the stored grid's box lo..hi (x, y, z)
        shape: tuple[int, int, int],  # (nx, ny, nz) of the stored grid
        origin: tuple[float, float, float],
        spacing: tuple[float, float, float],
        z_positive: str,  # "up" | "down"
        offset: float,
        rotation: float,
        cache_bytes: int,
    ) -> Volume: ...
    @property
    def is_lazy(self) -> bool: ...
    @property
    def bytes_read(self) -> int: ...
    @property
    def cache_info(self) -> tuple[int, int, int] | None: ...
    def clear_cache(self) -> None: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: bytes) -> Volume: ...
    def max_depth(self) -> int: ...
    def nodes(self, depth: int) -> OctreeNodes: ...

def render_isosurface(
    renderer: Renderer,
    volume: Volume,
    isovalue: float,
    camera: Camera,
    culling: str,
    occluder_depth: int | None,
    cull_depth: int | None,
    color: tuple[float, float, float],
    cache: bool,
    return_map: bool,
    walk: str,
) -> IsoOutput: ...
def clear_isosurface_cache(renderer: Renderer) -> None: ...
def set_isosurface_cache_budget(renderer: Renderer, bytes: int) -> None: ...
def isosurface_cache_budget(renderer: Renderer) -> int: ...
def extract_isosurface(
    volume: Volume, isovalue: float
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...
