"""The workflow's plan, targets, resources and pages, built without Snakemake on datasets of
every shape: the twin, a single-position record, a record without ambient sensor and a
many-run record. Expected names and counts are worked out by hand from the datasets."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from helpers.builders import write_dataset
from thermaxis.config import merge
from thermaxis.figures import registry
from thermaxis.pipeline import paths, preflight, targets, tuning
from thermaxis.pipeline.plan import plan_of
from thermaxis.reports import pages

REPO = Path(__file__).resolve().parents[2]


def checked_of(dataset: Path, tmp_path, monkeypatch, **overrides):
    """The gate on the default config for ``dataset``, run in ``tmp_path`` (results/ there)."""
    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text(encoding="utf-8"))
    monkeypatch.chdir(tmp_path)
    return preflight.check_before_jobs(merge(config, {"dataset": str(dataset), **overrides}))


def pages_of(checked):
    plan = plan_of(checked)
    config = checked.config
    facts = pages.figure_facts(
        plan, checked.dataset.signal_units(), config["selection"], config["decoupling"]["degree"]
    )
    figures = registry.expand(facts, "all")
    return plan, figures, pages.Pages(plan, checked.out, facts, figures, config, "workflow/rules")


@pytest.fixture
def twin(tmp_path, monkeypatch):
    return checked_of(REPO / "data" / "raw" / "twin", tmp_path, monkeypatch)


def test_the_twin_plans_four_folds_both_approaches_and_the_paper(twin):
    plan = plan_of(twin)
    assert plan.runs == plan.folds == ("E1", "E2", "E3", "E4")
    assert plan.approaches == ("decoupled", "pointwise")
    assert plan.paper and plan.simulated and plan.decoupled and plan.ambient == "T10"
    assert plan.algorithms == ("mlr", "svr", "ridge", "pls", "gpr")
    assert plan.paper_algorithms == ("mlr", "svr")
    assert plan.report_fold == "E4"  # config paper_fold
    assert plan.fig_run == "E1" and plan.other_runs == ("E2", "E3", "E4")
    assert plan.embed_format == "png"  # formats png, pdf
    assert plan.report_models == (
        ("decoupled", "mlr"),
        ("decoupled", "svr"),
        ("pointwise", "mlr"),
        ("pointwise", "svr"),
    )
    assert not plan.combined_conditions  # 4 runs, one report each up to 12
    # 4 folds, 4 a worker: one process; 4 runs, 8 a worker: one.
    assert plan.fold_threads == {"models": 1, "recommend": 1} and plan.clean_threads == 1
    assert plan.left_out() == []
    assert "SIMULATED" in plan.statement


def test_the_twins_targets_and_pages(twin):
    plan, figures, page = pages_of(twin)
    outputs = targets.all_outputs(plan, twin.out, figures)
    assert len(outputs) == len(set(outputs))
    root = "results/twin"
    for name in ("paper_report", "dataset_report", "condition_E1", "condition_E4", "model_E4"):
        assert f"{root}/reports/{name}.html" in outputs
    assert f"{root}/tables/paper_comparison.csv" in outputs
    assert f"{root}/tables/table5_slope_intercept.csv" in outputs
    assert set(targets.dataset_tables(plan, root)) == {
        "ambient",
        "ambient_series",
        "kb",
        "kb_markdown",
        "polynomials",
    }
    assert set(targets.audit_tables(plan, root)) == {
        "paper_csv",
        "paper_markdown",
        "faithfulness",
        "faithfulness_markdown",
    }
    # Runs, events, metrics, recommendation, compensation, sensitive points, faithfulness.
    assert [p for _, p, _ in page.index_tables()] == [
        f"{root}/tables/dataset_summary.csv",
        f"{root}/tables/cleaning_events.csv",
        f"{root}/tables/metrics.csv",
        f"{root}/tables/recommendation.csv",
        f"{root}/compensation/summary.csv",
        f"{root}/tables/sensitive_points.csv",
        f"{root}/tables/faithfulness.csv",
    ]
    # Every paper algorithm's error predictions of fold E4 by approach, and k/b decoupled.
    predicted = [k for k in page.paper_report_figures() if k.endswith(("_mlr", "_svr"))]
    assert sorted(predicted) == sorted(
        f"{kind}_E4_{approach}_{algorithm}"
        for algorithm in ("mlr", "svr")
        for kind, approach in (
            ("error_prediction", "decoupled"),
            ("error_prediction", "pointwise"),
            ("kb_prediction", "decoupled"),
        )
    )


@pytest.fixture
def two_runs(tmp_path, monkeypatch):
    """Two runs, four positions, three sensors, no ambient sensor, not the paper's."""
    dataset = write_dataset(tmp_path / "two", name="two")
    return checked_of(dataset, tmp_path, monkeypatch)


def test_a_record_without_ambient_leaves_out_fig3_and_table1(two_runs):
    plan = plan_of(two_runs)
    assert plan.ambient is None and not plan.paper and plan.decoupled
    assert plan.left_out() == [
        "no ambient_sensor: the ambient figure (Fig. 3) and ambient table are left out"
    ]
    assert set(targets.dataset_tables(plan, "r")) == {"kb", "kb_markdown", "polynomials"}
    assert targets.audit_tables(plan, "r") == {}
    linked = targets.linked_tables(plan, "r")
    assert "r/tables/ambient_ranges.csv" not in linked
    assert "r/tables/faithfulness.csv" not in linked
    # 10 tables (summary, QC, Table 5 and its Markdown, sensitive points, metrics,
    # coefficients, fitting, k/b and error predictions) and the statistics' 4 files.
    assert len(linked) == 10 + 4


