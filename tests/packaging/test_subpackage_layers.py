"""The subpackages of src/thermaxis in one direction, and their private names kept inside.

A *subpackage* is the first name under ``thermaxis`` (``method``, ``statistics``,
``config`` for the top-level ``config.py``). Imports are read with ``ast`` wherever they
stand, inside functions too: a deferred import still ties two subpackages together.

- An underscored name belongs to its subpackage: another that imports it (or a tool or a
  workflow script) depends on what the owner may change without notice.
- Two subpackages that import each other are one knot: neither can be read, tested or moved
  without the other (issue 63 asks that none do).
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

from helpers import REPO

SRC = REPO / "src"


def _subpackage(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "thermaxis" and len(parts) > 1 else None


def _module_of(path: Path, root: Path) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def thermaxis_imports(path: Path, module: str | None):
    """(imported module, imported names, line) of every absolute or relative import of
    thermaxis in ``path``; ``module`` (its dotted name, None outside the package) resolves
    relative imports."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("thermaxis."):
                    yield alias.name, (), node.lineno
        elif isinstance(node, ast.ImportFrom):
            target = node.module or ""
            if node.level:
                package = module.split(".")
                if path.name != "__init__.py":
                    package = package[:-1]
                base = package[: len(package) - node.level + 1]
                target = ".".join([*base, *([node.module] if node.module else [])])
            if target == "thermaxis":
                for alias in node.names:
                    yield f"thermaxis.{alias.name}", (), node.lineno
            elif target.startswith("thermaxis."):
                yield target, tuple(alias.name for alias in node.names), node.lineno


def underscored_crossings(src: Path, outside: list[Path]) -> list[str]:
    """``file:line module.name`` for each underscored name imported from another subpackage."""
    found = []
    files = [(p, _module_of(p, src)) for p in sorted((src / "thermaxis").rglob("*.py"))]
    files += [(p, None) for p in outside]
    for path, module in files:
        own = _subpackage(module) if module else None
        for target, names, line in thermaxis_imports(path, module):
            for name in names:
                if name.startswith("_") and _subpackage(target) != own:
                    found.append(f"{path.relative_to(path.parents[2])}:{line} {target}.{name}")
    return found


def two_way_pairs(src: Path) -> dict[tuple[str, str], list[str]]:
    """Pairs of subpackages that import each other, with one import each way."""
    where: dict[tuple[str, str], list[str]] = defaultdict(list)
    for path in sorted((src / "thermaxis").rglob("*.py")):
        module = _module_of(path, src)
        own = _subpackage(module)
        for target, _, line in thermaxis_imports(path, module):
            theirs = _subpackage(target)
            if own and theirs and theirs != own:
                where[(own, theirs)].append(f"{path.relative_to(src)}:{line}")
    return {
        (a, b): [where[(a, b)][0], where[(b, a)][0]]
        for a, b in sorted(where)
        if a < b and (b, a) in where
    }


def test_no_underscored_name_is_imported_across_subpackages():
    outside = sorted((REPO / "tools").rglob("*.py")) + sorted(
        (REPO / "workflow" / "scripts").glob("*.py")
    )
    assert underscored_crossings(SRC, outside) == []


def test_no_two_subpackages_import_each_other():
    assert two_way_pairs(SRC) == {}


def test_the_checks_see_a_crossing_and_a_knot(tmp_path):
    files = {
        "thermaxis/__init__.py": "",
        "thermaxis/a/__init__.py": "",
        "thermaxis/a/one.py": "from thermaxis.b.two import _private\n",
        "thermaxis/b/__init__.py": "",
        # Relative, and inside a function: still an edge back to a.
        "thermaxis/b/two.py": "def f():\n    from ..a import one\n_private = 1\n",
    }
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    assert underscored_crossings(tmp_path, []) == ["thermaxis/a/one.py:1 thermaxis.b.two._private"]
    assert list(two_way_pairs(tmp_path)) == [("a", "b")]
