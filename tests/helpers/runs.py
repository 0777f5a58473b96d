"""The session runs the workflow tests share: what each one is and how it is made.

``tests/conftest.py`` turns :func:`make_lines_run` and :func:`make_built` into the session
fixtures ``lines_run`` and ``built`` and keeps each one's test files on one pytest-xdist
worker.
"""

from __future__ import annotations

import subprocess
from dataclasses import dataclass
from pathlib import Path

import yaml

from helpers.builders import write_dataset
from helpers.truth import exact_line
from helpers.workflow import run_snakemake, snakemake_env, tiny_config, workflow_workdir

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
class Run:
    work: Path
    dataset: Path
    config: Path
    out: Path


def make_lines_run(tmp: Path) -> Run:
    """The whole workflow (target ``all``: tables, figures, compensation, reports) on three
    runs of five measurements whose errors are exact lines (``helpers.truth.exact_line``).
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
    # No model reports (notebooks are the costliest jobs, and this run is made twice, see
    # test_interrupted_run): the reports build `built` has them and checks their bytes.
    # The paper's decoupled model is deployed: its controller line (K0, tan beta, P0) is the
    # compensation exactly, which test_cli_workflow replays.
    config = tiny_config(
        work,
        dataset,
        reports={"model_algorithms": []},
        sweep=LINES_SWEEP,
        compensation={"model": "paper"},
    )
    run_snakemake(work, "--configfile", str(config))
    return Run(work=work, dataset=dataset, config=config, out=work / "results" / "lines")


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
