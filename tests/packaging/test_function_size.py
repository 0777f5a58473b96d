"""At most ten functions of src/ over 60 lines (issue 63).

ruff's PLR0915 (pyproject.toml) counts statements, a proxy that a long call spread over
many lines escapes; this counts the lines themselves, from ``def`` to the function's last
line (decorators excluded, docstring and comments included, as a reader meets them).
"""

from __future__ import annotations

import ast
import textwrap

from helpers import REPO

MAX_LINES = 60
MAX_LONG_FUNCTIONS = 10


def long_functions(source: str) -> list[tuple[str, int, int]]:
    """(name, first line, length) of every function or method over MAX_LINES lines."""
    return [
        (node.name, node.lineno, node.end_lineno - node.lineno + 1)
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.end_lineno - node.lineno + 1 > MAX_LINES
    ]


def test_the_count_is_lines_from_def_to_the_last_line_without_decorators():
    # 1 def line + 59 body lines = 60: allowed; one more line is 61: over.
    body = "".join(f"    x{i} = {i}\n" for i in range(59))
    at_limit = "@staticmethod\ndef at_limit():\n" + body
    over = "def over():\n" + body + "    return x0\n"
    nested = "class Axis:\n" + textwrap.indent(over, "    ")
    assert long_functions(at_limit) == []
    assert long_functions(over) == [("over", 1, 61)]
    assert long_functions(nested) == [("over", 2, 61)]


def test_at_most_ten_functions_of_src_over_sixty_lines():
    found = sorted(
        (length, f"{path.relative_to(REPO)}:{line} {name}")
        for path in (REPO / "src").rglob("*.py")
        for name, line, length in long_functions(path.read_text(encoding="utf-8"))
    )
    listing = "\n".join(f"  {length} lines: {where}" for length, where in reversed(found))
    assert len(found) <= MAX_LONG_FUNCTIONS, (
        f"{len(found)} functions of src/ over {MAX_LINES} lines, expected at most "
        f"{MAX_LONG_FUNCTIONS}; split them into small functions by concern:\n{listing}"
    )
