"""No module of the library over 700 lines (issue 63): a longer one mixes concerns, and is
split by concern rather than let grow."""

from __future__ import annotations

from pathlib import Path

from helpers import REPO

MAX_LINES = 700


def long_modules(src: Path, limit: int = MAX_LINES) -> list[str]:
    """``path: lines`` of each Python module under ``src`` longer than ``limit`` lines."""
    found = []
    for path in sorted(src.rglob("*.py")):
        n = len(path.read_text(encoding="utf-8").splitlines())
        if n > limit:
            found.append(f"{path.relative_to(src)}: {n}")
    return found


def test_no_module_under_src_is_over_700_lines():
    assert long_modules(REPO / "src") == []


def test_the_check_sees_a_module_one_line_too_long(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "short.py").write_text("x = 1\n" * MAX_LINES)
    (tmp_path / "pkg" / "long.py").write_text("x = 1\n" * (MAX_LINES + 1))
    assert long_modules(tmp_path) == [f"pkg/long.py: {MAX_LINES + 1}"]
