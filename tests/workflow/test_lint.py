"""The workflow and the Python sources stay lint-clean and formatted."""

import subprocess
import sys
from pathlib import Path

from helpers import REPO

BIN = Path(sys.executable).parent


def test_snakemake_lint_reports_nothing():
    proc = subprocess.run(
        [str(BIN / "snakemake"), "--lint"], cwd=REPO, capture_output=True, text=True, timeout=300
    )
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert "Congratulations, your workflow is in a good condition!" in out, out


def test_snakefmt_check_passes():
    proc = subprocess.run(
        [str(BIN / "snakefmt"), "--check", "Snakefile", "workflow/rules/"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


# What `make lint` checks, all of it clean.
RUFF_CLEAN = ["src", "tools", "workflow/scripts", "tests"]
RUFF_CLEAN_FILES: list[str] = []


def test_ruff_check_passes():
    proc = subprocess.run(
        [str(BIN / "ruff"), "check", "--no-cache", *RUFF_CLEAN, *RUFF_CLEAN_FILES],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
