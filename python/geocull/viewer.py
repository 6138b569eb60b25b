"""An interactive notebook viewer: ``gc.Viewer(scene, width, height, culling=...)``.

Drag on the image to orbit about the target (right = azimuth up, i.e. the eye moves clockwise seen
from above; down = the eye rises), turn the mouse wheel to zoom (down to a minimum distance); the
culling mode, the pixel threshold, the vertical exaggeration (``z_scale``; also "+" / "-" on the
focused image) and a reset button are controls under the image, followed by the frame's stats. Each
frame is rendered by the scene's :class:`geocull.Renderer` and sent to the browser as raw RGBA (no
image encoding).

The protocol never leaves the browser waiting. The browser sends one request at a time (the mouse
moves made meanwhile merged into the next) and the kernel answers every request, with an
acknowledgement (``ack``: the request's view id and number) that travels in the same state update as
the frame, also when the frame is identical to the last one (a drag at the elevation limit, a wheel
turn at the minimum distance) or when handling it failed; a browser that hears nothing for 15 s
sends again anyway. (With :data:`EARLY_NEXT`, the kernel also says when it starts on a request and
the browser may queue one more behind it.) "Reset view" bumps an epoch: motion queued or in flight from before is
dropped, by the browser and by the kernel. An exception in a callback (the view's, the controls',
or the ``on_frame`` given to :func:`Viewer`) is shown under the image and the viewer stays usable;
the next good frame clears it. The canvas carries ``data-frames`` (frames rendered) for tests. The
stats line reports what the browser measured: frames drawn per second and the time from the first
mouse move of a request to its frame on screen (median of the last 20); the canvas's
``geocullLog`` holds each request's times (scripts/viewer_latency.py reads it). When the view rests, the
browser stores the frame as a PNG in the widget's state (``png``), which a saved notebook keeps,
and the output's ``image/png`` shows the frame at display time where no widget can be drawn.

The logic lives in :class:`ViewerState`, which has no widget dependency (tests drive it
headlessly); :class:`Viewer` wraps it in an ``anywidget`` (with ipywidgets controls), imported
only when a Viewer is made: ``pip install anywidget``.
"""

from __future__ import annotations

import base64
import json
import time
import traceback
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

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
#: Default minimum distance of the eye from the target (and minimum orthographic view height), as
#: a fraction of the scene's diagonal: the wheel stops there instead of passing through the target.
MIN_DISTANCE_FRACTION = 1e-3
#: Whether the kernel tells the browser when it starts on a request ("started"), so that the browser
#: sends its next one (the motion made so far) to wait behind it and the kernel renders back to back
#: while a frame travels. Off by default: measured in JupyterLab + Chromium on a 2-core CPU machine
#: (lavapipe, 419 k triangles at 640 x 480, scripts/viewer_latency.py) it raised the median
#: drag-to-frame latency by ~50 ms for ~10 % more frames/s, the renders competing with the browser
#: and the server for the cores. Where the renderer does not share the browser's CPU (a GPU) and the
#: transport costs more than the render, it should pay off. Off: one request at a time.
EARLY_NEXT = False
#: The pixel-threshold slider's stops (pixels; 0 draws every tile with a visible pixel).
THRESHOLD_STOPS = (0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0)
#: The vertical-exaggeration slider's stops (``z_scale``; the browser's "+" / "-" keys step through them).
Z_SCALE_STOPS = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0)


