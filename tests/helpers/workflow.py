"""Snakemake in a scratch work folder: the folder, the environment, a run, a dry run's plan."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import yaml

from helpers import REPO

SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
# 2023-11-14T22:13:20Z: pins the run time recorded in provenance and reports, the one
# field that is otherwise meant to differ between runs.
FIXED_EPOCH = "1700000000"


def workflow_workdir(tmp_path: Path) -> Path:
    """A scratch copy of the workflow's entry points (symlinks), so results stay in tmp."""
    work = tmp_path / "work"
    (work / "data").mkdir(parents=True)
    for name in ("Snakefile", "config", "workflow", "notebooks"):
        os.symlink(REPO / name, work / name)
    return work


def snakemake_env() -> dict:
    env = {
        **os.environ,
        "MPLBACKEND": "Agg",
        "PYTHONHASHSEED": "0",
        "SOURCE_DATE_EPOCH": FIXED_EPOCH,
    }
    env["PATH"] = f"{Path(sys.executable).parent}:{env['PATH']}"
    return env


def run_snakemake(
    work: Path, *args, check=True, env=None, timeout=900
) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        [SNAKEMAKE, "--cores", "2", "--nolock", *args],
        cwd=work,
        capture_output=True,
        text=True,
        env=env or snakemake_env(),
        timeout=timeout,
    )
    if check and proc.returncode != 0:
        raise AssertionError(
            f"snakemake failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}"
            + failed_job_logs(work, proc.stdout + proc.stderr)
        )
    return proc


def failed_job_logs(work: Path, output: str) -> str:
    """The tail of each log Snakemake names for a failed job, which its own output only points to."""
    tails = []
    named = re.findall(r"^\s*log: (.+?) \(check log", output, flags=re.M)
    for name in dict.fromkeys(n for logs in named for n in logs.split(", ")):
        log = work / name
        if log.is_file():
            tails.append(f"\n--- {name} ---\n{log.read_text(errors='replace')[-3000:]}")
    return "".join(tails)


def planned_rules(proc: subprocess.CompletedProcess) -> set[str]:
    """Rule names a Snakemake dry run (`-n`) would run."""
    return set(re.findall(r"^(?:local)?rule (\w+):", proc.stdout + proc.stderr, flags=re.M))


def tiny_config(work: Path, dataset: Path, name: str = "test_config.yaml", **extra) -> Path:
    """The workflow configuration of the end-to-end tests, written to ``work/name``.

    Two algorithms with a two-point SVR grid, one figure and report algorithm, and the
    figures as PNG at 60 dpi (drawing them is most of a figure job) keep the runs short;
    the full algorithm set is exercised by the unit tests and `make results`, the PDFs by
    the ``lines`` run. ``extra`` replaces top-level keys.
    """
    config = {
        "dataset": str(dataset),
        "ambient_sensor": "S1",
        "selection": {"n_clusters": 2},
        "models": {
            "algorithms": ["mlr", "svr"],
            "svr_grid": {"C": [1.0, 10.0], "epsilon": [0.1], "gamma": ["scale"]},
        },
        "figures": {"algorithms": ["mlr"], "formats": ["png"], "dpi": 60},
        "reports": {"model_algorithms": ["mlr"]},
        **extra,
    }
    path = work / name
    path.write_text(yaml.safe_dump(config))
    return path
