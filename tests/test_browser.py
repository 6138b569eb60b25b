"""The notebook viewer in a real browser: JupyterLab serves a notebook with a Viewer, headless
Chromium drives it through selenium as a user would (tests/browser_harness.py), and after every step
a frame must arrive: the viewer's frame counter moves on even when the image is the same as the
last one (a drag past the elevation limit, a wheel turn at the minimum distance, a culling mode that
draws the same picture). It was written against a viewer that froze there for good.

Runs under ``make test-browser`` (which installs chromium, chromium-driver, JupyterLab and selenium
and sets GEOCULL_BROWSER_TEST=1); skipped otherwise.
"""

from __future__ import annotations

import os
import re
import time

import pytest

pytestmark = pytest.mark.skipif(os.environ.get("GEOCULL_BROWSER_TEST") != "1",
                                reason="the browser test runs under make test-browser")

VIEWER_CELL = """
import geocull as gc
from geocull.data import stacked_test_scene

scene = stacked_test_scene(n=48, n_horizons=3).build(tiles=(4, 4), coarse_factor=4)
boom = {"on": False}

def on_frame(res):
    if boom["on"]:
        raise RuntimeError("boom from the test's on_frame callback")

v = gc.Viewer(scene, 320, 240, culling="none", on_frame=on_frame)
v
"""

ERROR = ".geocull-error"


def _stats(lab) -> str:
    """The viewer's stats line (the HTML under the controls that reports the view)."""
    return str(lab.js("for (const e of document.querySelectorAll('.jp-OutputArea-output .widget-html-content'))"
                      "  if (e.innerText.includes('azimuth')) return e.innerText;"
                      "return '';"))


def _distance(stats: str) -> str:
    m = re.search(r"distance ([\d,.]+) m", stats)
    assert m, stats
    return m.group(1)


def test_viewer_answers_every_step_in_jupyterlab(tmp_path):
    import geocull as gc
    from browser_harness import Lab

    t0 = time.monotonic()
    with Lab([VIEWER_CELL], tmp_path) as lab:
        t = lab.token()
        assert t is not None and (t["w"], t["h"]) == (320, 240) and t["lit"] > 1000

        # Down past the elevation limit: the first drag reaches it (a new image), the second asks for
        # a view that the limit makes identical to the last one, and must be answered all the same.
        lab.drag(0, 200)
        t = lab.wait_frame(t, "drag down to the elevation limit", changed=True)
        assert "elevation 90°" in _stats(lab)
        lab.drag(0, 120)
        t = lab.wait_frame(t, "drag past the elevation limit (the same image)")
        lab.drag(80, 0)
        t = lab.wait_frame(t, "drag sideways after the limit", changed=True)

        # Into the scene down to the minimum distance (the last turns give the same view), out again.
        distances = []
        for i in range(16):
            lab.wheel(-400)
            t = lab.wait_frame(t, f"wheel in, turn {i + 1}")
            distances.append(_distance(_stats(lab)))
        assert distances[-1] == distances[-2] and float(distances[-1].replace(",", "")) > 0, distances
        for i in range(16):
            lab.wheel(400)
            t = lab.wait_frame(t, f"wheel out, turn {i + 1}")
        assert _distance(_stats(lab)) != distances[-1]

        for mode in [m for m in gc.CULLING_MODES if m != "none"] + ["none"]:
            lab.select(mode)
            t = lab.wait_frame(t, f"culling mode {mode}")
            assert _stats(lab).startswith(f"{mode}:"), _stats(lab)

        lab.select("three_pass")
        t = lab.wait_frame(t, "culling mode three_pass")
        lab.slider_to_start()
        t = lab.wait_frame(t, "pixel threshold slider to 0")
        assert lab.text(".widget-slider .widget-readout").strip() == "0"

        lab.click_button("reset view")
        t = lab.wait_frame(t, "reset view", changed=True)
        assert "azimuth 210°, elevation 30°" in _stats(lab), _stats(lab)

        # An exception in a callback is shown under the image; the viewer goes on.
        assert lab.run_in_kernel("boom['on'] = True") == "ok"
        lab.drag(40, 0)
        lab._wait(lambda: "boom from the test's on_frame callback" in lab.text(ERROR), lab.step_timeout,
                  "the callback's error was not shown")
        under = lab.js("const c = document.querySelector('.jp-OutputArea-output canvas'), "
                       "e = document.querySelector(arguments[0]);"
                       "return e.getBoundingClientRect().top >= c.getBoundingClientRect().bottom;", ERROR)
        assert under, "the error is not under the image"
        t = lab.settle(lab.token() or t)
        assert lab.run_in_kernel("boom['on'] = False") == "ok"
        lab.drag(40, 0)
        t = lab.wait_frame(t, "drag after the error", changed=True)
        assert lab.text(ERROR).strip() == ""

        # At rest the browser keeps the frame as PNG in the widget's state (what a saved notebook keeps).
        lab._wait(lambda: lab.run_in_kernel("assert v.canvas.png.startswith('data:image/png;base64,')") == "ok",
                  lab.step_timeout, "the frame was not kept as PNG in the widget's state")

        errors = lab.console_errors()
        assert not errors, errors
    assert time.monotonic() - t0 < 180