class ViewerState:
    """The viewer without widgets: an orbit (target, azimuth, elevation, distance: as in
    :meth:`geocull.Camera.orbit`), render options, and the last frame. Every change re-renders and
    calls ``on_frame(result)``.

    scene: the :class:`geocull.Scene`; renderer: a :class:`geocull.Renderer` (its size is the
    image's), default a new one of ``width`` x ``height``; camera: the starting view (default
    :meth:`Camera.fit` of the scene from azimuth 210, elevation 30); culling, pixel_threshold and
    ``render_options`` go to :meth:`Renderer.render`. The default culling, "temporal", suits a view
    that moves a little from frame to frame: each frame starts from the tiles the last one showed.
    min_distance: the closest the eye comes to the target with the wheel (render-space metres; for
    orthographic views the smallest view height), default :data:`MIN_DISTANCE_FRACTION` of the
    scene's diagonal (of the starting distance for a scene without bounds). z_scale: the vertical
    exaggeration (> 0; default the camera's, 1 for the default camera); :meth:`set_z_scale`
    changes it.
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
        min_distance: float | None = None,
        z_scale: float | None = None,
        **render_options: Any,
    ) -> None:
        self.scene = scene
        self.renderer = renderer if renderer is not None else Renderer(cv.integer(width, "width"),
                                                                       cv.integer(height, "height"))
        self.culling: CullingMode = self._mode(culling)
        self.pixel_threshold = cv.number(pixel_threshold, "pixel_threshold")
        self.render_options = dict(render_options)
        self.on_frame = on_frame
        self.z_scale = self._z(z_scale if z_scale is not None else camera.z_scale if camera is not None else 1.0)
        self._fit_home = camera is None  # the default view is fitted again at another z_scale
        self.home = camera if camera is not None else self._fit()
        self.result: RenderResult[RenderStats] | None = None
        self.frames = 0
        #: What the browser measured (set by the widget): frames drawn per second while the view
        #: moves, and the median time from a mouse move to its frame on screen (ms).
        self.browser_fps: float | None = None
        self.browser_latency_ms: float | None = None
        self._set_orbit(self.home)
        if min_distance is None:
            b = getattr(scene, "bounds", None)
            if b is not None:
                span = (np.asarray(b[1], float) - np.asarray(b[0], float)) * np.array([1.0, 1.0, self.home.z_scale])
                diag = float(np.linalg.norm(span))
            else:
                diag = 0.0
            self.min_distance = MIN_DISTANCE_FRACTION * (diag if diag > 0 else self.distance)
        else:
            self.min_distance = cv.number(min_distance, "min_distance")
            if not self.min_distance > 0:
                raise InputError(f"min_distance: expected a number > 0, got {min_distance!r}")

    def _fit(self) -> Camera:
        return Camera.fit(self.scene, azimuth=210.0, elevation=30.0, aspect=self.renderer.width / self.renderer.height,
                          z_scale=self.z_scale)

    @staticmethod
    def _z(z_scale: Any) -> float:
        z = cv.number(z_scale, "z_scale")
        if not (np.isfinite(z) and z > 0):
            raise InputError(f"z_scale: expected a number > 0, got {z_scale!r}")
        return z

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
        """The current camera (the orbit with the starting camera's fov, projection, ...; the
        viewer's :attr:`z_scale`)."""
        c = self.lens
        return Camera.orbit(self.target, self.azimuth, self.elevation, self.distance, c.up, c.fov_y, c.near,
                            c.far, c.projection, c.ortho_height, self.z_scale)

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
        ZOOM_PER_WHEEL ** (wheel / 100), and kept at or above :attr:`min_distance`."""
        ddx, ddy, w = cv.number(dx, "dx"), cv.number(dy, "dy"), cv.number(wheel, "wheel")
        self.azimuth = (self.azimuth + ddx * DEGREES_PER_PIXEL) % 360.0
        el = self.elevation + ddy * DEGREES_PER_PIXEL
        self.elevation = max(-MAX_ELEVATION, min(MAX_ELEVATION, el))
        if w:
            f = ZOOM_PER_WHEEL ** (-w / 100.0)
            if self.lens.projection == "orthographic":
                h = self.lens.ortho_height
                if h is not None and h / f < self.min_distance:
                    f = h / self.min_distance
                if h is None or abs(f - 1.0) > 1e-12:
                    self.lens = self.lens.zoomed(f)
            else:
                self.distance = max(self.min_distance, self.distance / f)
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

    def set_z_scale(self, z_scale: float) -> RenderResult[RenderStats]:
        """Set the vertical exaggeration (> 0: z drawn times ``z_scale``; InputError otherwise) and
        re-render. The target (world coordinates), the angles and the distance are kept; the
        default view (no ``camera`` given) is fitted again at the new exaggeration, for
        :meth:`reset`."""
        self.z_scale = self._z(z_scale)
        if self._fit_home:
            self.home = self._fit()
        return self.render()

    def reset(self) -> RenderResult[RenderStats]:
        """Back to the starting view (at the current :attr:`z_scale`); re-renders."""
        self._set_orbit(self.home)
        return self.render()

    def stats_text(self) -> str:
        """One line about the last frame: mode, triangles and tiles drawn, the renderer's time, what
        the browser measured (when it has reported), and the view."""
        if self.result is None:
            return ""
        s = self.result.stats
        ms, rb = float(s["total_ms"]), float(s.get("readback_ms", 0.0))
        browser = ""
        if self.browser_fps is not None or self.browser_latency_ms is not None:
            parts = []
            if self.browser_fps is not None:
                parts.append(f"{self.browser_fps:.1f} frames/s")
            if self.browser_latency_ms is not None:
                parts.append(f"{self.browser_latency_ms:.0f} ms drag→frame")
            browser = f" · browser: {', '.join(parts)}"
        return (f"{self.culling}: {int(s['triangles_drawn']):,} of {int(s['triangles_fine_total']):,} triangles, "
                f"{int(s['tiles_drawn'])}/{int(s['tiles_total'])} tiles, render {ms:.1f} ms + {rb:.1f} ms read-back"
                f"{browser} · azimuth {self.azimuth:.0f}°, elevation {self.elevation:.0f}°, "
                f"distance {self.distance:,.0f} m, z ×{self.z_scale:g}")


_ESM = """
const ANSWER_TIMEOUT_MS = 15000;  // a request unanswered this long (kernel restarted?) is given up
const IDLE_MS = 400;              // the view rests: report the measures, keep the frame as PNG
const Z_STOPS = __Z_STOPS__;      // vertical exaggerations the "+" / "-" keys step through

function render({ model, el }) {
  const root = document.createElement("div");
  root.className = "geocull-viewer";
  const canvas = document.createElement("canvas");
  canvas.style.cssText = "display:block;cursor:grab;touch-action:none";
  canvas.tabIndex = 0;  // focusable, for the keys
  const error = document.createElement("pre");
  error.className = "geocull-error";
  error.style.cssText = "display:none;margin:4px 0;padding:4px 6px;max-height:14em;overflow:auto;" +
    "white-space:pre-wrap;font-size:12px;color:#a40000;background:#fff2f2;border-left:3px solid #a40000";
  root.appendChild(canvas);
  root.appendChild(error);
  el.appendChild(root);
  const ctx = canvas.getContext("2d");
  const id = Math.random().toString(36).slice(2) + Date.now().toString(36);
  let seq = 0, inflight = [], timer = null, idle = null;
  let dx = 0, dy = 0, wheel = 0, since = null, last = null;
  let fps = null, latency = null;
  const lats = [], shown = [], log = [];
  canvas.geocullLog = log;

  function queued() { return dx !== 0 || dy !== 0 || wheel !== 0; }
  function mark() { canvas.dataset.pending = inflight.length > 0 || queued() ? "1" : "0"; }
  // At most one request the kernel has not started on: the next waits behind the one rendering.
  function free() { return inflight.length === 0 || (inflight.length === 1 && inflight[0].started); }
  function flush() {
    if (free() && queued()) {
      seq += 1;
      inflight.push({ seq: seq, t0: since === null ? performance.now() : since, sent: performance.now(),
                      started: false });
      model.send({ type: "view", id: id, seq: seq, epoch: model.get("epoch"), dx: dx, dy: dy, wheel: wheel,
                   fps: fps, latency_ms: latency });
      dx = 0; dy = 0; wheel = 0; since = null;
      clearTimeout(timer);
      timer = setTimeout(() => { inflight = []; flush(); }, ANSWER_TIMEOUT_MS);
    }
    mark();
  }
  function started(msg) {
    const r = inflight.find((q) => msg.id === id && q.seq === msg.seq);
    if (r) { r.started = true; flush(); }
  }
  function input() {
    if (since === null) since = performance.now();
    clearTimeout(idle);
    flush();
  }
  function answered(ack) {
    const i = ack && ack.id === id ? inflight.findIndex((q) => q.seq === ack.seq) : -1;
    if (i < 0) return;
    const r = inflight[i];
    inflight.splice(0, i + 1);
    clearTimeout(timer);
    if (inflight.length) timer = setTimeout(() => { inflight = []; flush(); }, ANSWER_TIMEOUT_MS);
    const now = performance.now();
    lats.push(now - r.t0);
    if (lats.length > 20) lats.shift();
    const sorted = lats.slice().sort((a, b) => a - b);
    latency = sorted[sorted.length >> 1];
    shown.push(now);
    while (shown.length > 1 && now - shown[0] > 2000) shown.shift();
    if (shown.length >= 3) fps = (shown.length - 1) * 1000 / (now - shown[0]);
    canvas.dataset.latency = String(latency);
    canvas.dataset.roundtrip = String(now - r.sent);
    canvas.dataset.kernelMs = String(ack.kernel_ms);
    // Each answered request's times (ms, performance.now()) for scripts/viewer_latency.py.
    log.push({ input: r.t0, sent: r.sent, answered: now, kernel_ms: ack.kernel_ms });
    if (log.length > 5000) log.shift();
    flush();
    if (inflight.length === 0 && !queued()) {
      clearTimeout(idle);
      idle = setTimeout(rest, IDLE_MS);
    }
  }
  function rest() {
    if (inflight.length > 0 || queued()) return;
    model.send({ type: "stats", fps: fps, latency_ms: latency });
    if (canvas.width > 0 && canvas.height > 0) {
      const png = canvas.toDataURL("image/png");
      if (png !== model.get("png")) { model.set("png", png); model.save_changes(); }
    }
  }
  function size(w, h) { if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; } }
  function draw() {
    const w = model.get("width"), h = model.get("height"), buf = model.get("frame");
    if (buf && buf.byteLength === w * h * 4) {
      size(w, h);
      const px = new Uint8ClampedArray(buf.buffer, buf.byteOffset, buf.byteLength);
      ctx.putImageData(new ImageData(px, w, h), 0, 0);
      return;
    }
    const png = model.get("png");  // a saved state without the raw frame: its PNG
    if (png) {
      const img = new Image();
      img.onload = () => { size(img.width, img.height); ctx.drawImage(img, 0, 0); };
      img.src = png;
    }
  }
  function showError() {
    const text = model.get("error") || "";
    error.textContent = text;
    error.style.display = text ? "block" : "none";
  }
  function count() { canvas.dataset.frames = String(model.get("frames")); }

  model.on("msg:custom", (msg) => { if (msg && msg.type === "started") started(msg); });
  model.on("change:frame", draw);
  model.on("change:frames", count);
  model.on("change:error", showError);
  model.on("change:epoch", () => { dx = 0; dy = 0; wheel = 0; since = null; mark(); });
  // "change" comes after every change:<name> of one update, so the frame is drawn before its answer
  // is counted; answered() acts only on the answer to the request in flight.
  model.on("change", () => answered(model.get("ack")));

  canvas.addEventListener("pointerdown", (e) => {
    last = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); canvas.style.cursor = "grabbing";
  });
  canvas.addEventListener("pointermove", (e) => {
    if (last === null) return;
    dx += e.clientX - last[0]; dy += e.clientY - last[1]; last = [e.clientX, e.clientY]; input();
  });
  const up = () => { last = null; canvas.style.cursor = "grab"; };
  canvas.addEventListener("pointerup", up);
  canvas.addEventListener("pointercancel", up);
  canvas.addEventListener("wheel", (e) => { e.preventDefault(); wheel += e.deltaY; input(); }, { passive: false });
  // "+" / "-": the next larger / smaller vertical exaggeration; the kernel renders when z_scale changes.
  function zstep(up) {
    const z = model.get("z_scale");
    const next = up ? Z_STOPS.find((v) => v > z * 1.0001) : Z_STOPS.slice().reverse().find((v) => v < z / 1.0001);
    if (next !== undefined) { model.set("z_scale", next); model.save_changes(); }
  }
  canvas.addEventListener("keydown", (e) => {
    if (e.key === "+" || e.key === "=") { e.preventDefault(); zstep(true); }
    else if (e.key === "-" || e.key === "_") { e.preventDefault(); zstep(false); }
  });
  draw();
  count();
  showError();
  mark();
  return () => { clearTimeout(timer); clearTimeout(idle); };
}
export default { render };
""".replace("__Z_STOPS__", json.dumps(list(Z_SCALE_STOPS)))


def _describe(what: str, e: BaseException) -> str:
    """The text shown under the image for an exception raised while handling ``what``."""
    tb = "".join(traceback.format_exception(type(e), e, e.__traceback__))
    return f"Error in the viewer's {what}: {type(e).__name__}: {e}\n\n{tb}"


def _stops(stops: Any, extra: float) -> list[tuple[str, float]]:
    """A SelectionSlider's (label, value) options: ``stops`` and ``extra``, sorted."""
    return [(f"{v:g}", float(v)) for v in sorted({*(float(x) for x in stops), float(extra)})]


