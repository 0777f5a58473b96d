"""The project-wide error: one line naming the file, the row or column, and what was expected."""

from __future__ import annotations

__all__ = [
    "DataError",
]


class DataError(ValueError):
    """A raw input that does not follow the documented layout."""
