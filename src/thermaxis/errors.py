"""The project-wide error: one line naming the file, the row or column, and what was expected;
the warning of a selection that ran with less than it was asked for; and warnings recorded
where they are raised, to be raised again elsewhere (a worker's in the job's process, a
reused fit's at its reuse)."""

from __future__ import annotations

import warnings
from collections.abc import Callable

__all__ = [
    "DataError",
    "SelectionWarning",
    "raise_again",
    "recorded",
]


class DataError(ValueError):
    """A raw input that does not follow the documented layout."""


class SelectionWarning(UserWarning):
    """A sensitive-point selection made with less than it was asked for: a constant sensor
    left out, fewer classes than the lambda-cut was asked for, a smaller common set."""


def recorded(function: Callable, *args):
    """``function(*args)`` and every warning it raised (none filtered out), as
    ``(message, category, filename, lineno)`` tuples that pickle."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        value = function(*args)
    return value, [(str(w.message), w.category, w.filename, w.lineno) for w in caught]


def raise_again(raised) -> None:
    """Raise warnings :func:`recorded` recorded, in order, under the caller's filters."""
    for message, category, filename, lineno in raised:
        warnings.warn_explicit(message, category, filename, lineno)
