"""The project-wide error: one line naming the file, the row or column, and what was expected;
and the warning of a selection that ran with less than it was asked for."""

from __future__ import annotations

__all__ = [
    "DataError",
    "SelectionWarning",
]


class DataError(ValueError):
    """A raw input that does not follow the documented layout."""


class SelectionWarning(UserWarning):
    """A sensitive-point selection made with less than it was asked for: a constant sensor
    left out, fewer classes than the lambda-cut was asked for, a smaller common set."""
