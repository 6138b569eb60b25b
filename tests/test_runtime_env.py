"""Opening a renderer prints no driver noise: without XDG_RUNTIME_DIR, libwayland-client (tried by
the Vulkan loader and Mesa while a device opens) wrote "error: XDG_RUNTIME_DIR is invalid or not set
in the environment." twice on stderr, e.g. under every notebook cell that made a renderer. geocull
sets a private one on import (geocull._runtime); a value already set is kept."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

SCRIPT = r"""
import json, os, stat, sys
import geocull as gc
from geocull.data import stacked_test_scene

scene = stacked_test_scene(n=16, n_horizons=2).build(tiles=(2, 2), coarse_factor=4)
res = gc.Renderer(24, 16, backend=sys.argv[1]).render(scene, gc.Camera.fit(scene), culling="none")
d = os.environ.get("XDG_RUNTIME_DIR")
st = os.stat(d) if d and os.path.isdir(d) else None
print(json.dumps({"dir": d, "mode": None if st is None else stat.S_IMODE(st.st_mode),
                  "owner": None if st is None else st.st_uid, "lit": int((res.image[..., 3] > 0).sum())}))
"""


def _run(backend: str, **env: str) -> tuple[subprocess.CompletedProcess[str], dict]:
    e = {k: v for k, v in os.environ.items() if k not in ("XDG_RUNTIME_DIR", "GEOCULL_BACKEND")}
    e.update(env)
    p = subprocess.run([sys.executable, "-c", SCRIPT, backend], capture_output=True, text=True, env=e, timeout=120)
    assert p.returncode == 0, p.stderr
    return p, json.loads(p.stdout.strip().splitlines()[-1])


# The default, Vulkan by name, and GL as `make test-gl` picks it (through the variable that "auto"
# honours). Without the private folder the first two printed the two lines here (lavapipe); GL did not.
@pytest.mark.parametrize(("backend", "env"), [("auto", {}), ("vulkan", {}), ("auto", {"GEOCULL_BACKEND": "gl"})],
                         ids=["auto", "vulkan", "GEOCULL_BACKEND=gl"])
def test_a_renderer_opens_without_xdg_runtime_dir_lines(backend, env):
    p, out = _run(backend, **env)
    assert "XDG_RUNTIME_DIR" not in p.stderr, p.stderr
    assert out["lit"] > 0  # it did render
    assert out["dir"].startswith("/") and out["mode"] == 0o700 and out["owner"] == os.getuid()
    assert not os.path.exists(out["dir"])  # removed when the process ended


def test_a_set_runtime_dir_is_kept(tmp_path):
    p, out = _run("vulkan", XDG_RUNTIME_DIR=str(tmp_path))
    assert out["dir"] == str(tmp_path) and "XDG_RUNTIME_DIR" not in p.stderr
