"""The notebook viewer, headless: its callbacks (drag, wheel, culling mode, pixel threshold, reset)
change the camera and re-render, the widget hands each frame to the browser as raw RGBA and answers
every request (also when the frame is unchanged or a callback failed), and its JavaScript under node
(a stand-in model and DOM) keeps one request in flight. tests/test_browser.py drives it in Chromium."""

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


def test_wheel_stops_at_the_minimum_distance(scene, renderer_small):
    st = ViewerState(scene, renderer=renderer_small(32, 24), culling="none")
    lo, hi = (np.asarray(b) for b in scene.bounds)
    assert st.min_distance == pytest.approx(1e-3 * np.linalg.norm(hi - lo))
    for _ in range(80):
        st.wheel(-300)
    assert st.distance == pytest.approx(st.min_distance)  # never through the target
    st.wheel(100)
    assert st.distance == pytest.approx(st.min_distance * 1.15)
    st2 = ViewerState(scene, renderer=renderer_small(32, 24), culling="none", min_distance=500.0)
    st2.wheel(-10000)
    assert st2.distance == 500.0
    cam = gc.Camera.fit(scene, projection="orthographic")
    st3 = ViewerState(scene, renderer=renderer_small(32, 24), camera=cam, culling="none", min_distance=50.0)
    st3.wheel(-10000)
    assert st3.lens.ortho_height == pytest.approx(50.0)
    with pytest.raises(gc.InputError, match="min_distance"):
        ViewerState(scene, renderer=renderer_small(32, 24), min_distance=0.0)


def _view(v, seq, epoch=0, **motion):
    v.handle_message({"type": "view", "id": "v1", "seq": seq, "epoch": epoch, **motion})
    return v.canvas.ack


def test_every_request_is_answered_even_when_the_frame_is_the_same(scene, renderer_small):
    pytest.importorskip("anywidget")
    v = gc.Viewer(scene, renderer=renderer_small(40, 32), culling="none")
    st, canvas = v.state, v.canvas
    assert canvas.frames == st.frames == 1
    ack = _view(v, 1, dy=1000)  # up to the elevation limit: a new image
    assert st.elevation == MAX_ELEVATION and (ack["id"], ack["seq"]) == ("v1", 1) and ack["kernel_ms"] >= 0
    frame = bytes(canvas.frame)
    ack = _view(v, 2, dy=1000)  # past it: the same image, answered all the same
    assert bytes(canvas.frame) == frame and ack["seq"] == 2 and canvas.frames == st.frames == 3
    for i in range(60):  # down to the minimum distance: the last turns give the same view
        ack = _view(v, 3 + i, wheel=-500)
    assert ack["seq"] == 62 and st.distance == pytest.approx(st.min_distance) and canvas.frames == 63
    _view(v, 63, wheel="junk")  # a request that fails is answered too, and the error shown
    assert canvas.ack["seq"] == 63 and "drag/zoom" in canvas.error and isinstance(v.last_error, ValueError)
    _view(v, 64, dx=10)  # the next good frame clears it
    assert canvas.error == "" and canvas.ack["seq"] == 64


def test_the_kernel_says_when_it_starts_on_a_request(scene, renderer_small, monkeypatch):
    pytest.importorskip("anywidget")
    import geocull.viewer as gv

    v = gc.Viewer(scene, renderer=renderer_small(40, 32), culling="none")
    said = []
    monkeypatch.setattr(v.canvas, "send", lambda content, buffers=None: said.append((content, v.state.frames)))
    n = v.state.frames
    _view(v, 6, dx=3)
    assert said == [] and v.canvas.ack["seq"] == 6  # off by default: one request at a time
    monkeypatch.setattr(gv, "EARLY_NEXT", True)
    _view(v, 7, dx=3)
    assert said == [({"type": "started", "id": "v1", "seq": 7}, n + 1)]  # before the frame was rendered
    assert v.canvas.ack["seq"] == 7 and v.state.frames == n + 2


def test_reset_drops_motion_from_before_it(scene, renderer_small):
    pytest.importorskip("anywidget")
    v = gc.Viewer(scene, renderer=renderer_small(40, 32), culling="none")
    st, canvas = v.state, v.canvas
    home = st.camera.orbit_angles()
    _view(v, 1, dx=40, dy=75)
    v.controls["reset"].click()
    assert canvas.epoch == 1 and st.camera.orbit_angles() == pytest.approx(home)
    n = st.frames
    ack = _view(v, 2, epoch=0, dx=40, dy=75)  # sent before the browser heard of the reset: dropped
    assert ack["seq"] == 2 and st.frames == n and st.camera.orbit_angles() == pytest.approx(home)
    _view(v, 3, epoch=1, dx=10)  # made after it: applied
    assert st.azimuth == pytest.approx((home[0] + 10 * DEGREES_PER_PIXEL) % 360)


