"""Which library modules a workflow script or notebook runs, from its imports.

The workflow lists these modules among a rule's inputs, so editing a method reruns
exactly the results that depend on it. Deriving the list from the code (the import
statements, followed through ``src/thermaxis``) keeps it from drifting the way a
hand-kept list does.

The imports are found by a regular expression over each line that starts an import, at
any indent (a function's lazy import counts), with a parenthesised list over several
lines: the scan runs at every parse of the Snakefile, and ``ast.parse`` of the ~100
files took 0.25 s where this takes 0.02 s. An import-like line inside a docstring is
read too; at worst that adds an input, never drops one.
"""

from __future__ import annotations

import json
import re
from functools import cache
from pathlib import Path

__all__ = ["PACKAGE", "library_modules", "named_modules"]

# The thermaxis package folder (this module lives in its pipeline subpackage).
PACKAGE = Path(__file__).resolve().parents[1]


@cache
def _module_file(name: str) -> Path | None:
    """``thermaxis.a.b`` -> its file under the package (a module or a package's ``__init__``)."""
    parts = name.split(".")
    if parts[0] != PACKAGE.name:
        return None
    base = PACKAGE.joinpath(*parts[1:])
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _package_of(path: Path) -> str:
    relative = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(relative.parts)
    if parts[-1] == "__init__":
        parts.pop()
    else:
        parts.pop()  # a module's own package
    return ".".join(parts)


# ``from .x import (a, b as c)`` -> dots, module, list; ``import a.b as c, d`` -> list.
_IMPORT = re.compile(
    r"^[ \t]*(?:from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n;]*)"
    r"|import[ \t]+([^\n;]*))",
    re.MULTILINE,
)


def _listed(listing: str) -> list[str]:
    """The names of an import list, without comments, parentheses and ``as`` aliases."""
    listing = re.sub(r"#[^\n]*", "", listing).strip().strip("()")
    return [item.split(" as ")[0].strip() for item in listing.split(",") if item.strip()]


def _imported(source: str, package: str | None) -> set[str]:
    """Fully qualified names of everything ``source`` imports (a ``from x import y`` also
    names x.y); ``package``: the package relative imports start from."""
    names: set[str] = set()
    for match in _IMPORT.finditer(source):
        dots, module, listing, plain = match.groups()
        if plain is not None:
            names.update(_listed(plain))
            continue
        if dots and package is not None:
            parts = package.split(".")
            base = ".".join(parts[: len(parts) - (len(dots) - 1)] + ([module] if module else []))
        else:
            base = module
        names.add(base)
        names.update(f"{base}.{name}" for name in _listed(listing))
    return names


def _source(path: Path) -> str:
    if path.suffix == ".ipynb":
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    return path.read_text(encoding="utf-8")


@cache
def _direct(path: Path) -> tuple[Path, ...]:
    inside = PACKAGE in path.parents
    found = {
        _module_file(name)
        for name in _imported(_source(path), _package_of(path) if inside else None)
    }
    return tuple(sorted(f for f in found if f is not None))


def library_modules(*entries) -> list[str]:
    """Every package file that the scripts or notebooks ``entries`` import, directly or not, sorted."""
    seen: set[Path] = set()
    stack = [f for entry in entries for f in _direct(Path(entry).resolve())]
    while stack:
        path = stack.pop()
        if path in seen:
            continue
        seen.add(path)
        stack.extend(_direct(path))
    # A package's submodule runs its package's __init__ first.
    seen.update(
        p.parent / "__init__.py" for p in list(seen) if (p.parent / "__init__.py").is_file()
    )
    return sorted(str(p) for p in seen)


def named_modules(*names: str) -> list[str]:
    """The package files of the modules ``names`` (``thermaxis.figures.paper``) and every file they import.

    What a script runs that it imports by name at run time (the figure table's drawing
    functions), sorted.
    """
    files = []
    for name in names:
        found = _module_file(name)
        if found is None:
            raise ValueError(f"{name}: not a module of {PACKAGE}")
        files.append(found)
    return sorted({str(f) for f in files} | set(library_modules(*files)))