def _opt_float(v: Any) -> float | None:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if np.isfinite(f) and f >= 0 else None


def Viewer(  # noqa: N802 - a factory that reads as the class it returns
    scene: Scene,
    width: int = 640,
    height: int = 480,
    culling: CullingMode = "temporal",
    pixel_threshold: float = 10,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    on_frame: Callable[[RenderResult[RenderStats]], object] | None = None,
    min_distance: float | None = None,
    z_scale: float | None = None,
    **render_options: Any,
) -> Any:
    """A notebook widget showing ``scene`` (display it, or make it a cell's last expression): drag to
    orbit, wheel to zoom, a culling-mode menu, a pixel-threshold slider (0 to 1000 pixels), a
    vertical-exaggeration slider (:data:`Z_SCALE_STOPS`; "+" / "-" on the focused image step it; the
    canvas's synced ``z_scale`` trait, ``viewer.canvas.z_scale``, set from Python or the browser,
    re-renders at that exaggeration), a reset button, and the frame's stats under the image.
    Arguments as for :class:`ViewerState` (reachable as the widget's ``.state``:
    ``viewer.state.camera`` is the current view), plus ``on_frame(result)``: called with every
    frame after it was sent to the browser (an exception there is shown under the image, as any
    other in the viewer's callbacks, and kept as ``viewer.last_error``). Needs ``anywidget`` (and
    with it ipywidgets): ``pip install anywidget``."""
    canvas_cls, box_cls = _widget_classes()
    import ipywidgets as widgets

    canvas = canvas_cls()
    stats = widgets.HTML()
    stats.add_class("geocull-stats")
    link = _Link(canvas, stats, on_frame)
    state = ViewerState(scene, width, height, culling, pixel_threshold, camera, renderer, link.show, min_distance,
                        z_scale, **render_options)
    link.state = state
    canvas.z_scale = state.z_scale
    canvas.on_msg(link.on_msg)
    mode, thr, zs, reset_button = _controls(state)
    link.zs = zs
    mode.observe(lambda ch: link.guarded("culling menu", state.set_culling, ch["new"]), names="value")
    thr.observe(lambda ch: link.guarded("pixel threshold slider", state.set_pixel_threshold, ch["new"]),
                names="value")
    reset_button.on_click(lambda _b: link.guarded("reset button", link.reset))
    zs.observe(lambda ch: link.slid(ch["new"]), names="value")
    canvas.observe(lambda ch: link.guarded("vertical exaggeration", link.apply_z, ch["new"]), names="z_scale")
    box = box_cls([canvas, widgets.HBox([mode, thr, zs, reset_button]), stats])
    link.box = box
    box.state = state
    box.canvas = canvas
    box.stats = stats
    box.controls = dict(culling=mode, pixel_threshold=thr, z_scale=zs, reset=reset_button)
    box.handle_message = lambda content: link.on_msg(canvas, content, [])
    box.last_error = None
    link.guarded("first frame", state.render)
    return box


