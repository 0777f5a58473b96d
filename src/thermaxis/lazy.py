"""A package's names imported on first use (PEP 562 module ``__getattr__`` and ``__dir__``).

``import thermaxis`` stays instant, and a workflow job that imports one submodule of a
subpackage does not import its siblings (and their scipy.stats, scikit-learn) with it.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from importlib import import_module


def lazy_names(package: str, public: Mapping[str, str]):
    """``(__getattr__, __dir__)`` for ``package``: its name ``n`` is ``n`` of module ``public[n]``,
    imported when ``n`` is first asked for."""

    def __getattr__(name):
        if name in public:
            return getattr(import_module(public[name]), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted([*vars(sys.modules[package]), *public])

    return __getattr__, __dir__
