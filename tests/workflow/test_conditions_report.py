"""Many runs: above ``reports.combined_above_runs`` one report of all conditions replaces the per-run ones.

The ``lines`` run sets the limit to two, so its three runs get the combined report (the
only run of the rule ``conditions_report``); its page's numbers are checked against the
assembled errors read here. The plan at the schema's limit is checked with a dry run.
"""

from __future__ import annotations

import re

import pandas as pd

from helpers.runs import LINES_RUNS, LINES_SWEEP
from helpers.workflow import planned_rules, tiny_config


def test_more_runs_than_the_limit_plan_one_conditions_report(lines_run):
    plan = planned_rules(
        lines_run.snakemake("--configfile", str(lines_run.config), "-n", "--forceall")
    )
    assert "conditions_report" in plan and "condition_report" not in plan
    per_run = tiny_config(lines_run.work, lines_run.dataset, "per_run.yaml",
                          reports={"model_algorithms": []}, sweep=LINES_SWEEP)  # fmt: skip
    default = planned_rules(lines_run.snakemake("--configfile", str(per_run), "-n", "--forceall"))
    assert "condition_report" in default and "conditions_report" not in default


def test_the_conditions_report_has_a_section_per_run_and_the_small_multiples(lines_run):
    out = lines_run.out
    page = out / "reports" / "conditions.html"
    assert not list((out / "reports").glob("condition_*.html"))
    text = page.read_text(encoding="utf-8")
    for run in LINES_RUNS:
        assert f'<section id="run-{run}"><h3>Run {run}</h3>' in text
    # One small-multiples figure above the sections, embedded.
    assert len(re.findall(r'<img [^>]*src="data:image/png;base64,', text)) == 1
    assert text.index("All runs at a glance") < text.index('id="run-R1"') < text.index("Provenance")
    errors = pd.read_parquet(out / "assembled" / "errors.parquet")
    largest = errors.assign(a=errors["error_um"].abs()).groupby("run")["a"].max()
    assert (
        f"The largest unzeroed error is {largest.max():.1f} µm, in run {largest.idxmax()}" in text
    )
    counts = errors.groupby("run")["measurement"].nunique()
    assert counts.min() == counts.max()  # the lines dataset: five measurements in every run
    assert f"{len(LINES_RUNS)} runs of {counts.min()} measurements each." in text