def test_the_targets_of_two_runs_counted_by_hand(two_runs):
    plan, figures, _ = pages_of(two_runs)
    outputs = targets.all_outputs(plan, "r", figures)
    figure_files = [p for p in outputs if p.startswith("r/figures/")]
    # Figs. 2, 5, 6, 7, 8, 9, 10, 12, the fold comparison, the recommendation and the
    # stability of the sensitive points (11); per fold (2): error predictions of
    # 2 approaches x 2 algorithms, k/b predictions of 2 algorithms, the drift (7 each).
    # Two formats each.
    assert len(figure_files) == (11 + 2 * 7) * 2
    assert [p for p in outputs if not p.startswith("r/figures/")] == [
        "r/tables/dataset_summary.csv",
        "r/assembled/errors.parquet",
        "r/tables/cleaning_qc.csv",
        "r/tables/metrics.csv",
        "r/tables/table5_slope_intercept.csv",
        "r/tables/recommendation.csv",
        "r/tables/recommendation.md",
        "r/recommend/candidates.csv",
        "r/recommend/choice.json",
        "r/tables/comparisons.csv",
        "r/tables/claims.csv",
        "r/tables/claims.md",
        "r/tables/selection_stability.csv",
        "r/compensation/model.json",
        "r/compensation/ThermalCompensation.st",
        *(
            f"r/compensation/{t}.csv"
            for t in ("siemens_840d", "twincat", "residuals", "iso230_2", "summary")
        ),
        "r/provenance.json",
        "r/index.html",
        "r/reports/dataset_report.html",
        "r/reports/condition_R1.html",
        "r/reports/condition_R2.html",
        "r/reports/model_R1.html",
        "r/reports/model_R2.html",
    ]


def test_a_single_position_runs_the_pointwise_branch_alone(tmp_path, monkeypatch):
    dataset = write_dataset(tmp_path / "single", name="single", positions=(50.0,))
    checked = checked_of(dataset, tmp_path, monkeypatch)
    plan, figures, page = pages_of(checked)
    assert not plan.decoupled and plan.approaches == ("pointwise",)
    assert plan.report_models == (("pointwise", "mlr"), ("pointwise", "svr"))
    assert plan.left_out()[0].startswith("a single target position")
    assert targets.dataset_tables(plan, "r") == {}
    outputs = targets.all_outputs(plan, "r", figures)
    assert "r/tables/table5_slope_intercept.csv" not in outputs
    # Figs. 5, 6, 9, 10, the fold comparison, the recommendation and the stability (7);
    # per fold (2): pointwise error predictions of mlr and svr and the drift (3 each).
    assert len([p for p in outputs if p.startswith("r/figures/")]) == (7 + 2 * 3) * 2
    assert not any("kb_prediction" in p or "decoupled" in p for p in outputs)
    assert set(page.model_report_figures("R2")) == {
        "error_prediction_pointwise_mlr",
        "error_prediction_pointwise_svr",
        "compensation_drift",
    }


def test_many_runs_share_one_conditions_report_and_workers(tmp_path, monkeypatch):
    runs = tuple(f"R{i}" for i in range(1, 14))
    dataset = write_dataset(tmp_path / "many", name="many", runs=runs)
    checked = checked_of(dataset, tmp_path, monkeypatch)
    plan, _, page = pages_of(checked)
    assert plan.folds == runs and plan.combined_conditions  # 13 runs > 12
    assert targets.condition_reports(plan, "r") == ["r/reports/conditions.html"]
    assert page.condition_links("R7") == [
        ("section", "results/many/reports/conditions.html#run-R7")
    ]
    # 13 folds at 4 a worker: 3 processes; 13 runs at 8 a worker: 1.
    assert plan.fold_threads == {"models": 3, "recommend": 3} and plan.clean_threads == 1
    table = tuning.resource_table(len(plan.runs), len(plan.folds), lambda w: 1)
    runtime = tuning.rule_resources(table, "recommend")["runtime"]
    assert runtime(None, 1) == 130 and runtime(None, 2) == 260  # 10 min a fold, per attempt
    memory = tuning.rule_resources(table, "model_report")["mem_mb"]
    assert memory(None, 1) == 750
    assert tuning.rule_priority("recommend") > tuning.rule_priority(
        "models"
    ) + tuning.rule_priority("fig_predictions")
    assert tuning.rule_priority("no_such_rule") == 0


def test_a_result_path_is_filled_below_its_root():
    assert paths.under("results/x", paths.FOLD_TABLE, fold="R1", table="metrics") == (
        "results/x/models/R1/metrics.csv"
    )
    assert paths.under("results/x", paths.MODEL_REPORT, fold="R1", ext="html") == (
        "results/x/reports/model_R1.html"
    )
    assert paths.under("results/x", paths.CLEAN_ERRORS) == "results/x/clean/{run}/errors.parquet"
