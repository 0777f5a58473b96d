"""Recovery (issue 13): a workflow killed with SIGKILL completes on a plain rerun of the
``make results`` recipe (``python -m thermaxis.pipeline.resume snakemake ...``); a live run
is never disturbed.

The session's ``lines_run`` is made that way (helpers.runs): killed once its runs are
assembled, then rerun. Here is what the interruption showed; the tests of test_workflow,
test_compensation_workflow and test_cli_workflow check the recovered results against the
exact lines the dataset was written from, and its no-op rerun.
"""

from __future__ import annotations


def test_a_second_start_is_refused_while_the_first_runs(lines_run):
    refused = lines_run.interruption.refused
    assert refused.returncode == 1
    assert f"is already running in {lines_run.work}" in refused.stderr
    assert lines_run.interruption.first_was_running


def test_sigkill_leaves_the_lock_and_a_plain_rerun_clears_it_and_completes(lines_run):
    interruption = lines_run.interruption
    assert interruption.lock_left, "SIGKILL should leave Snakemake's lock behind"
    assert interruption.rerun.returncode == 0
    assert "clearing the lock of an interrupted run" in interruption.rerun.stderr
    assert not list((lines_run.work / ".snakemake" / "locks").glob("*.lock"))
    # No output is left marked incomplete (Snakemake's markers, one file per output).
    incomplete = lines_run.work / ".snakemake" / "incomplete"
    assert [p.name for p in incomplete.rglob("*") if p.is_file()] == []
    assert any(lines_run.out.rglob("*.png")) and any(lines_run.out.rglob("*.pdf"))
