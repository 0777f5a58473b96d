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


def test_every_repository_file_the_makefile_reads_is_tracked():
    # A clean clone has only tracked files: a spec matched by .gitignore (as data/benchmarks/
    # once was, by a pattern meant for Snakemake's benchmarks/ folder) breaks `make results`.
    text = MAKEFILE.read_text(encoding="utf-8")
    named = sorted(
        set(re.findall(r"\b((?:data|config|profiles|envs)/[\w./-]+\.(?:ya?ml|txt))", text))
    )
    assert "data/benchmarks/fl_thermal.yaml" in named
    if not (REPO / ".git").exists():
        pytest.skip("not a git checkout: nothing to compare the files with")
    ignored = subprocess.run(
        ["git", "check-ignore", "--no-index", *named], cwd=REPO, capture_output=True, text=True
    ).stdout.split()
    assert ignored == [], f"ignored by .gitignore: {ignored}"
    for name in named:
        assert (REPO / name).is_file(), name


@pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")
@pytest.mark.parametrize("verbose, option", [("0", ""), ("1", " --verbose")])
def test_the_snakemake_targets_run_the_thermaxis_command_and_v1_makes_it_verbose(verbose, option):
    """One code path: `make results/sweep/report` print what `thermaxis run/sweep/report` do
    (docs/cli.md); test_make_results and test_make_targets run them."""
    proc = subprocess.run(
        ["make", "-n", "-f", str(MAKEFILE), "-o", "env", "results", "sweep",
         "report", f"V={verbose}", "CORES=2"],
        cwd=REPO, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    commands = [line.split("thermaxis ", 1)[1] for line in proc.stdout.splitlines()
                if "/thermaxis " in line]  # fmt: skip
    assert commands == [
        f"run --cores 2{option} </dev/null",
        f"sweep --cores 2{option}",
        f"report --zip --cores 2{option}",
    ]