def test_callback_errors_are_shown_and_the_viewer_goes_on(scene, renderer_small):
    pytest.importorskip("anywidget")
    seen, boom = [], {"on": False}

    def on_frame(res):
        seen.append(res)
        if boom["on"]:
            raise RuntimeError("boom")

    v = gc.Viewer(scene, renderer=renderer_small(40, 32), culling="none", on_frame=on_frame)
    canvas = v.canvas
    assert len(seen) == 1 and canvas.error == ""
    boom["on"] = True
    v.controls["culling"].value = "frustum"
    assert canvas.error.startswith("Error in the viewer's culling menu: RuntimeError: boom")
    assert "Traceback" in canvas.error and isinstance(v.last_error, RuntimeError)
    v.controls["pixel_threshold"].value = 0.0  # the slider reaches 0
    assert v.state.pixel_threshold == 0.0 and "pixel threshold slider" in canvas.error
    boom["on"] = False
    ack = _view(v, 1, dx=5)
    assert canvas.error == "" and ack["seq"] == 1 and len(seen) == 4


def test_browser_measures_in_the_stats_line_and_a_png_for_static_outputs(scene, renderer_small):
    pytest.importorskip("anywidget")
    import base64

    v = gc.Viewer(scene, renderer=renderer_small(40, 32), culling="none")
    assert "browser" not in v.stats.value and "render" in v.stats.value
    v.handle_message({"type": "stats", "fps": 14.6, "latency_ms": 93.4})
    assert "browser: 14.6 frames/s, 93 ms drag→frame" in v.stats.value
    v.handle_message({"type": "stats", "fps": None, "latency_ms": "nan"})  # nothing measured: kept
    assert "14.6 frames/s" in v.stats.value
    bundle = v._repr_mimebundle_()
    assert bundle["application/vnd.jupyter.widget-view+json"]["model_id"] == v.model_id
    png = base64.b64decode(bundle["image/png"])
    assert png == gc.results.encode_png(v.state.result.image)
    assert bundle["text/plain"].startswith("geocull Viewer")


def test_z_scale_rerenders_with_that_vertical_exaggeration(scene, renderer_small):
    r = renderer_small(48, 40)
    frames = []
    st = ViewerState(scene, renderer=r, culling="none", on_frame=frames.append)
    first = st.render()
    assert st.z_scale == 1.0 and st.camera.z_scale == 1.0
    angles = (st.azimuth, st.elevation, st.distance)
    res = st.set_z_scale(5.0)
    assert len(frames) == 2 and st.camera.z_scale == 5.0
    assert (st.azimuth, st.elevation, st.distance) == angles  # the view is kept
    np.testing.assert_array_equal(res.image, r.render(scene, st.camera, culling="none").image)
    assert not np.array_equal(res.image, first.image) and "z ×5" in st.stats_text()
    st.reset()  # back to the default view, fitted at the exaggeration in use
    assert st.z_scale == 5.0 and st.camera.z_scale == 5.0
    assert st.camera.orbit_angles() == pytest.approx(gc.Camera.fit(scene, 210, 30, aspect=48 / 40,
                                                                   z_scale=5.0).orbit_angles())
    for bad in (0, -2, float("nan"), "x"):
        with pytest.raises(gc.InputError, match="^z_scale"):
            st.set_z_scale(bad)
    assert st.z_scale == 5.0 and len(frames) == 3
    cam = gc.Camera.fit(scene, z_scale=2.0)
    assert ViewerState(scene, renderer=r, camera=cam).z_scale == 2.0  # the camera's by default ...
    assert ViewerState(scene, renderer=r, camera=cam, z_scale=3.0).camera.z_scale == 3.0  # ... or given


def test_widget_z_scale_trait_and_slider_rerender(scene, renderer_small):
    pytest.importorskip("anywidget")
    v = gc.Viewer(scene, renderer=renderer_small(40, 32), culling="none")
    st, canvas, slider = v.state, v.canvas, v.controls["z_scale"]
    assert canvas.z_scale == slider.value == 1.0 and st.frames == 1
    canvas.z_scale = 4.0  # the trait (what the browser's keys set): a new frame at that exaggeration
    assert st.z_scale == 4.0 and st.camera.z_scale == 4.0 and st.frames == 2
    np.testing.assert_array_equal(np.frombuffer(canvas.frame, np.uint8).reshape(32, 40, 4), st.result.image)
    np.testing.assert_array_equal(st.result.image, v.state.renderer.render(scene, st.camera, culling="none").image)
    assert slider.value == 4.0  # a value between the stops becomes a stop of the slider
    slider.value = 10.0
    assert canvas.z_scale == 10.0 and st.camera.z_scale == 10.0 and st.frames == 3
    assert "z ×10" in v.stats.value
    canvas.z_scale = 0.0  # refused, shown under the image; the viewer goes on
    assert "vertical exaggeration" in canvas.error and st.z_scale == 10.0
    canvas.z_scale = 2.0
    assert canvas.error == "" and st.camera.z_scale == 2.0
    assert gc.Viewer(scene, renderer=renderer_small(40, 32), z_scale=3.0).canvas.z_scale == 3.0


