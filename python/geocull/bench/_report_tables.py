"""The sweep table's columns and the table written out: :func:`to_markdown`, :func:`to_frame`
(pandas), :func:`write_json` (strict JSON through :func:`jsonable`). Re-exported by
:mod:`geocull.bench.report`, where they are documented for users."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["COLUMNS", "INT_COLUMNS", "PARAM_COLUMNS", "fmt", "to_markdown", "to_frame", "jsonable", "write_json"]

# Columns of a sweep row, in display order.
COLUMNS = (
    "tiles", "coarse_factor", "view", "method", "mode", "pixel_threshold", "prepass_scale",
    "total_ms", "median_ms", "ratio_to_none", "ratio_to_oracle",
    "differing_pixel_fraction", "psnr", "missing_tiles",
    "triangles_drawn", "triangles_prepass", "triangles_fine_total", "tiles_drawn", "tiles_total",
    "triangle_diff_vs_oracle", "prepass_ms", "count_ms", "draw_ms", "build_s",
)

#: Columns holding whole numbers (counts): printed as integers (summaries hold their rounded means).
INT_COLUMNS = frozenset({
    "triangles_drawn", "triangles_prepass", "triangles_fine_total", "tiles_drawn", "tiles_total", "missing_tiles",
    "views", "tiles_at_risk", "predicted_max_missing_pixels", "missed_not_at_risk",
})
#: Parameter columns: printed as given (10, 0.5, 25), not as measured values.
PARAM_COLUMNS = frozenset({"pixel_threshold", "prepass_scale", "coarse_factor"})


def fmt(v: Any, column: str | None = None) -> str:
    """A table cell: "–" for None, counts (:data:`INT_COLUMNS`) as whole numbers with thousands
    separators, parameters (:data:`PARAM_COLUMNS`) as given, other floats short (scientific
    outside 1e-3..1e6)."""
    if v is None:
        return "–"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, (int, np.integer)):
        return f"{int(v):,}"
    if column in INT_COLUMNS and isinstance(v, (float, np.floating)) and math.isfinite(v):
        return f"{int(round(float(v))):,}"
    if column in PARAM_COLUMNS and isinstance(v, (float, np.floating)):
        return f"{float(v):g}"
    if isinstance(v, float):
        if math.isinf(v):
            return "inf"
        if math.isnan(v):
            return "nan"
        if v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e6):
            return f"{v:.2e}"
        return f"{v:.4g}" if abs(v) < 1 else f"{v:.3f}" if abs(v) < 100 else f"{v:.1f}"
    return str(v)


def to_markdown(table: Sequence[dict[str, Any]], columns: Sequence[str] | None = None) -> str:
    """The table as GitHub markdown; ``columns`` default to those of :data:`COLUMNS` present. Counts
    (:data:`INT_COLUMNS`) print as whole numbers, parameters as given (``10``, ``0.5``), and the
    ``mode`` column says which three_pass a row is."""
    if not table:
        return "(empty table)\n"
    if columns is None:
        present = set().union(*(r.keys() for r in table))
        columns = [c for c in COLUMNS if c in present] + sorted(
            c for c in present if c not in COLUMNS and c != "times_ms"
        )
    lines = ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    for r in table:
        lines.append("| " + " | ".join(fmt(r.get(c), c) for c in columns) + " |")
    return "\n".join(lines) + "\n"


def to_frame(table: Sequence[dict[str, Any]]) -> Any:
    """The table as a pandas DataFrame (ImportError with a hint if pandas is missing); counts
    (:data:`INT_COLUMNS`) as integer columns (pandas' ``Int64``, missing values ``<NA>``)."""
    try:
        import pandas as pd
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("to_frame/as_frame need pandas (pip install pandas); the list of dicts works without") from e
    df = pd.DataFrame(list(table))
    for c in df.columns:
        if c in INT_COLUMNS:
            df[c] = df[c].round().astype("Int64")
    return df


def jsonable(x: Any) -> Any:
    """``x`` with numpy scalars/arrays made plain and non-finite floats made None (strict JSON)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, np.generic):
        return jsonable(x.item())
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def write_json(obj: Any, path: str) -> None:
    """Write ``obj`` to ``path`` as indented JSON (numpy values converted, non-finite floats as null)."""
    with open(path, "w") as f:
        json.dump(jsonable(obj), f, indent=1, allow_nan=False)
        f.write("\n")
