"""The natural order of labels (runs, sensors, measurements), shared by tables, reports and figures."""

from __future__ import annotations

import re
from collections.abc import Iterable

__all__ = ["natural_key", "natural_sorted", "sort_naturally"]


def natural_key(value) -> tuple:
    """Sort 'E2' before 'E10' and 'T2' before 'T10': embedded numbers compare numerically."""
    parts = re.split(r"(\d+)", str(value))
    return tuple((0, int(p), "") if p.isdigit() else (1, 0, p) for p in parts)


def natural_sorted(values: Iterable) -> list:
    """Distinct values in natural order."""
    return sorted(dict.fromkeys(values), key=natural_key)


def sort_naturally(frame, by):
    """``frame.sort_values(by)`` with text columns (runs, sensors) in natural order."""

    def key(column):
        if column.dtype == object or str(column.dtype) in ("string", "str"):
            return column.map(natural_key)
        return column

    return frame.sort_values(list(by), key=key, kind="stable", ignore_index=True)
