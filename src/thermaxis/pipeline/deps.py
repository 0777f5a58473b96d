"""Which library modules a workflow script or notebook runs, from its imports.

The workflow lists these modules among a rule's inputs, so editing a method reruns
exactly the results that depend on it. Deriving the list from the code (``ast`` over
the imports, followed through ``src/thermaxis``) keeps it from drifting the way a
hand-kept list does.
"""

from __future__ import annotations

import ast
import json
from functools import cache
from pathlib import Path

__all__ = ["PACKAGE", "library_modules", "named_modules"]

# The thermaxis package folder (this module lives in its pipeline subpackage).
PACKAGE = Path(__file__).resolve().parents[1]


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


def _statements(body):
    """Every statement of ``body`` and of the blocks inside it (imports are statements, so
    expressions need not be visited: a tenth of the time of ``ast.walk``)."""
    for node in body:
        yield node
        for block in ("body", "orelse", "finalbody", "handlers", "cases"):
            inner = getattr(node, block, None)
            if isinstance(inner, list):
                yield from _statements(inner)


def _imported(tree: ast.Module, package: str | None) -> set[str]:
    """Fully qualified names of everything ``tree`` imports (a ``from x import y`` also names x.y)."""
    names: set[str] = set()
    for node in _statements(tree.body):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level and package is not None:
                base_parts = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(base_parts + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
    return names


def _source(path: Path) -> str:
    if path.suffix == ".ipynb":
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    return path.read_text(encoding="utf-8")


@cache
def _direct(path: Path) -> tuple[Path, ...]:
    inside = PACKAGE in path.parents
    tree = ast.parse(_source(path), filename=str(path))
    found = {_module_file(name) for name in _imported(tree, _package_of(path) if inside else None)}
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
