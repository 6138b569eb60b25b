"""``python -m geocull bench``: geocull's culling methods against each other and against PyVista.

For every view of a Gullfaks-like scene (default: 11 horizons of 418×418 samples + 16 faults,
≈ 3.9 M triangles, 1280×1024, all :func:`geocull.data.standard_views`) it renders, side by side in
one process and one run (a warm-up round, then ``--repeats`` rounds in rotated order):

- geocull ``none`` (every fine tile: the reference image), ``three_pass`` in the paper's
  approximate mode (``conservative=False``; pixel threshold 10, coarse factor 25, prepass scale 1.0
  and 0.5; coarse factor 100 at 0.5) and in the conservative mode (``cons``: threshold 0, coarse
  factor 25 at scale 1, coarse factor 100 at 0.5), ``oracle`` (exactly the tiles visible in the
  unculled image: the lower bound), ``horizon`` (CPU horizon culling);
- PyVista/VTK off-screen with MSAA off and with MSAA on (PyVista's default), same camera and clip
  range.

Frame time = minimum over the rounds of geocull's ``stats["total_ms"]`` (call → GPU done, no
read-back) or VTK's ``Render()`` + ``WaitForCompletion()`` wall time. Errors against geocull
``none``: differing pixel fraction and missing tiles (tiles visible in the unculled image but not
drawn) for geocull methods; for PyVista (shading differs) coverage agreement and relative depth
error. Also printed: scene build time, triangles, host + GPU bytes per fine triangle, peak RSS,
adapter. ``--pass-triangles N`` bounds the triangles of each render pass of the scenes' renderers
(:attr:`geocull.Renderer.pass_triangles`: driver memory against frame time on CPU drivers).
``--json PATH`` writes ``{"summary": {...}, "rows": [...]}``.

``--scene iso``: isosurfaces instead (:mod:`geocull.bench.iso`): geocull none / implicit, cold and
warm, against PyVista flying edges + render, on the Pesco field and real volumes from PyVista's wheel.

``--scene grid``: a faulted reservoir grid (:mod:`geocull.bench.grid`): build time and memory, the
cell-merging levels, and each ``grid_lod`` mode against level 0 and PyVista. ``--scene seismic``: the
scene with three slices and a lens (:mod:`geocull.bench.seismic`).

``--scene field``: a real field from files (:mod:`geocull.bench.field`; ``--data DIR``, default
``../shared/data/reek``): horizons, a grid and wells, every culling mode, LOD, the oracle and PyVista.

``--scene scale``: the default scene at the same extent ever finer (:mod:`geocull.bench.scale`; 3.9 M, 15 M and
61 M triangles, each in its own process): build, first image, ``none`` / ``temporal`` / ``temporal`` + lod frame
times, peak RSS and the lod frame's error, beside issue 41's targets.

``--scene lod``: the LOD build of mesh tiles (:mod:`geocull.bench.lod`): geocull's meshoptimizer levels
against fast-simplification (the ``bench`` extra) on the same tiles at the same triangle counts, build
time and geometric error (symmetric Hausdorff estimate and mean distance to the fine surface).

``--quick``: a small scene (120×120 samples, 6 faults), 320×256, 3 views, 2 repeats (CI).
``--tiny`` (or env ``GEOCULL_BENCH_TINY=1``; for tests): 48×48 samples, 64×48, 1 view, 1 repeat.

The package: :mod:`~geocull.bench.cli` (the command line: options and the dispatch to one module
per ``--scene``), :mod:`~geocull.bench.gullfaks` (the default scene; :func:`run` and
:func:`format_table` are re-exported here), :mod:`~geocull.bench.iso`, :mod:`~geocull.bench.grid`,
:mod:`~geocull.bench.seismic`, :mod:`~geocull.bench.field`, :mod:`~geocull.bench.scale`, :mod:`~geocull.bench.lod`, and
:mod:`~geocull.bench.report` (parameter sweeps, tables and plots of speed against error; the timing loop every
benchmark uses). The submodules are imported on first use (``geocull.bench.report``) or by ``from geocull.bench
import report``.
"""

from __future__ import annotations

import importlib as _importlib
from pathlib import Path as _Path
from typing import Any as _Any

from .cli import main
from .gullfaks import format_table, run

__all__ = ["main", "run", "format_table"]


def __getattr__(name: str) -> _Any:
    """``geocull.bench.report``, ``geocull.bench.field``, ...: a submodule imported on first use."""
    if not name.startswith("_") and (_Path(__file__).parent / f"{name}.py").is_file():
        return _importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'geocull.bench' has no attribute {name!r}")
