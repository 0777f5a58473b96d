"""The tables the workflow writes: read back from CSV, and shown as text.

Apart from the reports so that every stage (the statistics, the paper's audit, the
recommendation's page) can show a table as Markdown without importing the reports.

A run, fold or sensor is a label, not a number. Logger exports often name runs 1, 2, 10
or 01, and pandas would read such a column back as integers (01 as 1) that match no run
of the dataset. Every reader of a table the workflow wrote keeps these columns as text.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["LABEL_COLUMNS", "read_table", "format_cell", "markdown_table"]

# The columns whose values name a run, fold, condition, sensor, input term, logger,
# dataset, candidate or configuration, in any table the workflow writes.
LABEL_COLUMNS = (
    "run",
    "fold",
    "held_out",
    "condition",
    "sensor",
    "sensors",
    "term",
    "signals",
    "source",
    "dataset",
    "candidate",
    "config_id",
)


def read_table(path_or_buffer, **kwargs) -> pd.DataFrame:
    """``pandas.read_csv`` with :data:`LABEL_COLUMNS` read as text; ``dtype`` adds to them."""
    dtype = {name: str for name in LABEL_COLUMNS}
    dtype.update(kwargs.pop("dtype", None) or {})
    return pd.read_csv(path_or_buffer, dtype=dtype, **kwargs)


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
