"""JupyterLab and headless Chromium for driving the notebook viewer as a user would (used by
tests/test_browser.py and scripts/viewer_latency.py; needs jupyterlab, selenium, chromium and
chromedriver: ``make browser`` installs them).

:class:`Lab` writes a notebook into a temporary folder, starts JupyterLab on 127.0.0.1 (a free
port, no token, its own config/runtime/settings folders, the app exposed as ``window.jupyterapp``),
opens the notebook in Chromium through chromedriver, runs every cell and waits for the Viewer's
canvas. Its methods drag, turn the wheel, pick controls and read the frame state the page shows.
:meth:`Lab.close` always ends what it started: the browser (and any Chromium process left on its
profile folder), the kernel (its pid is written by the notebook) and the server's process group.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

#: Code of the notebook's first cell that writes the kernel's pid (so that close() can end it).
PID_CELL = "import os\nopen(os.environ['GEOCULL_KERNEL_PIDFILE'], 'w').write(str(os.getpid()))"

# The first canvas of the notebook's outputs and what it shows: the viewer's frame counter
# (data-frames, absent on a viewer without one) and a hash of its pixels.
_TOKEN_JS = """
const c = document.querySelector('.jp-OutputArea-output canvas');
if (!c || !c.width || !c.height) return null;
const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
let h = 0, lit = 0;
for (let i = 0; i < d.length; i += 4) {
  h = (Math.imul(h, 31) + d[i] + 7 * d[i + 1] + 13 * d[i + 2] + 17 * d[i + 3]) | 0;
  if (d[i + 3] !== 0) lit++;
}
return { frames: c.dataset.frames === undefined ? null : Number(c.dataset.frames), hash: h, lit: lit,
         w: c.width, h: c.height };
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def notebook_json(cells: list[str]) -> str:
    return json.dumps({
        "cells": [{"cell_type": "code", "execution_count": None, "id": f"c{i}", "metadata": {}, "outputs": [],
                   "source": src} for i, src in enumerate(cells)],
        "metadata": {"kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"}},
        "nbformat": 4, "nbformat_minor": 5,
    })


class StepTimeout(AssertionError):
    pass


def _terminate(signum: int, _frame: object) -> None:
    raise SystemExit(f"browser test ended by signal {signum}")


