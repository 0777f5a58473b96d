"""No import circle between the modules of src/thermaxis.

The imports are read with ``ast`` (no module is executed): ``import a.b``, ``from a import
b`` and relative imports (``from .solver import x``, ``from .. import errors``), wherever they
stand. An import is *deferred* when it sits inside a function (it runs when the function is
called) and *module level* otherwise (class bodies and ``if``/``try`` blocks run at import
time); imports under ``if TYPE_CHECKING:`` never run and are left out.

Which imports count: both, in two tests.

- ``test_no_circle_at_module_level``: the circles that can break ``import`` itself (a
  module seeing a half-initialised one).
- ``test_no_circle_through_deferred_imports``: the same graph plus the deferred imports.
  Deferring an import is the usual way to keep a heavy third-party import (matplotlib,
  scikit-learn, papermill) off the import path, and those are not in this graph at all;
  between two thermaxis modules, a deferred import that closes a circle only hides a
  layering knot, such as the old ``io`` -> ``guard`` (module level) -> ``io.DataError``
  (inside a function) that moved DataError to ``thermaxis.errors``.

An edge goes to the module named: ``from pkg import sub`` to ``pkg.sub`` when that is a
module, to ``pkg`` (its ``__init__``) otherwise. The parent packages Python also runs on
the way (``pkg`` for ``import pkg.sub``) are not edges: all subpackage ``__init__`` files
but twin's are docstrings, and twin's imports its own submodules, which would make every
``from thermaxis.twin.x import ...`` inside twin a circle that cannot fail. Dynamic imports
(``importlib.import_module``, as in ``thermaxis.__getattr__``) are not seen.
"""

from __future__ import annotations

import ast
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import pytest

from helpers import REPO

SRC = REPO / "src"


@dataclass(frozen=True)
class Import:
    source: str
    target: str
    line: int
    deferred: bool


