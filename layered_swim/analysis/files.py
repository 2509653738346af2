"""Tables people open in a spreadsheet: one CSV row per dict, numbers to six significant digits."""
from __future__ import annotations

import csv
from pathlib import Path

from layered_swim.outputs import atomic_path


def write_csv(path: str | Path, rows: list[dict]) -> None:
    """Write ``rows`` (dicts with the same keys, in order) as CSV; None becomes an empty cell."""
    with atomic_path(path) as tmp, tmp.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows({k: (f"{v:.6g}" if isinstance(v, float) else "" if v is None else v) for k, v in row.items()}
                         for row in rows)