class Lab:
    """One JupyterLab server and one headless Chromium showing a notebook made of ``cells`` (the
    pid cell is put first). ``step_timeout``: seconds a step may wait for the page."""

    def __init__(self, cells: list[str], workdir: Path, window: tuple[int, int] = (1400, 1100),
                 step_timeout: float = 20.0) -> None:
        self.cells = [PID_CELL, *cells]
        self.dir = Path(workdir)
        self.window = window
        self.step_timeout = step_timeout
        self.server: subprocess.Popen[bytes] | None = None
        self.driver: Any = None
        self.console: list[dict[str, Any]] = []
        self.port = 0

    # --- starting and stopping ---------------------------------------------------------------
    def __enter__(self) -> Lab:
        # A SIGTERM (`timeout` in make test-browser) unwinds through close() instead of leaving the
        # server and the browser running in their own sessions.
        self._old_term = signal.signal(signal.SIGTERM, _terminate)
        try:
            self.start()
        except BaseException:
            self.keep_evidence()
            self.close()
            raise
        return self

    def __exit__(self, exc_type: object, *exc: object) -> None:
        if exc_type is not None:
            self.keep_evidence()
        self.close()

    def keep_evidence(self) -> None:
        """A screenshot (failure.png) and the console (console.json) in the Lab's folder, printed paths."""
        if self.driver is None:
            return
        try:
            self.driver.save_screenshot(str(self.dir / "failure.png"))
            self.console += self.driver.get_log("browser")
            (self.dir / "console.json").write_text(json.dumps(self.console, indent=1))
            print(f"browser evidence: {self.dir / 'failure.png'}, {self.dir / 'console.json'}, "
                  f"{self.dir / 'jupyter.log'}")
        except Exception as e:  # noqa: BLE001 - evidence is best effort
            print(f"browser evidence not kept: {e}")

    def start(self) -> None:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        for sub in ("nb", "config", "data", "runtime", "settings", "workspaces", "ipython", "chrome"):
            (self.dir / sub).mkdir(parents=True, exist_ok=True)
        (self.dir / "nb" / "viewer.ipynb").write_text(notebook_json(self.cells))
        self.port = free_port()
        env = dict(os.environ, JUPYTER_CONFIG_DIR=str(self.dir / "config"),
                   JUPYTER_RUNTIME_DIR=str(self.dir / "runtime"), JUPYTERLAB_SETTINGS_DIR=str(self.dir / "settings"),
                   JUPYTERLAB_WORKSPACES_DIR=str(self.dir / "workspaces"), IPYTHONDIR=str(self.dir / "ipython"),
                   GEOCULL_KERNEL_PIDFILE=str(self.dir / "kernel.pid"), JUPYTER_PLATFORM_DIRS="1")
        self.log = open(self.dir / "jupyter.log", "wb")  # noqa: SIM115 - closed in close()
        self.server = subprocess.Popen(
            [sys.executable, "-m", "jupyterlab", "--no-browser", "--ServerApp.ip=127.0.0.1",
             f"--ServerApp.port={self.port}", "--ServerApp.port_retries=0", "--IdentityProvider.token=",
             "--ServerApp.password=", "--ServerApp.allow_root=True", f"--ServerApp.root_dir={self.dir / 'nb'}",
             "--LabApp.expose_app_in_browser=True", "--LabApp.extension_manager=readonly"],
            cwd=self.dir / "nb", env=env, stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True,
        )
        self._wait(self._server_up, 60, "JupyterLab did not answer on /api/status")

        opts = webdriver.ChromeOptions()
        opts.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
        for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                  "--disable-extensions", "--no-first-run", f"--window-size={self.window[0]},{self.window[1]}",
                  f"--user-data-dir={self.dir / 'chrome'}"):
            opts.add_argument(a)
        opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        service = Service(executable_path=shutil.which("chromedriver") or "/usr/bin/chromedriver",
                          log_output=str(self.dir / "chromedriver.log"))
        self.driver = webdriver.Chrome(options=opts, service=service)
        self.driver.set_script_timeout(60)
        self.driver.get(f"http://127.0.0.1:{self.port}/lab/tree/viewer.ipynb")
        self._wait(lambda: self.js("""
            const app = window.jupyterapp, w = app && app.shell.currentWidget;
            const k = w && w.sessionContext && w.sessionContext.session && w.sessionContext.session.kernel;
            return !!(k && k.connectionStatus === 'connected' && k.status === 'idle' && w.content.widgets.length);
        """), 90, "the notebook's kernel did not become idle")
        self.js("window.jupyterapp.commands.execute('notebook:run-all-cells');")
        self._wait(lambda: (self.token() or {}).get("lit", 0) > 0, 90, "the viewer's first frame did not appear")

    def _server_up(self) -> bool:
        assert self.server is not None
        if self.server.poll() is not None:
            raise RuntimeError(f"JupyterLab exited: {(self.dir / 'jupyter.log').read_text()[-3000:]}")
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{self.port}/api/status", timeout=2) as r:
                return bool(r.status == 200)
        except OSError:
            return False

    def close(self) -> None:
        """End the browser, the kernel and the server (each by its own pid or process group)."""
        if self.driver is not None:
            try:
                self.console += self.driver.get_log("browser")
            except Exception:  # noqa: BLE001 - the browser may already be gone
                pass
            try:
                self.driver.quit()
            except Exception:  # noqa: BLE001
                pass
            self.driver = None
        self._kill_own_chromium()
        pidfile = self.dir / "kernel.pid"
        if pidfile.exists():
            try:
                os.kill(int(pidfile.read_text()), signal.SIGKILL)
            except (OSError, ValueError):
                pass
        if self.server is not None:
            for sig, wait in ((signal.SIGTERM, 10.0), (signal.SIGKILL, 5.0)):
                try:
                    os.killpg(self.server.pid, sig)
                except OSError:
                    break
                try:
                    self.server.wait(timeout=wait)
                    break
                except subprocess.TimeoutExpired:
                    continue
            self.server = None
        if getattr(self, "log", None) is not None:
            self.log.close()
        if getattr(self, "_old_term", None) is not None:
            signal.signal(signal.SIGTERM, self._old_term)
            self._old_term = None

    def _kill_own_chromium(self) -> None:
        """Chromium processes still running on this Lab's profile folder (none after a clean quit)."""
        marker = f"--user-data-dir={self.dir / 'chrome'}".encode()
        for p in Path("/proc").iterdir():
            if not p.name.isdigit():
                continue
            try:
                if marker in (p / "cmdline").read_bytes():
                    os.kill(int(p.name), signal.SIGKILL)
            except OSError:
                pass

    # --- reading the page ----------------------------------------------------------------------
    def js(self, script: str, *args: Any) -> Any:
        return self.driver.execute_script(script, *args)

    def _wait(self, cond: Any, timeout: float, what: str) -> Any:
        deadline = time.monotonic() + timeout
        while True:
            v = cond()
            if v:
                return v
            if time.monotonic() > deadline:
                raise StepTimeout(f"{what} within {timeout:.0f} s")
            time.sleep(0.05)

    def token(self) -> dict[str, Any] | None:
        """The canvas's frame counter (None on a viewer without one) and pixel hash; None before it shows."""
        t: dict[str, Any] | None = self.js(_TOKEN_JS)
        return t

    def canvas(self) -> Any:
        from selenium.webdriver.common.by import By

        return self.driver.find_element(By.CSS_SELECTOR, ".jp-OutputArea-output canvas")

    def wait_frame(self, before: dict[str, Any], what: str, changed: bool = False) -> dict[str, Any]:
        """Wait until a frame answers the step just made: the frame counter moved on (or, on a viewer
        without a counter, the image changed); ``changed``: the image must differ too. Then wait
        until the viewer is quiet (no request in flight, the counter still for 0.3 s)."""
        def arrived() -> dict[str, Any] | None:
            now = self.token()
            if now is None:
                return None
            if now["frames"] is not None and before["frames"] is not None:
                ok = now["frames"] > before["frames"] and (not changed or now["hash"] != before["hash"])
            else:
                ok = now["hash"] != before["hash"]
            return now if ok else None

        try:
            now = self._wait(arrived, self.step_timeout, f"{what}: no frame arrived")
        except StepTimeout as e:
            raise StepTimeout(f"{e} (before: {before}, now: {self.token()})") from None
        return self.settle(now)

    def settle(self, now: dict[str, Any]) -> dict[str, Any]:
        last, since = now, time.monotonic()
        deadline = since + self.step_timeout
        while time.monotonic() - since < 0.3 and time.monotonic() < deadline:
            time.sleep(0.05)
            t = self.token()
            busy = self.js("const c = document.querySelector('.jp-OutputArea-output canvas');"
                           "return !!(c && c.dataset.pending === '1');")
            if t != last or busy:
                last, since = t or last, time.monotonic()
        return last

    def text(self, css: str) -> str:
        return str(self.js("const e = document.querySelector(arguments[0]); return e ? e.innerText : '';", css))

    def console_errors(self) -> list[dict[str, Any]]:
        """Every SEVERE entry of the browser console so far."""
        if self.driver is not None:
            self.console += self.driver.get_log("browser")
        return [e for e in self.console if e.get("level") == "SEVERE"]

    # --- acting as a user ----------------------------------------------------------------------
    def drag(self, dx: int, dy: int, steps: int = 4) -> None:
        """Press on the canvas's centre, move by (dx, dy) pixels in ``steps`` moves, release."""
        from selenium.webdriver.common.action_chains import ActionChains

        a = ActionChains(self.driver, duration=20).move_to_element(self.canvas()).click_and_hold()
        for i in range(steps):
            a = a.move_by_offset(dx * (i + 1) // steps - dx * i // steps, dy * (i + 1) // steps - dy * i // steps)
        a.release().perform()

    def wheel(self, delta_y: int) -> None:
        """One wheel turn over the canvas (> 0: scroll down = zoom out)."""
        from selenium.webdriver.common.action_chains import ActionChains
        from selenium.webdriver.common.actions.wheel_input import ScrollOrigin

        ActionChains(self.driver).scroll_from_origin(ScrollOrigin.from_element(self.canvas()), 0, delta_y).perform()

    def select(self, value: str) -> None:
        """Pick ``value`` in the viewer's drop-down (the culling mode)."""
        from selenium.webdriver.common.by import By
        from selenium.webdriver.support.ui import Select

        Select(self.driver.find_element(By.CSS_SELECTOR, ".widget-dropdown select")).select_by_visible_text(value)

    def slider_to_start(self) -> None:
        """Drag the slider's handle to the left end of its track."""
        from selenium.webdriver.common.action_chains import ActionChains
        from selenium.webdriver.common.by import By

        handle = self.driver.find_element(By.CSS_SELECTOR, ".widget-slider .noUi-handle")
        track = self.driver.find_element(By.CSS_SELECTOR, ".widget-slider .noUi-target")
        off = track.rect["x"] - (handle.rect["x"] + handle.rect["width"] / 2) - 3
        (ActionChains(self.driver, duration=20).click_and_hold(handle).move_by_offset(int(off), 0).release()
         .perform())

    def click_button(self, label: str) -> None:
        from selenium.webdriver.common.by import By

        for b in self.driver.find_elements(By.CSS_SELECTOR, ".jp-OutputArea-output button"):
            if b.text.strip() == label:
                b.click()
                return
        raise AssertionError(f"no button {label!r}")

    def run_in_kernel(self, code: str) -> str:
        """Execute ``code`` in the notebook's kernel (no cell); its status ('ok' or 'error')."""
        status: str = self.driver.execute_async_script("""
            const done = arguments[arguments.length - 1];
            const k = window.jupyterapp.shell.currentWidget.sessionContext.session.kernel;
            k.requestExecute({ code: arguments[0] }).done.then((m) => done(m.content.status), (e) => done(String(e)));
        """, code)
        return status