def _widget_classes() -> tuple[Any, Any]:
    """The viewer's canvas (an anywidget with the browser side :data:`_ESM`) and its box (the
    canvas, the controls and the stats; with a PNG of the last frame where no widget can be drawn)."""
    try:
        import anywidget
        import ipywidgets as widgets
        import traitlets
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("geocull.Viewer needs anywidget (and ipywidgets): pip install anywidget") from e

    from .results import encode_png

    class _Canvas(anywidget.AnyWidget):
        _esm = _ESM
        frame = traitlets.Bytes(b"").tag(sync=True)
        width = traitlets.Int(0).tag(sync=True)
        height = traitlets.Int(0).tag(sync=True)
        frames = traitlets.Int(0).tag(sync=True)  # frames rendered (data-frames on the canvas)
        ack = traitlets.Dict().tag(sync=True)  # the last request answered: {"id", "seq", "kernel_ms"}
        epoch = traitlets.Int(0).tag(sync=True)  # bumped by "reset view": older motion is dropped
        error = traitlets.Unicode("").tag(sync=True)  # shown under the image; "" hides it
        png = traitlets.Unicode("").tag(sync=True)  # data: URL of the last frame, set by the browser at rest
        z_scale = traitlets.Float(1.0).tag(sync=True)  # vertical exaggeration: the slider, the keys, Python

    class _ViewerBox(widgets.VBox):
        def _repr_mimebundle_(self, **kwargs: Any) -> Any:
            data = super()._repr_mimebundle_(**kwargs)
            state = self.state
            if isinstance(data, dict) and state.result is not None:  # where no widget can be drawn
                data["image/png"] = base64.b64encode(encode_png(state.result.image)).decode("ascii")
                data["text/plain"] = f"geocull Viewer · {state.stats_text()}"
            return data

    return _Canvas, _ViewerBox


