"""Shared pytest fixtures.

``renderer_small``: a session-wide factory of cached renderers, ``renderer_small(w, h)`` -> a
``geocull.Renderer`` of that size (opening a device costs ~0.1 s; renderers are reused across
tests, which is safe: a renderer re-uploads whenever it is handed another scene).
"""

from __future__ import annotations

import os

import pytest

# The tests check the core's own images, drawn over black: the renderers' default background (a
# light grey gradient, put in by Python where nothing was drawn) is black for the whole run, also in
# the processes tests start. tests/test_pictures.py tests the backgrounds themselves.
os.environ.setdefault("GEOCULL_BACKGROUND", "black")


@pytest.fixture(scope="session")
def renderer_small():
    import geocull as gc

    cache: dict[tuple[int, int], gc.Renderer] = {}

    def get(width: int = 32, height: int = 32) -> gc.Renderer:
        key = (width, height)
        if key not in cache:
            cache[key] = gc.Renderer(width, height)
        return cache[key]

    return get
