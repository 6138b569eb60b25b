"""A renderer inherited by a forked process (issue 39 item 2): ``os.fork()`` or multiprocessing's
"fork" start method (Linux's default) with a module-level renderer. Its device's driver threads
do not survive fork(): every use used to wait forever (and ignore Ctrl-C), and so did freeing
it, e.g. when the child exited. Now every use raises DeviceError at once, naming spawn and
forkserver, and freeing it in the child returns at once.

Each case runs in a fresh interpreter (``subprocess``) under a timeout, so that a hang fails the
test instead of the test run; the forked child is watched by its parent with a deadline too."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

import geocull as gc

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork() on this platform")

PRELUDE = textwrap.dedent("""
    import gc as pygc, json, multiprocessing as mp, os, sys, time
    import numpy as np
    import geocull as gc

    R = gc.Renderer(24, 20)  # module level, as in a script with a multiprocessing.Pool
    S = gc.Scene()
    S.add_heightfield(np.random.default_rng(0).random((9, 9)), tiles=(2, 2))
    CAM = gc.Camera.look_at((15.0, -6.0, 12.0), (4.0, 4.0, 0.0))
    c = np.linspace(-1, 1, 10)
    VOL = gc.Volume(np.sqrt(c[:, None, None] ** 2 + c[None, :, None] ** 2 + c[None, None, :] ** 2))
    REF = R.render(S, CAM).image  # the parent has used its device

    def wait(pid, seconds):
        # (exit code or -signal, None) of child pid, or (None, "hung") after `seconds` (then killed)
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            p, st = os.waitpid(pid, os.WNOHANG)
            if p:
                return (os.WEXITSTATUS(st) if os.WIFEXITED(st) else -os.WTERMSIG(st)), None
            time.sleep(0.02)
        os.kill(pid, 9)
        os.waitpid(pid, 0)
        return None, "hung"
""")

CHILD_CALLS = PRELUDE + textwrap.dedent("""
    def calls():
        yield "render", lambda: R.render(S, CAM)
        yield "render_isosurface", lambda: R.render_isosurface(VOL, 0.5, CAM)
        yield "iso.clear_cache", lambda: gc.iso.clear_cache(R)
        yield "gpu_bytes", lambda: R.gpu_bytes
        yield "cache_budget", lambda: setattr(R, "cache_budget", 1)
        yield "new renderer", lambda: gc.Renderer(8, 8)

    def render_in_pool_worker():
        return R.render(S, CAM).image

    rd, wr = os.pipe()
    pid = os.fork()
    if pid == 0:
        out = {}
        for name, f in calls():
            t = time.monotonic()
            try:
                f()
                out[name] = "no error"
            except gc.DeviceError as e:
                out[name] = "DeviceError: " + str(e)
            except BaseException as e:
                out[name] = repr(e)
            out[name + " seconds"] = time.monotonic() - t
        out["repr"] = repr(R)
        out["scene built"] = gc.Scene().add_heightfield(np.zeros((3, 3)))  # CPU work still runs
        t = time.monotonic()
        del R
        pygc.collect()  # the inherited renderer freed: used to wait forever
        out["free seconds"] = time.monotonic() - t
        os.write(wr, json.dumps(out).encode())
        os._exit(0)
    os.close(wr)
    code, hung = wait(pid, 60)
    data = os.read(rd, 1 << 20)
    res = {"child": json.loads(data) if data else None, "code": code, "hung": hung}
    # multiprocessing's "fork" pool: the worker's error reaches the parent at once
    t = time.monotonic()
    with mp.get_context("fork").Pool(1) as pool:
        try:
            pool.apply_async(render_in_pool_worker).get(timeout=60)
            res["pool"] = "no error"
        except gc.DeviceError as e:
            res["pool"] = "DeviceError: " + str(e)
        except BaseException as e:
            res["pool"] = repr(e)
    res["pool seconds"] = time.monotonic() - t
    res["parent still renders"] = bool((R.render(S, CAM).image == REF).all())
    print(json.dumps(res))
""")


def run_script(script: str, timeout: float = 240) -> str:
    try:
        p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"the script hung (over {timeout} s)")
    assert p.returncode == 0, p.stderr[-3000:]
    return p.stdout


def test_an_inherited_renderer_raises_device_error_at_once_in_a_forked_child():
    res = json.loads(run_script(CHILD_CALLS).strip().splitlines()[-1])
    assert res["hung"] is None and res["code"] == 0, res
    child = res["child"]
    for name in ("render", "render_isosurface", "iso.clear_cache", "gpu_bytes", "cache_budget"):
        msg = child[name]
        assert msg.startswith("DeviceError: this renderer was opened by process "), (name, msg)
        assert "forked" in msg and '"spawn"' in msg and '"forkserver"' in msg, (name, msg)
        assert child[name + " seconds"] < 1.0, (name, child)
    assert child["new renderer"].startswith("DeviceError: ") and "spawn" in child["new renderer"]
    assert "unusable in this forked process" in child["repr"]
    assert child["scene built"] == 0
    assert child["free seconds"] < 1.0
    assert res["pool"].startswith("DeviceError: this renderer was opened by process "), res["pool"]
    assert res["pool seconds"] < 30
    assert res["parent still renders"]


EXIT_NORMALLY = PRELUDE + textwrap.dedent("""
    pid = os.fork()
    if pid == 0:
        try:
            R.render(S, CAM)
        except gc.DeviceError:
            pass
        sys.exit(0)  # interpreter exit: Python's and the C libraries' exit handlers run
    code, hung = wait(pid, 60)
    print(json.dumps({"code": code, "hung": hung}))
""")


def _lavapipe() -> bool:
    info = gc.Renderer(8, 8).adapter_info
    return "Vulkan" in info and "llvmpipe" in info


@pytest.mark.xfail(condition=_lavapipe(), strict=True,
                   reason="Mesa's lavapipe (swrast_dri.so) joins its queue threads in a C atexit handler; in a "
                          "child forked from a process with an open device those threads do not exist and "
                          "exit() crashes there (SIGSEGV), after Python has finished. Not Python's to fix "
                          "(multiprocessing's children leave by os._exit and are not affected; GL exits cleanly)")
def test_a_forked_child_with_an_inherited_renderer_exits_cleanly():
    res = json.loads(run_script(EXIT_NORMALLY).strip().splitlines()[-1])
    assert res["hung"] is None, res  # it used to wait forever freeing the renderer
    assert res["code"] == 0, res
