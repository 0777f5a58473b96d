"""Many runs: above ``reports.combined_above_runs`` one report of all conditions replaces the per-run ones.

The plan is checked with a dry run on the ``lines`` run's work folder; the notebook is
executed on that run's tables the way the rule runs it, and its numbers are checked
against the assembled errors read here.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pandas as pd

from helpers import REPO
from helpers.runs import LINES_RUNS, LINES_SWEEP
from helpers.workflow import planned_rules, run_snakemake, snakemake_env, tiny_config


def test_more_runs_than_the_limit_plan_one_conditions_report(lines_run):
    config = tiny_config(
        lines_run.work,
        lines_run.dataset,
        "many_runs.yaml",
        reports={"model_algorithms": [], "combined_above_runs": 2},
        sweep=LINES_SWEEP,
    )
    plan = planned_rules(
        run_snakemake(lines_run.work, "--configfile", str(config), "-n", "--forceall")
    )
    assert "conditions_report" in plan and "condition_report" not in plan
    default = planned_rules(
        run_snakemake(lines_run.work, "--configfile", str(lines_run.config), "-n", "--forceall")
    )
    assert "condition_report" in default and "conditions_report" not in default


def test_the_conditions_report_has_a_section_per_run_and_the_small_multiples(lines_run, tmp_path):
    out = lines_run.out
    inputs = {
        "summary": str(out / "tables" / "dataset_summary.csv"),
        "errors": str(out / "assembled" / "errors.parquet"),
        "temperatures": str(out / "assembled" / "temperatures.parquet"),
    }
    parameters = {
        "dataset_name": "lines", "simulated": True, "statement": "Dataset `lines`: SIMULATED data.",
        "dataset_root": str(lines_run.dataset), "repo": str(REPO), "config": {}, "inputs": inputs,
        "runs": list(LINES_RUNS),
    }  # fmt: skip
    page = tmp_path / "conditions.html"
    proc = subprocess.run(
        [sys.executable, "-m", "thermaxis.reports.notebooks", "run", str(REPO / "notebooks" / "conditions_report.ipynb"),
         str(tmp_path / "conditions.ipynb"), str(page), "--kernel", "python3", "--title", "Conditions",
         "--parameters", json.dumps(parameters)],
        cwd=REPO, env=snakemake_env(), capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    text = page.read_text(encoding="utf-8")
    for run in LINES_RUNS:
        assert f'<section id="run-{run}"><h3>Run {run}</h3>' in text
    # One small-multiples figure above the sections, embedded.
    assert len(re.findall(r'<img [^>]*src="data:image/png;base64,', text)) == 1
    assert text.index("All runs at a glance") < text.index('id="run-R1"') < text.index("Provenance")
    errors = pd.read_parquet(inputs["errors"])
    largest = errors.assign(a=errors["error_um"].abs()).groupby("run")["a"].max()
    assert (
        f"The largest unzeroed error is {largest.max():.1f} µm, in run {largest.idxmax()}" in text
    )
    counts = errors.groupby("run")["measurement"].nunique()
    assert counts.min() == counts.max()  # the lines dataset: five measurements in every run
    assert f"{len(LINES_RUNS)} runs of {counts.min()} measurements each." in text
