"""Plain-text tables and numbers for the commands' output."""
from __future__ import annotations


def table(rows: list[list[str]], header: list[str] | None = None) -> str:
    rows = ([header] if header else []) + rows
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


def fmt(value) -> str:
    return f"{value:.3f}" if isinstance(value, float) else str(value)


def flat(result: dict) -> dict:
    """Nested summaries (the fluid's report) as ``fluid.key`` rows."""
    flat = {}
    for key, value in result.items():
        if isinstance(value, dict):
            flat.update({f"{key}.{k}": v for k, v in value.items() if not isinstance(v, (dict, list))})
        elif not isinstance(value, list):
            flat[key] = value
    return flat


def summary_rows(result: dict) -> list[list[str]]:
    """A stroke analysis's summary as [quantity, mean, unit] rows (``analyze``, ``compare``)."""
    from layered_swim.analysis.report import QUANTITIES, fmt

    rows = []
    for name, (text, unit, _) in QUANTITIES.items():
        value = result["summary"].get(name)
        if value is not None:
            rows.append([text, fmt(name, value["mean"] if isinstance(value, dict) else value), unit])
    return rows