def modules(root: Path, package: str = "thermaxis") -> dict[str, tuple[Path, bool]]:
    """Dotted name -> (file, is a package) for every module of ``package`` under ``root``."""
    found = {}
    for path in sorted((root / package).rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        found[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return found


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


class _Imports(ast.NodeVisitor):
    def __init__(self, name: str, is_package: bool, known: dict):
        self.name, self.known, self.depth, self.found = name, known, 0, []
        self.package = name if is_package else name.rpartition(".")[0]

    def _add(self, target: str, node: ast.stmt) -> None:
        # ``import a.b.c`` of a name that is not a module (``import thermaxis.x.y`` where y
        # is a function is an error anyway): the longest prefix that is.
        while target and target not in self.known:
            target = target.rpartition(".")[0]
        if target:
            self.found.append(Import(self.name, target, node.lineno, self.depth > 0))

    def visit_FunctionDef(self, node):
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    visit_AsyncFunctionDef = visit_Lambda = visit_FunctionDef

    def visit_If(self, node):
        if _is_type_checking(node.test):
            for child in node.orelse:
                self.visit(child)
        else:
            self.generic_visit(node)

    def visit_Import(self, node):
        for alias in node.names:
            self._add(alias.name, node)

    def visit_ImportFrom(self, node):
        if node.level:
            base = self.package.split(".")
            base = base[: len(base) - (node.level - 1)]
            module = ".".join(base + ([node.module] if node.module else []))
        else:
            module = node.module
        for alias in node.names:
            submodule = f"{module}.{alias.name}"
            self._add(submodule if submodule in self.known else module, node)


def imports(root: Path, package: str = "thermaxis") -> list[Import]:
    known = modules(root, package)
    found = []
    for name, (path, is_package) in known.items():
        visitor = _Imports(name, is_package, known)
        visitor.visit(ast.parse(path.read_text(encoding="utf-8"), filename=str(path)))
        found.extend(visitor.found)
    return found


def graph(found: list[Import], deferred: bool) -> dict[str, dict[str, Import]]:
    """source -> target -> the first import of that edge."""
    edges: dict[str, dict[str, Import]] = {}
    for item in found:
        if deferred or not item.deferred:
            edges.setdefault(item.source, {}).setdefault(item.target, item)
    return edges


def circles(edges: dict[str, dict[str, Import]]) -> list[list[Import]]:
    """One shortest circle through each strongly connected group of modules (Tarjan)."""
    index, low, on_stack, stack, groups = {}, {}, set(), [], []

    def connect(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in edges.get(node, {}):
            if nxt not in index:
                connect(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            group = set()
            while True:
                member = stack.pop()
                on_stack.discard(member)
                group.add(member)
                if member == node:
                    break
            if len(group) > 1 or node in edges.get(node, {}):
                groups.append(group)

    for node in sorted(edges):
        if node not in index:
            connect(node)
    return [_shortest_circle(edges, group) for group in groups]


def _shortest_circle(edges, group: set[str]) -> list[Import]:
    start = min(group)
    # Breadth first from start back to start, inside the group.
    came: dict[str, Import] = {}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for nxt, item in sorted(edges.get(node, {}).items()):
            if nxt not in group:
                continue
            if nxt == start:
                path = [item]
                while path[0].source != start:
                    path.insert(0, came[path[0].source])
                return path
            if nxt not in came:
                came[nxt] = item
                queue.append(nxt)
    raise AssertionError(f"no circle in {group}")  # a strongly connected group has one


def describe(circle: list[Import]) -> str:
    steps = [
        f"{item.source} (line {item.line}{', in a function' if item.deferred else ''})"
        for item in circle
    ]
    return " -> ".join([*steps, circle[0].source])


def _fail_on(found_circles: list[list[Import]], kind: str) -> None:
    if found_circles:
        lines = "\n".join(describe(circle) for circle in found_circles)
        pytest.fail(f"{len(found_circles)} import circle(s) {kind}:\n{lines}", pytrace=False)


# --------------------------------------------------------------------------- src/thermaxis


@pytest.fixture(scope="module")
def found() -> list[Import]:
    return imports(SRC)


def test_no_circle_at_module_level(found):
    _fail_on(circles(graph(found, deferred=False)), "at module level")


def test_no_circle_through_deferred_imports(found):
    _fail_on(circles(graph(found, deferred=True)), "through imports inside functions")


def test_the_walk_sees_the_library(found):
    known = modules(SRC)
    assert len(known) == len(list((SRC / "thermaxis").rglob("*.py")))
    edges = {(item.source, item.target) for item in found}
    # Three imports written three ways: absolute, relative (twin/__init__.py), deferred.
    assert ("thermaxis.compensation.runtime", "thermaxis.compensation.model") in edges
    assert ("thermaxis.twin", "thermaxis.twin.solver") in edges
    deferred = {(item.source, item.target) for item in found if item.deferred}
    assert ("thermaxis.compensation.model", "thermaxis.method.folds") in deferred


# --------------------------------------------------------------------------- the walk itself


def _write(root: Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_a_circle_is_named_with_its_lines(tmp_path):
    # pkg.a -> pkg.sub.b (relative, two levels) -> pkg.a (module level): one circle.
    _write(
        tmp_path,
        {
            "pkg/__init__.py": "",
            "pkg/a.py": "import os\nfrom pkg.sub import b\n",
            "pkg/sub/__init__.py": "",
            "pkg/sub/b.py": '"""doc"""\n\nfrom .. import a\n',
            "pkg/c.py": (
                "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg import d\n"
            ),
            "pkg/d.py": "from .c import TYPE_CHECKING\n",
        },
    )
    found_circles = circles(graph(imports(tmp_path, "pkg"), deferred=False))
    assert [describe(c) for c in found_circles] == ["pkg.a (line 2) -> pkg.sub.b (line 3) -> pkg.a"]


def test_a_deferred_import_closes_a_circle_only_in_the_second_graph(tmp_path):
    # The old io/guard knot: io imports guard at load time, guard imports io in a function.
    _write(
        tmp_path,
        {
            "pkg/__init__.py": "",
            "pkg/io.py": "from pkg import guard\n\nclass DataError(Exception):\n    pass\n",
            "pkg/guard.py": "def check():\n    from pkg.io import DataError\n    raise DataError\n",
        },
    )
    found = imports(tmp_path, "pkg")
    assert circles(graph(found, deferred=False)) == []
    (circle,) = circles(graph(found, deferred=True))
    assert describe(circle) == "pkg.guard (line 2, in a function) -> pkg.io (line 1) -> pkg.guard"
