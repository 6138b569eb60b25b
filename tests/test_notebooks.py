"""The example notebooks are committed without outputs (CI executes them: `make notebooks`), are
valid nbformat 4, and the runner finds every one."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.ipynb"))


def test_there_are_notebooks():
    names = {p.name for p in NOTEBOOKS}
    assert {"xtgeo_three_pass_vs_pyvista.ipynb", "speed_vs_error_report.ipynb", "seismic_isosurface.ipynb",
            "reek_field.ipynb"} <= names


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_has_no_outputs(path):
    nb = json.loads(path.read_text())
    assert nb["nbformat"] == 4
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert code, "a notebook without code"
    for c in code:
        assert c.get("outputs") == [] and c.get("execution_count") is None, f"{path.name}: outputs committed"
    nbformat = pytest.importorskip("nbformat")
    nbformat.validate(nbformat.reads(path.read_text(), as_version=4))
