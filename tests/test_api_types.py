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


def test_literals_match_the_core():
    assert set(get_args(gc.VolumeOrder)) == {"zyx", "xyz"} and set(get_args(gc.ZPositive)) == {"up", "down"}
    assert set(get_args(gc.Projection)) == {"perspective", "orthographic"}
    v = np.linspace(-1, 1, 27).reshape(3, 3, 3)
    for order in get_args(gc.VolumeOrder):
        for zp in get_args(gc.ZPositive):
            gc.Volume(v, order=order, z_positive=zp)
    for p in get_args(gc.Projection):
        gc.Camera.look_at((1.0, 0.0, 0.0), (0.0, 0.0, 0.0), projection=p)


def test_mypy_catches_misspelt_keywords_and_modes(tmp_path):
    """The public signatures are precise enough for a type checker: a misspelt keyword (colour=), an
    unknown culling mode, a wrong z_positive and an xtgeo-style int yflip are errors under mypy
    --strict, while the correct calls (numpy arrays where ArrayLike, trimesh-like objects) pass."""
    api = pytest.importorskip("mypy.api")
    snippet = tmp_path / "use.py"
    snippet.write_text(
        "import numpy as np\n"
        "import geocull as gc\n"
        "s = gc.Scene()\n"
        "s.add_heightfield(np.zeros((3, 3)), origin=np.array([0.0, 0.0]), rotation=30.0, yflip=True)\n"
        "s.add_mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), color=(1.0, 0.0, 0.0))\n"
        "cam = gc.Camera.look_at(np.zeros(3), (1.0, 1.0, 1.0), projection='orthographic')\n"
        "gc.Renderer(8, 8).render(s, cam, culling='horizon')\n"
        "gc.Volume(np.zeros((2, 2, 2)), order='xyz', z_positive='down')\n"
        "s.add_mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), colour=(1.0, 0.0, 0.0))  # line 9\n"
        "gc.Renderer(8, 8).render(s, cam, culling='horizn')  # line 10\n"
        "gc.Volume(np.zeros((2, 2, 2)), z_positive='downwards')  # line 11\n"
        "s.add_heightfield(np.zeros((3, 3)), yflip=-1)  # line 12\n"
    )
    out, err, status = api.run(["--strict", "--no-incremental", "--cache-dir", str(tmp_path / ".mypy"),
                                str(snippet)])
    lines = {int(x.split(":")[1]) for x in out.splitlines() if ": error:" in x}
    assert lines == {9, 10, 11, 12}, out + err
