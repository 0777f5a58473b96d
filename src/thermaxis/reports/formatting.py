"""Table cells and tables as text: one formatting for Markdown and HTML outputs."""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["format_cell", "markdown_table"]


def format_cell(value, float_format: str) -> str:
    """One table cell as text: floats in ``float_format``, missing values blank."""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    # Free-form properties of dataset.yaml (``tags: [a, b]``) are lists or mappings.
    if isinstance(value, (list, tuple)):
        return ", ".join(format_cell(v, float_format) for v in value)
    if isinstance(value, dict):
        return ", ".join(f"{k}: {format_cell(v, float_format)}" for k, v in value.items())
    if pd.isna(value):
        return ""
    if isinstance(value, (float, np.floating)):
        return float_format % value
    return str(value)


def markdown_table(frame: pd.DataFrame, float_format: str = "%.2f") -> str:
    header = "| " + " | ".join(map(str, frame.columns)) + " |"
    rule = "|" + "|".join("---" for _ in frame.columns) + "|"
    body = [
        "| " + " | ".join(format_cell(v, float_format) for v in row) + " |"
        for row in frame.itertuples(index=False)
    ]
    return "\n".join([header, rule, *body]) + "\n"
