"""The session runs the workflow tests share: what each one is and how it is made.

``tests/conftest.py`` turns :func:`make_lines_run` and :func:`make_built` into the session
fixtures ``lines_run`` and ``built`` and keeps each one's test files on one pytest-xdist
worker.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import yaml

from helpers import REPO
from helpers.builders import write_dataset
from helpers.truth import exact_line
from helpers.workflow import (
    SNAKEMAKE,
    run_snakemake,
    snakemake_env,
    tiny_config,
    workflow_workdir,
)

# --------------------------------------------------------------------------- the `lines` run

LINES_RUNS = ("R1", "R2", "R3")
LINES_SENSORS = ("S1", "S2", "S3", "S4")
# The sweep grid of the `sweep` target (not part of `all`), which test_sweep_workflow runs
# on top of `lines_run`: 3 folds x (fuzzy 2 x 2 + correlation 2 = 6 selection settings)
# x (2 degrees + pointwise) x 2 algorithms.
LINES_SWEEP = {
    "methods": ["fuzzy_grey", "correlation"],
    "n_clusters": [2, 3],
    "similarity": ["pearson"],
    "grade": ["deng", "absolute"],
    "degrees": [1, 2],
    "algorithms": ["mlr", "svr"],
    "svr_grid": "models",
}


@dataclass(frozen=True)
class Interruption:
    """What the lines run's interruption showed (test_interrupted_run checks it)."""

    refused: subprocess.CompletedProcess  # a second start while the first one ran
    first_was_running: bool  # ... and the first one ran on, holding Snakemake's lock
    lock_left: bool  # SIGKILL left that lock behind
    rerun: subprocess.CompletedProcess  # the plain rerun that completed the run


@dataclass(frozen=True)
class Run:
    work: Path
    dataset: Path
    config: Path
    out: Path
    library: Path  # the run's own copy of src/thermaxis, which a test may edit
    env: dict  # Snakemake's environment, with that copy first on the path
    interruption: Interruption

    def snakemake(self, *args, check=True) -> subprocess.CompletedProcess:
        return run_snakemake(self.work, *args, check=check, env=self.env)


# Waiting for the killed run to reach the middle of the workflow; a bound, not a measurement.
WAIT_S = 300


def _wait_for(path: Path, proc: subprocess.Popen) -> None:
    deadline = time.monotonic() + WAIT_S
    while not path.exists():
        assert proc.poll() is None, "the run ended before it could be interrupted"
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.2)


def _interrupted_then_rerun(work: Path, config: Path, env: dict, out: Path) -> Interruption:
    """The `make results` recipe (``python -m thermaxis.pipeline.resume snakemake ...``)
    started cold, killed with SIGKILL once the runs are assembled, then started again."""
    command = [sys.executable, "-m", "thermaxis.pipeline.resume", SNAKEMAKE, "--cores", "2",
               "--configfile", config.name]  # fmt: skip
    locks = work / ".snakemake" / "locks"
    first = subprocess.Popen(command, cwd=work, env=env, start_new_session=True,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        _wait_for(out / "assembled" / "errors.parquet", first)
        refused = subprocess.run(command, cwd=work, env=env, capture_output=True, text=True)
        first_was_running = first.poll() is None and bool(list(locks.glob("*.lock")))
    finally:
        os.killpg(first.pid, signal.SIGKILL)
        first.wait()
    lock_left = bool(list(locks.glob("*.lock")))
    rerun = subprocess.run(command, cwd=work, env=env, capture_output=True, text=True)
    if rerun.returncode != 0:
        raise AssertionError(f"the rerun after SIGKILL failed:\n{rerun.stderr[-5000:]}")
    return Interruption(refused, first_was_running, lock_left, rerun)


def make_lines_run(tmp: Path) -> Run:
    """The whole workflow (target ``all``: tables, figures, compensation, reports) on three
    runs of five measurements whose errors are exact lines (``helpers.truth.exact_line``).

    It is made the way a user recovers from a crash (issue 13): killed with SIGKILL half-way,
    then completed by a plain rerun; the tests that read it check that rerun's results
    against the exact lines. The library it runs is a copy of ``src/``, so that a test can
    edit a module without touching the checkout.
    """
    dataset = write_dataset(
        tmp / "lines",
        runs=LINES_RUNS,
        sensors=LINES_SENSORS,
        curve=exact_line,
        name="lines",
        n_measurements=5,
    )
    work = workflow_workdir(tmp)
    library = tmp / "library"
    shutil.copytree(REPO / "src" / "thermaxis", library / "thermaxis",
                    ignore=shutil.ignore_patterns("__pycache__"))  # fmt: skip
    base = snakemake_env()
    env = {
        **base,
        "PYTHONPATH": os.pathsep.join(filter(None, [str(library), base.get("PYTHONPATH")])),
    }
    # No model reports and one report of all conditions instead of one per run (notebooks
    # are the costliest jobs): the reports build `built` has the per-run and model reports
    # and checks their bytes; test_conditions_report reads the combined one.
    # The paper's decoupled model is deployed: its controller line (K0, tan beta, P0) is the
    # compensation exactly, which test_cli_workflow replays. The figures in both formats.
    config = tiny_config(
        work,
        dataset,
        reports={"model_algorithms": [], "combined_above_runs": 2},
        sweep=LINES_SWEEP,
        compensation={"model": "paper"},
        figures={"algorithms": ["mlr"], "formats": ["png", "pdf"], "dpi": 60},
    )
    out = work / "results" / "lines"
    interruption = _interrupted_then_rerun(work, config, env, out)
    return Run(work=work, dataset=dataset, config=config, out=out,
               library=library / "thermaxis", env=env, interruption=interruption)  # fmt: skip


# --------------------------------------------------------------------------- the reports build


@dataclass(frozen=True)
class Built:
    work: Path
    out: Path
    dataset: Path
    config: Path
    env: dict


def reports_snakemake(built: Built, *args, check=True) -> subprocess.CompletedProcess:
    return run_snakemake(
        built.work, "--configfile", str(built.config), *args, check=check, env=built.env
    )


# Run labels a logger export might use: pandas would read them back from a CSV as 1 and 2.
BUILT_RUNS = ("01", "02")


def make_built(tmp: Path) -> Built:
    """The workflow with every kind of report on a small simulated dataset that reproduces
    the paper, its runs labelled :data:`BUILT_RUNS`."""
    dataset = write_dataset(tmp / "rep", runs=BUILT_RUNS, name="rep", reproduces="xu2023")
    work = workflow_workdir(tmp)
    config = work / "reports_config.yaml"
    config.write_text(
        yaml.safe_dump(
            {
                "dataset": str(dataset),
                "ambient_sensor": "S1",
                "selection": {"n_clusters": 2},
                # One fold, one algorithm: every kind of report, as few notebooks as possible.
                "folds": [BUILT_RUNS[1]],
                "paper_fold": BUILT_RUNS[1],
                "models": {"algorithms": ["mlr"]},
                "figures": {"algorithms": ["mlr"], "formats": ["png"], "dpi": 80},
                "reports": {"model_algorithms": ["mlr"]},
            }
        )
    )
    built = Built(
        work=work,
        out=work / "results" / "rep",
        dataset=dataset,
        config=config,
        env=snakemake_env(),
    )
    reports_snakemake(built)
    return built
