"""`make help` lists every target of the Makefile, one line each."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from helpers import REPO

MAKEFILE = REPO / "Makefile"


def _targets() -> list[str]:
    """The Makefile's rule names (``name:`` at the start of a line, not ``NAME :=``)."""
    text = MAKEFILE.read_text(encoding="utf-8")
    return re.findall(r"^([a-z][a-z0-9_-]*):(?!=)", text, flags=re.M)


def _help_lines() -> list[str]:
    if shutil.which("make"):
        proc = subprocess.run(
            ["make", "-s", "-f", str(MAKEFILE), "help"],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert proc.returncode == 0, proc.stderr
        return proc.stdout.splitlines()
    # Without make: the echo lines of the help recipe.
    recipe = MAKEFILE.read_text(encoding="utf-8").split("\nhelp:\n", 1)[1].split("\n\n", 1)[0]
    return re.findall(r'@echo "(.*)"', recipe)


def test_help_lists_every_target_once():
    targets = _targets()
    assert {"help", "results", "test", "lint"} <= set(targets)
    listed = [line.split()[1] for line in _help_lines() if line.startswith("make ")]
    assert sorted(listed) == sorted(targets)
    assert len(listed) == len(set(listed))


@pytest.mark.parametrize("line", _help_lines())
def test_every_help_line_says_what_the_target_does(line):
    assert re.fullmatch(r"make [a-z0-9_-]+ {2,}\S.*", line), line
