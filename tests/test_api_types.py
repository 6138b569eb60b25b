"""The typed surface matches what the core returns: the Literal of culling modes is the core's
registry, and every stats key a frame carries is declared in the TypedDicts (required keys always
present)."""

from __future__ import annotations

from typing import get_args

import numpy as np
import pytest

import geocull as gc


def test_culling_literal_is_the_registry():
    assert set(get_args(gc.CullingMode)) == set(gc.CULLING_MODES)
    assert gc.CULLING_MODES[0] == "none"


@pytest.mark.parametrize("mode", gc.CULLING_MODES)
def test_stats_keys_are_declared(mode):
    s = gc.Scene()
    s.add_heightfield(np.zeros((9, 9)), tiles=(2, 2))
    cam = gc.Camera.look_at((4.0, -6.0, 8.0), (4.0, 4.0, 0.0))
    res = gc.Renderer(32, 24).render(s, cam, culling=mode)
    declared = set(gc.RenderStats.__annotations__)
    assert set(res.stats) <= declared, set(res.stats) - declared
    assert gc.RenderStats.__required_keys__ <= set(res.stats)


def test_iso_stats_keys_are_declared():
    v = gc.Volume(np.linspace(-1, 1, 27).reshape(3, 3, 3))
    cam = gc.Camera.look_at((5.0, 4.0, 3.0), (1.0, 1.0, 1.0))
    res = gc.Renderer(16, 16).render_isosurface(v, 0.0, cam)
    assert set(res.stats) == set(gc.IsoStats.__annotations__)
