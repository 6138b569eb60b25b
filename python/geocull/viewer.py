"""An interactive notebook viewer: ``gc.Viewer(scene, width, height, culling=...)``.

Drag on the image to orbit about the target (right = azimuth up, i.e. the eye moves clockwise seen
from above; down = the eye rises), turn the mouse wheel to zoom; the culling mode and the pixel
threshold are controls under the image, followed by the frame's stats. Each frame is rendered
by the scene's :class:`geocull.Renderer` and sent to the browser as raw RGBA (no image encoding).
The browser asks for the next frame only when the last one has arrived, merging the mouse moves
made meanwhile, so the view keeps the frame rate the renderer allows and never falls behind.

The logic lives in :class:`ViewerState`, which has no widget dependency (tests drive it
headlessly); :class:`Viewer` wraps it in an ``anywidget`` (with ipywidgets controls), imported
only when a Viewer is made: ``pip install anywidget``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from . import _convert as cv
from ._errors import InputError
from .camera import Camera
from .renderer import CULLING_MODES, CullingMode, Renderer

if TYPE_CHECKING:
    from .results import RenderResult, RenderStats
    from .scene import Scene

__all__ = ["Viewer", "ViewerState"]

#: Degrees of orbit per pixel dragged.
DEGREES_PER_PIXEL = 0.4
#: Zoom per wheel unit: ``ZOOM_PER_WHEEL ** (-delta / 100)`` (a browser's notch is about 100).
ZOOM_PER_WHEEL = 1.15
#: Elevation limit of the viewer (short of +-90, where the view's up would flip).
MAX_ELEVATION = 89.5


class ViewerState:
    """The viewer without widgets: an orbit (target, azimuth, elevation, distance: as in
    :meth:`geocull.Camera.orbit`), render options, and the last frame. Every change re-renders and
    calls ``on_frame(result)``.

    scene: the :class:`geocull.Scene`; renderer: a :class:`geocull.Renderer` (its size is the
    image's), default a new one of ``width`` x ``height``; camera: the starting view (default
    :meth:`Camera.fit` of the scene from azimuth 210, elevation 30); culling, pixel_threshold and
    ``render_options`` go to :meth:`Renderer.render`. The default culling, "temporal", suits a view
    that moves a little from frame to frame: each frame starts from the tiles the last one showed.
    """

    def __init__(
        self,
        scene: Scene,
        width: int = 640,
        height: int = 480,
        culling: CullingMode = "temporal",
        pixel_threshold: float = 10,
        camera: Camera | None = None,
        renderer: Renderer | None = None,
        on_frame: Callable[[RenderResult[RenderStats]], None] | None = None,
        **render_options: Any,
    ) -> None:
        self.scene = scene
        self.renderer = renderer if renderer is not None else Renderer(cv.integer(width, "width"),
                                                                       cv.integer(height, "height"))
        self.culling: CullingMode = self._mode(culling)
        self.pixel_threshold = cv.number(pixel_threshold, "pixel_threshold")
        self.render_options = dict(render_options)
        self.on_frame = on_frame
        self.home = camera if camera is not None else Camera.fit(
            scene, azimuth=210.0, elevation=30.0, aspect=self.renderer.width / self.renderer.height
        )
        self.result: RenderResult[RenderStats] | None = None
        self.frames = 0
        self._set_orbit(self.home)

    @staticmethod
    def _mode(culling: str) -> CullingMode:
        if culling not in CULLING_MODES:
            raise InputError(f"culling: {culling!r} is not one of {', '.join(CULLING_MODES)}")
        return culling  # type: ignore[return-value]

    def _set_orbit(self, cam: Camera) -> None:
        self.lens = cam
        self.target = cam.target
        self.azimuth, self.elevation, self.distance = cam.orbit_angles()
        self.elevation = max(-MAX_ELEVATION, min(MAX_ELEVATION, self.elevation))

    @property
    def camera(self) -> Camera:
        """The current camera (the orbit with the starting camera's fov, projection, z_scale, ...)."""
        c = self.lens
        return Camera.orbit(self.target, self.azimuth, self.elevation, self.distance, c.up, c.fov_y, c.near,
                            c.far, c.projection, c.ortho_height, c.z_scale)

    def render(self) -> RenderResult[RenderStats]:
        """Render the current view, keep it as :attr:`result` and hand it to ``on_frame``."""
        self.result = self.renderer.render(self.scene, self.camera, culling=self.culling,
                                           pixel_threshold=self.pixel_threshold, **self.render_options)
        self.frames += 1
        if self.on_frame is not None:
            self.on_frame(self.result)
        return self.result

    def move(self, dx: float = 0.0, dy: float = 0.0, wheel: float = 0.0) -> RenderResult[RenderStats]:
        """Apply a mouse drag of (dx, dy) pixels (right, down) and a wheel turn of ``wheel`` (a
        browser's deltaY: > 0 scrolls down = zoom out), then render once. Drag: azimuth +=
        dx * DEGREES_PER_PIXEL, elevation += dy * DEGREES_PER_PIXEL (clamped to +-MAX_ELEVATION).
        Wheel: the distance (perspective) or the view height (orthographic) is multiplied by
        ZOOM_PER_WHEEL ** (wheel / 100)."""
        self.azimuth = (self.azimuth + cv.number(dx, "dx") * DEGREES_PER_PIXEL) % 360.0
        el = self.elevation + cv.number(dy, "dy") * DEGREES_PER_PIXEL
        self.elevation = max(-MAX_ELEVATION, min(MAX_ELEVATION, el))
        w = cv.number(wheel, "wheel")
        if w:
            f = ZOOM_PER_WHEEL ** (-w / 100.0)
            if self.lens.projection == "orthographic":
                self.lens = self.lens.zoomed(f)
            else:
                self.distance /= f
        return self.render()

    def drag(self, dx: float, dy: float) -> RenderResult[RenderStats]:
        """:meth:`move` with a drag only."""
        return self.move(dx=dx, dy=dy)

    def wheel(self, delta: float) -> RenderResult[RenderStats]:
        """:meth:`move` with a wheel turn only."""
        return self.move(wheel=delta)

    def set_culling(self, culling: str) -> RenderResult[RenderStats]:
        """Switch the culling mode (one of :data:`geocull.CULLING_MODES`); re-renders."""
        self.culling = self._mode(culling)
        return self.render()

    def set_pixel_threshold(self, pixel_threshold: float) -> RenderResult[RenderStats]:
        """Set three_pass's pixel threshold (>= 0, pixels); re-renders."""
        self.pixel_threshold = cv.number(pixel_threshold, "pixel_threshold")
        return self.render()

    def reset(self) -> RenderResult[RenderStats]:
        """Back to the starting view; re-renders."""
        self._set_orbit(self.home)
        return self.render()

    def stats_text(self) -> str:
        """One line about the last frame: mode, triangles and tiles drawn, frame time."""
        if self.result is None:
            return ""
        s = self.result.stats
        ms = float(s["total_ms"])
        fps = f", {1000.0 / ms:.0f} frames/s possible" if ms > 0 else ""
        return (f"{self.culling}: {int(s['triangles_drawn']):,} of {int(s['triangles_fine_total']):,} triangles, "
                f"{int(s['tiles_drawn'])}/{int(s['tiles_total'])} tiles, {ms:.1f} ms{fps} · "
                f"azimuth {self.azimuth:.0f}°, elevation {self.elevation:.0f}°, distance {self.distance:,.0f} m")


_ESM = """
function render({ model, el }) {
  const canvas = document.createElement("canvas");
  canvas.style.cursor = "grab";
  canvas.style.touchAction = "none";
  el.appendChild(canvas);
  const ctx = canvas.getContext("2d");
  let busy = false, dx = 0, dy = 0, wheel = 0, last = null;
  function flush() {
    if (busy || (dx === 0 && dy === 0 && wheel === 0)) return;
    busy = true;
    model.send({ type: "view", dx: dx, dy: dy, wheel: wheel });
    dx = 0; dy = 0; wheel = 0;
  }
  function draw() {
    const w = model.get("width"), h = model.get("height"), buf = model.get("frame");
    if (!buf || buf.byteLength !== w * h * 4) return;
    canvas.width = w; canvas.height = h;
    const px = new Uint8ClampedArray(buf.buffer, buf.byteOffset, buf.byteLength);
    ctx.putImageData(new ImageData(px, w, h), 0, 0);
  }
  model.on("change:frame", () => { draw(); busy = false; flush(); });
  canvas.addEventListener("pointerdown", (e) => {
    last = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); canvas.style.cursor = "grabbing";
  });
  canvas.addEventListener("pointermove", (e) => {
    if (last === null) return;
    dx += e.clientX - last[0]; dy += e.clientY - last[1]; last = [e.clientX, e.clientY]; flush();
  });
  const up = () => { last = null; canvas.style.cursor = "grab"; };
  canvas.addEventListener("pointerup", up);
  canvas.addEventListener("pointercancel", up);
  canvas.addEventListener("wheel", (e) => { e.preventDefault(); wheel += e.deltaY; flush(); }, { passive: false });
  draw();
}
export default { render };
"""


def Viewer(  # noqa: N802 - a factory that reads as the class it returns
    scene: Scene,
    width: int = 640,
    height: int = 480,
    culling: CullingMode = "temporal",
    pixel_threshold: float = 10,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    **render_options: Any,
) -> Any:
    """A notebook widget showing ``scene`` (display it, or make it a cell's last expression): drag to
    orbit, wheel to zoom, a culling-mode menu, a pixel-threshold slider, a reset button, and the
    frame's stats under the image. Arguments as for :class:`ViewerState` (reachable as the widget's
    ``.state``: ``viewer.state.camera`` is the current view). Needs ``anywidget`` (and with it
    ipywidgets): ``pip install anywidget``."""
    try:
        import anywidget
        import ipywidgets as widgets
        import traitlets
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("geocull.Viewer needs anywidget (and ipywidgets): pip install anywidget") from e

    class _Canvas(anywidget.AnyWidget):
        _esm = _ESM
        frame = traitlets.Bytes(b"").tag(sync=True)
        width = traitlets.Int(0).tag(sync=True)
        height = traitlets.Int(0).tag(sync=True)

    canvas = _Canvas()
    stats = widgets.HTML()

    def show(res: RenderResult[RenderStats]) -> None:
        h, w = res.image.shape[:2]
        with canvas.hold_sync():
            canvas.width, canvas.height = int(w), int(h)
            canvas.frame = res.image.tobytes()
        stats.value = f"<span style='font-family:monospace'>{state.stats_text()}</span>"

    state = ViewerState(scene, width, height, culling, pixel_threshold, camera, renderer, show, **render_options)

    def on_msg(_widget: Any, content: dict[str, Any], _buffers: Any) -> None:
        if isinstance(content, dict) and content.get("type") == "view":
            state.move(*(float(content.get(k, 0.0)) for k in ("dx", "dy", "wheel")))

    canvas.on_msg(on_msg)
    mode = widgets.Dropdown(options=list(CULLING_MODES), value=state.culling, description="culling")
    thr = widgets.FloatLogSlider(value=max(state.pixel_threshold, 0.1), base=10, min=-1, max=3, step=0.1,
                                 description="pixels ≤", readout_format=".1f")
    reset = widgets.Button(description="reset view")
    mode.observe(lambda ch: state.set_culling(ch["new"]), names="value")
    thr.observe(lambda ch: state.set_pixel_threshold(ch["new"]), names="value")
    reset.on_click(lambda _b: state.reset())
    box = widgets.VBox([canvas, widgets.HBox([mode, thr, reset]), stats])
    box.state = state
    box.canvas = canvas
    box.stats = stats
    box.controls = dict(culling=mode, pixel_threshold=thr, reset=reset)
    box.handle_message = lambda content: on_msg(canvas, content, [])
    state.render()
    return box
