"""Drag-to-frame latency of the notebook Viewer in a real browser (JupyterLab + headless Chromium).

    .venv/bin/python scripts/viewer_latency.py [--seconds 6] [--size 137] [--width 640 --height 480]
        [--culling temporal] [--lod screen_error] [--early-next] [--json out/viewer_latency.json]

Opens a notebook with a Gullfaks-like scene (11 horizons of size x size samples and 4 faults: about
418 k triangles with the defaults) in a Viewer, presses the mouse on the image and moves it through
Chrome's input pipeline (DevTools Input.dispatchMouseEvent, one move every 16 ms, the eye circling
at 0.4 degree per pixel) for ``--seconds``, releases, and reads what the viewer's JavaScript logged
for every request: when its first mouse move happened, when it was sent, when its frame was on the
canvas, and how long the kernel spent on it. Reports frames per second while dragging, the latency
from a mouse move to its frame (median, 90th percentile), and where it goes: waiting for the
request before (queue), the kernel (render, read-back, copy), and the rest of the round trip
(transport: websocket, server, serialisation, drawing). Needs ``make browser``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from browser_harness import Lab  # noqa: E402

CELL = """
import json, os
import geocull as gc
import geocull.viewer
from geocull.data import gullfaks_like

geocull.viewer.EARLY_NEXT = {early}

spec = gullfaks_like(nx={size}, ny={size}, n_horizons=11, n_faults=4, fault_triangles=(2000, 6000))
scene = spec.build(tiles=(10, 10), coarse_factor=25)
v = gc.Viewer(scene, {width}, {height}, culling={culling!r}, lod={lod!r})
json.dump({{"triangles": int(scene.n_triangles)}},
          open(os.path.join(os.path.dirname(os.environ["GEOCULL_KERNEL_PIDFILE"]), "scene.json"), "w"))
v
"""


def drag_through_cdp(lab: Lab, seconds: float, step_px: float = 3.0, period_s: float = 0.016) -> tuple[float, float]:
    """Press on the canvas centre, move ``step_px`` per event every ``period_s`` (sideways, with a
    slow up-and-down), release; returns the page's performance.now() at the start and the end."""
    r = lab.js("const b = document.querySelector('.jp-OutputArea-output canvas').getBoundingClientRect();"
               "return [b.left + b.width / 2, b.top + b.height / 2];")
    x0, y0 = float(r[0]), float(r[1])
    cdp = lab.driver.execute_cdp_cmd
    t_start = float(lab.js("return performance.now();"))
    cdp("Input.dispatchMouseEvent", {"type": "mousePressed", "x": x0, "y": y0, "button": "left", "buttons": 1,
                                     "clickCount": 1})
    n, t_end_wall = 0, time.monotonic() + seconds
    x, y = x0, y0
    while time.monotonic() < t_end_wall:
        n += 1
        x = x0 + 40.0 * np.sin(n * step_px / 40.0)
        y = y0 + 20.0 * np.sin(n * step_px / 97.0)
        cdp("Input.dispatchMouseEvent", {"type": "mouseMoved", "x": x, "y": y, "button": "left", "buttons": 1})
        time.sleep(period_s)
    cdp("Input.dispatchMouseEvent", {"type": "mouseReleased", "x": x, "y": y, "button": "left", "buttons": 0,
                                     "clickCount": 1})
    t_end = float(lab.js("return performance.now();"))
    return t_start, t_end


def summarise(log: list[dict], t_start: float, t_end: float) -> dict:
    rows = [e for e in log if t_start <= e["input"] <= t_end]
    if len(rows) < 3:
        raise SystemExit(f"only {len(rows)} requests answered during the drag")
    a = {k: np.array([float(e[k]) for e in rows]) for k in ("input", "sent", "answered", "kernel_ms")}
    latency = a["answered"] - a["input"]
    roundtrip = a["answered"] - a["sent"]
    span = a["answered"][-1] - a["answered"][0]

    def stat(v: np.ndarray) -> dict:
        return {"median": round(float(np.median(v)), 1), "p90": round(float(np.percentile(v, 90)), 1),
                "max": round(float(v.max()), 1)}

    return {
        "requests": len(rows),
        "frames_per_s": round((len(rows) - 1) * 1000.0 / span, 1) if span > 0 else None,
        "latency_ms": stat(latency),
        "queue_ms": stat(a["sent"] - a["input"]),
        "roundtrip_ms": stat(roundtrip),
        "kernel_ms": stat(a["kernel_ms"]),
        "transport_ms": stat(roundtrip - a["kernel_ms"]),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=6.0)
    p.add_argument("--size", type=int, default=137)
    p.add_argument("--width", type=int, default=640)
    p.add_argument("--height", type=int, default=480)
    p.add_argument("--culling", default="temporal")
    p.add_argument("--lod", default="screen_error")
    p.add_argument("--repeat", type=int, default=2, help="drags measured (after one to warm up)")
    p.add_argument("--early-next", action="store_true",
                   help="the kernel says when it starts on a request, the browser queues one more (EARLY_NEXT)")
    p.add_argument("--json", default=None)
    a = p.parse_args()

    cell = CELL.format(size=a.size, width=a.width, height=a.height, culling=a.culling, lod=a.lod,
                       early=a.early_next)
    with tempfile.TemporaryDirectory(prefix="geocull-latency-") as d, \
            Lab([cell], Path(d), step_timeout=60.0) as lab:
        scene = json.loads((Path(d) / "scene.json").read_text())
        drag_through_cdp(lab, 1.5)  # warm up: the temporal history, the drivers' shader caches
        lab.settle(lab.token() or {})
        runs = []
        for _ in range(a.repeat):
            t0, t1 = drag_through_cdp(lab, a.seconds)
            lab.settle(lab.token() or {})
            log = lab.js("return document.querySelector('.jp-OutputArea-output canvas').geocullLog;")
            runs.append(summarise(log, t0, t1))
        time.sleep(0.8)  # the view rests: the browser reports its measures to the stats line
        stats_line = str(lab.js("for (const e of document.querySelectorAll('.jp-OutputArea-output "
                                ".widget-html-content')) if (e.innerText.includes('azimuth')) return e.innerText;"
                                "return '';"))
        errors = lab.console_errors()
    out = {"triangles": scene["triangles"], "width": a.width, "height": a.height, "culling": a.culling,
           "lod": a.lod, "early_next": a.early_next, "seconds": a.seconds, "runs": runs,
           "stats_line": stats_line, "console_errors": len(errors)}
    print(json.dumps(out, indent=1, ensure_ascii=False))
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(out, indent=1, ensure_ascii=False))


if __name__ == "__main__":
    main()
