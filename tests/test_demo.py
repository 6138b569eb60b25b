"""``python -m geocull demo`` on a tiny scene: the side-by-side table (none, three_pass, PyVista) with
each row's image error against the unculled image, and the PNG."""

from __future__ import annotations

import os

import pytest

from geocull.__main__ import main
from geocull.testing import read_png


@pytest.mark.parametrize("pyvista", [False, True])
def test_demo_prints_the_comparison(tmp_path, capsys, pyvista):
    if pyvista:
        pytest.importorskip("pyvista")
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    out = tmp_path / "d.png"
    args = ["demo", "--size", "24", "--width", "64", "--height", "48", "--repeats", "2", "--out", str(out)]
    assert main(args + ([] if pyvista else ["--no-pyvista"])) == 0
    text = capsys.readouterr().out
    lines = {ln.split()[0]: ln for ln in text.splitlines() if ln.split()}
    assert "best ms" in text and "x none" in text
    assert lines["none"].split()[2] == "1.00"  # none against itself
    assert "0 (0.000 %)" in lines["none"]
    assert "three_pass" in lines and (("pyvista" in lines) == pyvista)
    pytest.importorskip("PIL")  # read_png reads with Pillow (the test extra)
    assert read_png(out).shape == (48, 64, 4)
