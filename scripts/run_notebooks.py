"""Execute every example notebook (examples/*.ipynb) with nbclient, as CI does (`make notebooks`).

Each runs in a fresh kernel of this interpreter with examples/ as its working directory; the
executed copies (with outputs) go to out/notebooks/, the committed notebooks stay without outputs.
A notebook that raises, or runs past --timeout seconds in one cell, fails the run. Prints each
notebook's wall time.

    python scripts/run_notebooks.py [--timeout 300] [--out out/notebooks] [NOTEBOOK ...]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("notebooks", nargs="*", type=Path, help="default: examples/*.ipynb")
    ap.add_argument("--timeout", type=int, default=300, help="seconds per cell")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "notebooks")
    a = ap.parse_args(argv)

    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError

    paths = a.notebooks or sorted((ROOT / "examples").glob("*.ipynb"))
    if not paths:
        print("run_notebooks: no notebooks found", file=sys.stderr)
        return 1
    a.out.mkdir(parents=True, exist_ok=True)
    failed = 0
    for p in paths:
        nb = nbformat.read(p, as_version=4)
        client = NotebookClient(nb, timeout=a.timeout, kernel_name="python3",
                                resources={"metadata": {"path": str(p.parent.resolve())}})
        t0 = time.perf_counter()
        try:
            client.execute()
            status = "ok"
        except CellExecutionError as e:
            status, failed = f"FAILED\n{e}", failed + 1
        dt = time.perf_counter() - t0
        nbformat.write(nb, a.out / p.name)
        print(f"notebook {p.name}: {status} in {dt:.1f} s (executed copy: {a.out / p.name})", flush=True)
    print(f"notebooks: {len(paths) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
