"""The notebook viewer, headless: its callbacks (drag, wheel, culling mode, pixel threshold, reset)
change the camera and re-render, and the widget hands each frame to the browser as raw RGBA."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc
from geocull.data import stacked_test_scene
from geocull.viewer import DEGREES_PER_PIXEL, MAX_ELEVATION, ViewerState


@pytest.fixture(scope="module")
def scene():
    return stacked_test_scene(n=24, n_horizons=2).build(tiles=(3, 3), coarse_factor=4)


def test_state_drag_wheel_and_modes_rerender(scene, renderer_small):
    frames = []
    st = ViewerState(scene, renderer=renderer_small(48, 40), culling="none", on_frame=frames.append)
    first = st.render()
    az, el, d = st.azimuth, st.elevation, st.distance
    assert st.camera.orbit_angles() == pytest.approx((az, el, d))

    res = st.drag(10, 0)  # right: the eye moves clockwise seen from above
    assert st.azimuth == pytest.approx((az + 10 * DEGREES_PER_PIXEL) % 360) and st.elevation == pytest.approx(el)
    assert st.camera.eye != pytest.approx(gc.Camera.orbit(st.target, az, el, d).eye)
    assert not np.array_equal(res.image, first.image)  # the image follows the camera
    st.drag(0, 1000)  # far down: clamped short of straight down
    assert st.elevation == MAX_ELEVATION

    d0 = st.distance
    st.wheel(-100)  # scroll up: zoom in
    assert st.distance < d0
    st.wheel(100)
    assert st.distance == pytest.approx(d0)

    st.set_culling("three_pass")
    st.set_pixel_threshold(1000)
    assert st.result is not None and st.result.culling == "three_pass"
    assert st.result.stats["tiles_drawn"] < st.result.stats["tiles_total"]  # a huge threshold culls
    assert "three_pass" in st.stats_text() and "triangles" in st.stats_text()
    back = st.reset()
    assert st.camera.orbit_angles() == pytest.approx((az, el, d))
    assert back.culling == "three_pass"
    assert len(frames) == st.frames == 8
    with pytest.raises(gc.InputError, match="culling"):
        st.set_culling("bogus")


def test_orthographic_wheel_zooms_the_view_height(scene, renderer_small):
    cam = gc.Camera.fit(scene, projection="orthographic")
    st = ViewerState(scene, renderer=renderer_small(32, 32), camera=cam, culling="none")
    h0 = st.lens.ortho_height
    st.wheel(-200)
    assert h0 is not None and st.lens.ortho_height == pytest.approx(h0 / 1.15**2)
    assert st.camera.projection == "orthographic"


def test_widget_messages_drive_the_view(scene, renderer_small):
    pytest.importorskip("anywidget")
    v = gc.Viewer(scene, renderer=renderer_small(40, 32), culling="none")
    st, canvas = v.state, v.canvas
    assert (canvas.width, canvas.height) == (40, 32) and len(canvas.frame) == 40 * 32 * 4
    before = bytes(canvas.frame)
    az = st.azimuth
    v.handle_message({"type": "view", "dx": 25, "dy": -5, "wheel": 120})  # what the browser sends
    assert st.azimuth == pytest.approx((az + 25 * DEGREES_PER_PIXEL) % 360)
    assert canvas.frame != before  # a new frame went to the browser
    np.testing.assert_array_equal(np.frombuffer(canvas.frame, np.uint8).reshape(32, 40, 4), st.result.image)
    v.controls["culling"].value = "three_pass"
    assert st.culling == "three_pass" and "three_pass" in v.stats.value
    v.controls["pixel_threshold"].value = 100.0
    assert st.pixel_threshold == 100.0
    n = st.frames
    v.handle_message({"type": "other"})  # ignored
    assert st.frames == n


HARNESS = r"""
const handlers = {}, sent = [], drawn = [];
const listeners = {};
const canvas = {
  style: {}, width: 0, height: 0,
  addEventListener: (t, f) => { listeners[t] = f; },
  setPointerCapture: () => {},
  getContext: () => ({ putImageData: (img) => drawn.push([img.width, img.height, img.data.length]) }),
};
globalThis.document = { createElement: () => canvas };
globalThis.ImageData = class { constructor(d, w, h) { this.data = d; this.width = w; this.height = h; } };
const state = { width: 4, height: 2, frame: new DataView(new Uint8Array(32).buffer) };
const model = {
  get: (k) => state[k], on: (ev, f) => { handlers[ev] = f; }, send: (m) => sent.push(m),
};
const el = { appendChild: () => {} };
const mod = await import(process.argv[2]);
mod.default.render({ model, el });
const ev = (x, y) => ({ clientX: x, clientY: y, pointerId: 1 });
listeners.pointerdown(ev(0, 0));
listeners.pointermove(ev(5, 0));      // sent at once
listeners.pointermove(ev(12, 3));     // the frame is not back yet: merged
listeners.pointermove(ev(20, 3));
let prevented = 0;
listeners.wheel({ deltaY: 100, preventDefault: () => { prevented++; } });
handlers["change:frame"]();           // the frame arrives: drawn, then the merged moves go out
listeners.pointerup();
listeners.pointermove(ev(30, 3));     // not dragging: nothing
handlers["change:frame"]();
console.log(JSON.stringify({ sent, drawn, prevented }));
"""


def test_browser_code_merges_moves_while_a_frame_is_on_its_way(tmp_path):
    """The widget's JavaScript under node with a stand-in model and canvas: one request at a time,
    the moves made meanwhile merged into the next, frames drawn at the model's size."""
    import json
    import shutil
    import subprocess

    from geocull.viewer import _ESM

    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed")
    (tmp_path / "viewer.mjs").write_text(_ESM)
    (tmp_path / "harness.mjs").write_text(HARNESS)
    p = subprocess.run([node, str(tmp_path / "harness.mjs"), str(tmp_path / "viewer.mjs")],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["sent"] == [{"type": "view", "dx": 5, "dy": 0, "wheel": 0},
                           {"type": "view", "dx": 15, "dy": 3, "wheel": 100}]
    assert out["prevented"] == 1
    assert out["drawn"][-1] == [4, 2, 32] and len(out["drawn"]) == 3  # at render, then on each frame
