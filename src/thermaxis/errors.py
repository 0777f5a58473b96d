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
    "schema_message",
    "shown",
]

# A cell echoed in a message is cut to this many characters of its repr: a message stays
# one readable line whatever a file holds (a 5 MB line, a pasted document).
SHOWN_CHARS = 60


class DataError(ValueError):
    """A raw input that does not follow the documented layout."""


def shown(cell) -> str:
    """A data cell as a message quotes it: its repr, a numpy number as a plain one ('inf',
    not 'np.float64(inf)'), cut to :data:`SHOWN_CHARS` characters with its length said."""
    if hasattr(cell, "item") and type(cell).__module__ == "numpy":
        cell = cell.item()
    text = repr(cell)
    if len(text) <= SHOWN_CHARS:
        return text
    return f"{text[:SHOWN_CHARS]}... ({len(str(cell)):,} characters)"


def schema_message(error) -> str:
    """A JSON-schema error's message with the value it quotes :func:`shown`: jsonschema
    starts it with the value's whole repr (a 14-number list, a pasted document)."""
    whole = repr(error.instance)
    if error.message.startswith(whole):
        return shown(error.instance) + error.message[len(whole) :]
    return error.message


def first_schema_error(schema: dict, instance):
    """The error a one-line message names: the first by path of ``instance`` against the
    JSON ``schema`` (so the same bad document always names the same place), or None."""
    import jsonschema

    errors = jsonschema.Draft202012Validator(schema).iter_errors(instance)
    return min(errors, key=lambda e: list(e.absolute_path), default=None)


def schema_where(error) -> str:
    """Where an error lies, as a path of keys and indices; "top level" for the document."""
    return "/".join(map(str, error.absolute_path)) or "top level"


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