def _controls(state: ViewerState) -> tuple[Any, Any, Any, Any]:
    """The controls under the image: the culling menu, the pixel-threshold and vertical-exaggeration
    sliders (at the state's values) and the reset button."""
    import ipywidgets as widgets

    mode = widgets.Dropdown(options=list(CULLING_MODES), value=state.culling, description="culling")
    stops = sorted({*THRESHOLD_STOPS, float(state.pixel_threshold)})
    thr = widgets.SelectionSlider(options=[(f"{v:g}", v) for v in stops], value=float(state.pixel_threshold),
                                  description="pixels ≤", continuous_update=False)
    zs = widgets.SelectionSlider(options=_stops(Z_SCALE_STOPS, state.z_scale), value=state.z_scale,
                                 description="z ×", continuous_update=False)
    reset_button = widgets.Button(description="reset view")
    return mode, thr, zs, reset_button


class _Link:
    """A Viewer's callbacks between the browser, the controls and its :class:`ViewerState`: frames
    to the canvas, the browser's messages (views, its measurements), reset, the vertical
    exaggeration's slider and trait, and exceptions shown under the image."""

    state: ViewerState  # set by Viewer once the state exists (its on_frame is :meth:`show`)
    zs: Any  # the vertical-exaggeration slider, set by Viewer
    box: Any  # the widget, set by Viewer: its last_error

    def __init__(self, canvas: Any, stats: Any,
                 on_frame: Callable[[RenderResult[RenderStats]], object] | None) -> None:
        self.canvas = canvas
        self.stats = stats
        self.on_frame = on_frame
        self.syncing = False  # the slider follows the trait: its own events then are not the user's

    def stats_html(self) -> str:
        return f"<span style='font-family:monospace'>{self.state.stats_text()}</span>"

    def show(self, res: RenderResult[RenderStats]) -> None:
        canvas = self.canvas
        h, w = res.image.shape[:2]
        with canvas.hold_sync():
            canvas.width, canvas.height = int(w), int(h)
            canvas.frame = res.image.tobytes()
            canvas.frames = self.state.frames
        self.stats.value = self.stats_html()
        if self.on_frame is not None:
            self.on_frame(res)
        canvas.error = ""

    def guarded(self, what: str, fn: Callable[..., object], *args: Any) -> None:
        try:
            fn(*args)
        except Exception as e:  # noqa: BLE001 - shown under the image: the viewer must go on
            self.box.last_error = e
            self.canvas.error = _describe(what, e)

    def note_browser(self, content: dict[str, Any]) -> None:
        fps, lat = _opt_float(content.get("fps")), _opt_float(content.get("latency_ms"))
        if fps is not None:
            self.state.browser_fps = fps
        if lat is not None:
            self.state.browser_latency_ms = lat

    def view(self, content: dict[str, Any]) -> None:
        self.note_browser(content)
        if content.get("epoch", self.canvas.epoch) != self.canvas.epoch:
            return  # motion made before "reset view": dropped
        self.state.move(*(float(content.get(k) or 0.0) for k in ("dx", "dy", "wheel")))

    def on_msg(self, _widget: Any, content: Any, _buffers: Any) -> None:
        canvas = self.canvas
        if not isinstance(content, dict):
            return
        if content.get("type") == "stats":
            self.note_browser(content)
            if self.state.result is not None:
                self.stats.value = self.stats_html()
        elif content.get("type") == "view":
            t0 = time.perf_counter()
            if EARLY_NEXT:  # the browser may send its next request now: it waits behind this one
                canvas.send({"type": "started", "id": str(content.get("id")), "seq": content.get("seq")})
            with canvas.hold_sync():  # the frame and its answer in one update
                try:
                    self.guarded("drag/zoom", self.view, content)
                finally:
                    canvas.ack = {"id": str(content.get("id")), "seq": content.get("seq"),
                                  "kernel_ms": round((time.perf_counter() - t0) * 1000.0, 2)}

    def reset(self) -> None:
        self.canvas.epoch += 1  # first, so that the browser drops what it has queued
        self.state.reset()

    def apply_z(self, z: float) -> None:
        state, zs = self.state, self.zs
        state.set_z_scale(z)
        self.syncing = True
        try:
            if state.z_scale not in [v for _, v in zs.options]:  # a value from Python or the keys: a stop of its own
                zs.options = _stops([v for _, v in zs.options], state.z_scale)
            zs.value = state.z_scale
        finally:
            self.syncing = False

    def slid(self, z: float) -> None:
        if not self.syncing:
            self.canvas.z_scale = z
