"""Text templates shipped as package data (``<subpackage>/templates/*.tmpl``).

Generated files whose text is mostly fixed (the controller's Structured Text block, the
twin's README) are kept as template files, filled with :class:`string.Template`
(``${name}`` placeholders, ``$$`` for a literal dollar), so the fixed text reads as it is
written out and the code computes only the values.
"""

from __future__ import annotations

import string
from functools import cache
from importlib import resources

__all__ = ["load_template", "fill"]


@cache
def load_template(package: str, name: str) -> string.Template:
    """Template ``name`` from ``package``'s ``templates`` folder (e.g. ``thermaxis.twin``, ``README.md.tmpl``)."""
    text = (resources.files(package) / "templates" / name).read_text(encoding="utf-8")
    return string.Template(text)


def fill(package: str, name: str, **values) -> str:
    """Template ``name`` of ``package`` with every placeholder replaced (a missing value is an error)."""
    return load_template(package, name).substitute(values)