KEYS_HARNESS = r"""
const state = { width: 1, height: 1, frame: null, frames: 0, epoch: 0, ack: {}, error: "", png: "", z_scale: 1 };
const saved = [], made = [];
globalThis.document = { createElement: (tag) => { const listeners = {}; const e = {
  tag, style: {}, dataset: {}, listeners, appendChild() {}, addEventListener(t, f) { listeners[t] = f; },
  getContext() { return {}; } }; made.push(e); return e; } };
const model = { get: (k) => state[k], set: (k, v) => { state[k] = v; }, save_changes: () => saved.push(state.z_scale),
                send() {}, on() {} };
const mod = await import(process.argv[2]);
mod.default.render({ model, el: { appendChild() {} } });
const canvas = made.find((e) => e.tag === "canvas");
const key = (k) => canvas.listeners.keydown({ key: k, preventDefault() {} });
key("+"); key("="); key("-"); key("-"); key("-"); key("-"); key("a");
state.z_scale = 7; key("+"); key("-");
console.log(JSON.stringify({ saved, tabIndex: canvas.tabIndex }));
"""


def test_browser_keys_step_the_z_scale(tmp_path):
    """"+" / "-" on the focused image step the synced z_scale through Z_SCALE_STOPS (under node)."""
    import json
    import shutil
    import subprocess

    from geocull.viewer import _ESM, Z_SCALE_STOPS

    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed")
    (tmp_path / "viewer.mjs").write_text(_ESM)
    (tmp_path / "keys.mjs").write_text(KEYS_HARNESS)
    p = subprocess.run([node, str(tmp_path / "keys.mjs"), str(tmp_path / "viewer.mjs")],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert Z_SCALE_STOPS[:3] == (0.5, 1.0, 2.0) and 10.0 in Z_SCALE_STOPS and 5.0 in Z_SCALE_STOPS
    # 1 -> 2 -> 3, then down 2, 1, 0.5 and no lower; other keys nothing; from 7: up to 10, then down to 5.
    assert out["saved"] == [2, 3, 2, 1, 0.5, 10, 5]
    assert out["tabIndex"] == 0


HARNESS = r"""
const sent = [], drawn = [], saved = [], handlers = {};
function element(tag) {
  const listeners = {};
  return {
    tag, style: {}, dataset: {}, children: [], listeners, width: 0, height: 0, textContent: "",
    appendChild(c) { this.children.push(c); },
    addEventListener(t, f) { listeners[t] = f; },
    setPointerCapture() {},
    getContext() { return { putImageData: (img) => drawn.push([img.width, img.height, img.data.length]) }; },
    toDataURL() { return "data:image/png;base64,AAAA"; },
  };
}
const made = [];
globalThis.document = { createElement: (t) => { const e = element(t); made.push(e); return e; } };
globalThis.ImageData = class { constructor(d, w, h) { this.data = d; this.width = w; this.height = h; } };
const buf = (v) => new DataView(new Uint8Array(32).fill(v).buffer);
const state = { width: 4, height: 2, frame: buf(1), frames: 1, epoch: 0, ack: {}, error: "", png: "" };
const model = {
  get: (k) => state[k],
  set: (k, v) => { state[k] = v; },
  save_changes: () => saved.push(state.png),
  send: (m) => sent.push(JSON.parse(JSON.stringify(m))),
  on: (ev, f) => { (handlers[ev] = handlers[ev] || []).push(f); },
};
function update(changes) {  // a state update from the kernel: change:<name> for each key, then change
  Object.assign(state, changes);
  for (const k of Object.keys(changes)) (handlers["change:" + k] || []).forEach((f) => f());
  (handlers["change"] || []).forEach((f) => f());
}
const el = { appendChild: () => {} };
const mod = await import(process.argv[2]);
mod.default.render({ model, el });
const canvas = made.find((e) => e.tag === "canvas"), error = made.find((e) => e.tag === "pre");
const L = canvas.listeners, ev = (x, y) => ({ clientX: x, clientY: y, pointerId: 1 });
const out = { steps: {} };
L.pointerdown(ev(0, 0));
L.pointermove(ev(5, 0));                       // sent at once
L.pointermove(ev(12, 3));                      // a request is in flight: merged
L.pointermove(ev(20, 3));
L.wheel({ deltaY: 100, preventDefault: () => { out.prevented = true; } });
const id = sent[0].id;
update({ ack: { id: "another view", seq: 1 } }); // another view's answer: not ours
out.steps.otherView = sent.length;
update({ frame: buf(2), frames: 2, ack: { id, seq: 1, kernel_ms: 3 } });  // drawn, then the merged moves go out
out.steps.afterFirst = sent.length;
update({ frames: 3, ack: { id, seq: 2, kernel_ms: 2 } });  // the same image (no frame): still an answer
L.pointermove(ev(30, 3));                      // so the next move goes out at once
out.steps.afterSameImage = sent.length;
L.pointerup();
L.pointermove(ev(40, 3));                      // not dragging: nothing
L.wheel({ deltaY: -50, preventDefault: () => {} });  // queued behind request 3 ...
update({ epoch: 1 });                          // ... and dropped by "reset view"
update({ frame: buf(3), frames: 4, ack: { id, seq: 3, kernel_ms: 2 } });
out.steps.afterReset = sent.length;
L.wheel({ deltaY: -50, preventDefault: () => {} });  // after the reset: sent, with the new epoch
update({ frames: 5, ack: { id, seq: 4, kernel_ms: 2 } });
const custom = (m) => (handlers["msg:custom"] || []).forEach((f) => f(m));
L.pointerdown(ev(0, 0));
L.pointermove(ev(1, 0));                       // request 5
L.pointermove(ev(3, 0));                       // queued
custom({ type: "started", id: "another view", seq: 5 });
out.steps.otherStarted = sent.length;
custom({ type: "started", id, seq: 5 });       // the kernel is on 5: the queued motion goes out as 6 ...
out.steps.afterStarted = sent.length;
L.pointermove(ev(6, 0));                       // ... but 7 waits: 6 has not started
out.steps.secondWaits = sent.length;
update({ frames: 6, ack: { id, seq: 5, kernel_ms: 2 } });  // 5 answered; 6 not started yet: 7 still waits
out.steps.afterFifth = sent.length;
update({ frames: 7, ack: { id, seq: 6, kernel_ms: 2 } });  // 6 answered: 7 goes out
out.steps.afterSixth = sent.length;
update({ frames: 8, ack: { id, seq: 7, kernel_ms: 2 } });
L.pointerup();
update({ error: "Error in the viewer's drag/zoom: RuntimeError: boom" });
out.error = [error.textContent, error.style.display];
await new Promise((r) => setTimeout(r, 700));  // the view rests: measures reported, frame kept as PNG
out.sent = sent; out.drawn = drawn; out.saved = saved;
out.dataset = canvas.dataset;
update({ error: "" });
out.errorCleared = error.style.display;
console.log(JSON.stringify(out));
"""


def test_browser_code_answers_merging_and_reset(tmp_path):
    """The widget's JavaScript under node with a stand-in model and DOM: one request at a time, the
    moves made meanwhile merged into the next; an answer releases the next request whether or not
    it brings a new image; answers for other views are ignored; "reset view" (a new epoch) drops
    the queued motion; once the kernel says it started on a request, one more may wait behind it
    (never two); errors show under the image; at rest the browser reports its measures and keeps
    the frame as PNG in the model."""
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
    views = [m for m in out["sent"] if m["type"] == "view"]
    motion = [(m["seq"], m["epoch"], m["dx"], m["dy"], m["wheel"]) for m in views]
    assert motion == [(1, 0, 5, 0, 0), (2, 0, 15, 3, 100), (3, 0, 10, 0, 0), (4, 1, 0, 0, -50),
                      (5, 1, 1, 0, 0), (6, 1, 2, 0, 0), (7, 1, 3, 0, 0)]
    assert len({m["id"] for m in views}) == 1
    assert out["steps"] == {"otherView": 1, "afterFirst": 2, "afterSameImage": 3, "afterReset": 3,
                            "otherStarted": 5, "afterStarted": 6, "secondWaits": 6, "afterFifth": 6,
                            "afterSixth": 7}
    assert out["prevented"] is True
    assert len(out["drawn"]) == 3 and out["drawn"][-1] == [4, 2, 32]  # at render, then each new frame
    assert out["dataset"]["frames"] == "8" and out["dataset"]["pending"] == "0"
    assert float(out["dataset"]["latency"]) >= 0 and out["dataset"]["kernelMs"] == "2"
    assert views[-1]["latency_ms"] is not None  # the measures ride on the requests ...
    stats = [m for m in out["sent"] if m["type"] == "stats"]
    assert len(stats) == 1 and stats[0]["latency_ms"] is not None  # ... and are reported at rest
    assert out["saved"] == ["data:image/png;base64,AAAA"]
    assert out["error"] == ["Error in the viewer's drag/zoom: RuntimeError: boom", "block"]
    assert out["errorCleared"] == "none"
