"""Progress reports (geocull._progress): fractions that never decrease and end at exactly 1.0, for
scene builds (tile counts from the Rust core), sweeps and the benchmark; silent by default in scripts,
on in notebooks; a callback's exception stops a build and leaves the scene as it was."""

from __future__ import annotations

import io
import sys
import types

import numpy as np
import pytest

import geocull as gc
from geocull import _progress


def recorder():
    seen: list[tuple[float, str]] = []
    return seen, lambda f, m: seen.append((f, m))


def check_fractions(seen):
    fr = [f for f, _ in seen]
    assert fr and fr[0] == 0.0 and fr[-1] == 1.0, fr
    assert all(b >= a for a, b in zip(fr[:-1], fr[1:], strict=True)), fr
    assert fr.count(1.0) == 1 and all(0.0 <= f <= 1.0 for f in fr)
    return fr


def big_z(n=600):
    return np.random.default_rng(0).normal(size=(n, n)).cumsum(axis=0)


def test_heightfield_build_reports_tile_fractions():
    seen, cb = recorder()
    s = gc.Scene()
    s.add_heightfield(big_z(), tiles=(20, 20), coarse_factor=25, progress=cb)
    fr = check_fractions(seen)
    # The core reports tiles finished out of 400 while it builds (every 25 ms; the build takes
    # several times that), so some fraction lies strictly between 0 and 1, on a multiple of 1/400.
    # (All 400 done before the call returns shows as 0.999999: 1.0 is kept for the end.)
    mid = [f for f in fr if 0.0 < f < 0.999999]
    assert mid and all(abs(f * 400 - round(f * 400)) < 1e-6 for f in mid), fr
    seen2, cb2 = recorder()
    s.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], progress=cb2)
    check_fractions(seen2)


def test_a_raising_callback_stops_the_build_and_leaves_the_scene_unchanged():
    s = gc.Scene()

    def cb(f, m):
        if 0.0 < f < 1.0:
            raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        s.add_heightfield(big_z(), tiles=(20, 20), progress=cb)
    assert s.object_ids() == [] and s.n_triangles == 0


def test_silent_in_scripts_and_on_in_notebooks(monkeypatch, capsys):
    assert _progress.resolve(None) is None and _progress.resolve(False) is None
    gc.Scene().add_heightfield(np.zeros((4, 4)))
    assert capsys.readouterr().err == ""
    fake = types.ModuleType("IPython")
    fake.get_ipython = lambda: types.SimpleNamespace(kernel=object())  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "IPython", fake)
    assert _progress.in_notebook() and _progress.resolve(None) is not None
    with pytest.raises(gc.InputError, match="progress"):
        _progress.resolve("yes")  # type: ignore[arg-type]


def test_text_bar_without_tqdm(monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)  # import fails: the plain bar
    bar = _progress.resolve(True)
    assert isinstance(bar, _progress._TextBar)
    out = io.StringIO()
    bar.stream = out
    with _progress.task(bar, 4, "work") as t:
        for _ in range(4):
            t.advance(1)
    text = out.getvalue()
    assert text.endswith("\n") and "100.0%" in text and "work" in text


def test_task_clamps_and_is_monotone():
    seen, cb = recorder()
    with _progress.task(cb, 3, "a") as t:
        t.advance(2)
        t.update(1)  # lower: ignored
        t.advance(5)  # past the total: held below 1 until the end
        t.update(t.done, "b")
    fr = check_fractions(seen)
    assert fr[1] == pytest.approx(2 / 3) and max(fr[:-1]) < 1.0 and seen[-1][1] == "b"
    seen, cb = recorder()
    with pytest.raises(KeyError), _progress.task(cb, 2):
        raise KeyError
    assert [f for f, _ in seen] == [0.0]  # no 1.0 when the work failed


def test_sweep_and_bench_progress():
    from geocull import bench
    from geocull.bench import cli, report
    from geocull.data import stacked_test_scene, standard_views

    spec = stacked_test_scene(n=16, n_horizons=1, with_faults=False)
    seen, cb = recorder()
    report.sweep(spec, standard_views(spec)[:2], thresholds=[10], coarse_factors=[4, 16], tiles=[2],
                 prepass_scales=[1.0], width=32, height=32, repeats=1, progress=cb)
    fr = check_fractions(seen)
    assert {0.25, 0.5, 0.75} <= set(fr)  # 2 builds x 2 views
    assert any("building scene" in m for _, m in seen)

    a = cli.parser().parse_args(["--tiny", "--no-pyvista", "--no-horizon"])
    seen, cb = recorder()
    bench.run(cli.config(a), progress=cb)
    fr = check_fractions(seen)
    assert pytest.approx(1 / 3) in fr and pytest.approx(2 / 3) in fr  # two builds, one view


def test_scene_spec_build_reports_every_object():
    from geocull.data import stacked_test_scene

    spec = stacked_test_scene(n=64, n_horizons=3)
    seen, cb = recorder()
    scene = spec.build(tiles=(4, 4), coarse_factor=4, progress=cb)
    fr = check_fractions(seen)
    assert len(scene.object_ids()) == len(spec.horizons) + len(spec.faults)
    # every object ends its share: the fractions after each object's last report are its cumulative weight
    w = [2.0 * h["z"].size for h in spec.horizons] + [float(len(f["faces"])) for f in spec.faults]
    marks = np.cumsum(w)[:-1] / sum(w)
    assert all(any(abs(f - m) < 1e-9 for f in fr) for m in marks), (fr, marks)
    assert any("object 2/" in m for _, m in seen)


def test_isosurface_build_reports_fractions_of_the_tiles_it_extracted():
    # Its tiles exist only once the surface is extracted: the core gives the total then, and
    # the fractions reported are multiples of 1 / (the object's tiles), not of the estimate.
    from geocull.data import pesco_synthetic

    vals, origin, spacing = pesco_synthetic(64)
    vol = gc.Volume(vals, origin=origin, spacing=spacing)
    seen, cb = recorder()
    s = gc.Scene()
    oid = s.add_isosurface(vol, 0.0, progress=cb)
    fr = check_fractions(seen)
    n = int(np.sum(s.tile_table()["object"] == oid))
    mid = [f for f in fr if 0.0 < f < 0.999999]
    assert n > 20 and mid and all(abs(f * n - round(f * n)) < 1e-6 for f in mid), (n, fr)


def test_the_cores_total_replaces_the_estimate():
    seen, cb = recorder()
    with _progress.task(cb, 1, "x") as t:
        t(0, 0)  # total not known yet: the estimate stands
        t(3, 10)
        t(4)
    fr = check_fractions(seen)
    assert fr[1:-1] == [pytest.approx(0.3), pytest.approx(0.4)], fr  # (a repeated 0.0 is not reported)
