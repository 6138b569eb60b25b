"""Reproduces Figures 6 and 9 of Jia et al. (cell-merging LOD of truncated reservoir grids) as a
table, on geocull's synthetic faulted grid (``geocull.data.faulted_grid``: a normal fault, a
pinch-out, an erosional truncation, inactive cells, four regions): per cell-merging level, the
faces and vertices drawn as a percentage of level 0 (Figure 6) and the change of the enclosed
volume (Figure 9; the paper reports at most 3 % for up to 4 coarsenings), then the build time and
the frame time of each ``grid_lod`` mode against level 0 and against PyVista on the same grid
(``geocull.bench.grid``, one run, side by side).

Usage: python examples/grid_levels.py [--n 100] [--nk 100] [--blocks 16] [--out out/examples/grid]
       python examples/grid_levels.py --quick     (small, for CI)
"""

from __future__ import annotations

import argparse
import json
import os
from typing import Any

from geocull.bench import grid as bench_grid

PAPER = "paper (Jia et al.): faces fall with each coarsening; volume change at most 3 % for up to 4 coarsenings"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--n", type=int, default=100, help="cells along i and j (default 100)")
    p.add_argument("--nk", type=int, default=100, help="layers (default 100: 1M cells)")
    p.add_argument("--blocks", type=int, default=16, help="cells per block side (1..32)")
    p.add_argument("--size", type=int, default=1024, help="image width (height 4/5 of it)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--no-pyvista", action="store_true")
    p.add_argument("--quick", action="store_true", help="30 x 30 x 20 cells, 320 x 256, for CI")
    p.add_argument("--out", default="out/examples/grid")
    a = p.parse_args()
    if a.quick:
        a.n, a.nk, a.size, a.repeats, a.blocks = 30, 20, 320, 1, 8
    cfg: dict[str, Any] = dict(grid_n=a.n, grid_nk=a.nk, width=a.size, height=a.size * 4 // 5, repeats=a.repeats,
                               pyvista=not a.no_pyvista, blocks=(a.blocks, a.blocks))
    res = bench_grid.run(cfg)
    print(bench_grid.format_table(res))
    print(PAPER)
    worst = max(abs(lv["volume_change_pct"]) for lv in res["levels"][:5])
    print(f"here: volume change at most {worst:.4f} % over levels 0..{min(4, len(res['levels']) - 1)}")
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "grid_levels.json"), "w") as f:
        json.dump(res, f, indent=1, default=float)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
