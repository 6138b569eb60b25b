"""The process environment the graphics drivers read, set up before the extension opens a device.

Opening a device lets the Vulkan loader's and Mesa's window-system code try a Wayland display;
libwayland-client then prints ``error: XDG_RUNTIME_DIR is invalid or not set in the environment.``
on stderr, once per try, whenever that variable is unset or not an absolute path (containers, CI,
Jupyter kernels started by a service: two red lines under every notebook cell that opens a
renderer). geocull never shows a window, so :func:`private_runtime_dir` gives such a process a
private runtime folder of its own (a new 0700 temporary folder, removed at exit): the connection
attempt then fails quietly, as on a desktop without Wayland. A value that is already an absolute
path is left alone, and child processes inherit whichever is set. geocull's ``__init__`` calls it on
import (before any device can open).
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile

__all__ = ["private_runtime_dir"]


def private_runtime_dir() -> str | None:
    """Set ``XDG_RUNTIME_DIR`` to a new private folder when it is unset, empty or relative; returns
    the folder made, or None when the variable was kept."""
    if os.environ.get("XDG_RUNTIME_DIR", "").startswith("/"):
        return None
    path = tempfile.mkdtemp(prefix="geocull-runtime-")  # mode 0700, owned by this user
    os.environ["XDG_RUNTIME_DIR"] = path
    atexit.register(shutil.rmtree, path, True)
    return path
