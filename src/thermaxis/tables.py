"""Reading back the CSV tables the workflow writes.

A run, fold or sensor is a label, not a number. Logger exports often name runs 1, 2, 10
or 01, and pandas would read such a column back as integers (01 as 1) that match no run
of the dataset. Every reader of a table the workflow wrote keeps these columns as text.
"""

from __future__ import annotations

import pandas as pd

__all__ = ["LABEL_COLUMNS", "read_table"]

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
