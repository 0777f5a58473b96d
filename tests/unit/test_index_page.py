"""The index pages: the headline's numbers worked out by hand, escaping, the claims table."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pandas as pd
import pytest

from helpers import REPO
from helpers.builders import held_out_summary
from thermaxis.compensation.verdict import deployment_verdict
from thermaxis.errors import DataError
from thermaxis.reports.crossdataset import model_ranking
from thermaxis.reports.index import (
    FigureGroup,
    Headline,
    IndexFigure,
    PageTable,
    answers_table,
    claims_table,
    deployment_comparison,
    render_index,
    render_results_index,
)


def _metrics() -> pd.DataFrame:
    rows = []
    # (fold, approach, algorithm, rmse, max_abs) of the error target; a k row that must not count.
    for fold, approach, algorithm, rmse, max_abs in (
        ("E1", "decoupled", "mlr", 1.0, 2.0),
        ("E2", "decoupled", "mlr", 3.0, 6.0),
        ("E1", "pointwise", "svr", 0.5, 1.0),
        ("E2", "pointwise", "svr", 1.5, 5.0),
    ):
        rows.append(dict(fold=fold, approach=approach, algorithm=algorithm, target="error",
                         rmse=rmse, max_abs=max_abs, mae=0.0, residual_min=0.0, residual_max=0.0))  # fmt: skip
    rows.append(dict(rows[0], target="k", rmse=99.0, max_abs=99.0))
    return pd.DataFrame(rows)


def test_the_ranking_is_each_models_mean_over_folds_best_first():
    ranking = model_ranking(_metrics())
    # pointwise SVR: (0.5 + 1.5) / 2 = 1.0 < decoupled MLR: (1 + 3) / 2 = 2.0.
    assert ranking[["approach", "algorithm"]].values.tolist() == [
        ["pointwise", "svr"],
        ["decoupled", "mlr"],
    ]
    assert ranking["mean_rmse_um"].tolist() == [1.0, 2.0]
    assert ranking["mean_max_abs_um"].tolist() == [3.0, 4.0]
    assert ranking["worst_max_abs_um"].tolist() == [5.0, 6.0]


def test_the_comparison_adds_the_mean_over_the_held_out_runs():
    folds = pd.DataFrame({"fold": ["E1", "E2"], "chosen": ["a", "b"], "rmse_um": [1.0, 2.0],
                          "paper_rmse_um": [4.0, 6.0], "max_abs_um": [2.0, 2.0], "paper_max_abs_um": [8.0, 9.0]})  # fmt: skip
    table = deployment_comparison(folds)
    assert table.iloc[-1].to_dict() == {"fold": "mean", "chosen": "", "rmse_um": 1.5,
                                        "paper_rmse_um": 5.0, "max_abs_um": 2.0, "paper_max_abs_um": 8.5}  # fmt: skip


def _claims() -> pd.DataFrame:
    return pd.DataFrame({"claim": ["decoupling <b>halves</b> the error"], "dataset": ["twin"], "effect": [0.5],
                         "lo": [0.4], "hi": [0.6], "p_value": [0.01], "verdict": ["holds"]})  # fmt: skip


def test_a_claims_table_without_its_columns_is_named():
    with pytest.raises(DataError, match=r"claims.csv: missing column\(s\) verdict"):
        claims_table(_claims().drop(columns="verdict"), "tables/claims.csv")


def _page(**headline) -> str:
    # Held-out run <E2>: largest |deviation| 1.0 -> 1.5 um, beyond the 0.1 um tolerance.
    rows = held_out_summary([("<E2>", 1, 1.0, 1.5, 0.5, 0.5)])
    verdict = deployment_verdict(rows, tolerance=0.1, significance=0.05)
    deployment = {"candidate": "decoupled-mlr-all", "model": "recommended",
                  "recommended_for_deployment": False, "verdict": verdict}  # fmt: skip
    figure = IndexFigure("fig5_unzeroed", "Fig. 5 of run <x>", "figures/f.png",
                         (("png", "figures/f.png"), ("pdf", "figures/f.pdf")))  # fmt: skip
    return render_index(
        "ds<1>",
        "Dataset `ds`: MEASURED data.",
        False,
        Headline(model_ranking(_metrics()), "Recommended: **x**.", deployment, **headline),
        [FigureGroup("Errors and temperatures", (figure,))],
        [PageTable("Runs", pd.DataFrame({"run": ["<R1>"], "n": [3]}), "tables/runs.csv")],
    )


def test_the_page_leads_with_the_answer_and_escapes_every_value():
    page = _page(claims=claims_table(_claims(), "claims.csv"))
    assert page.index('id="answer"') < page.index('id="figures"') < page.index('id="tables"')
    assert "<R1>" not in page and "&lt;R1&gt;" in page and "ds&lt;1&gt;" in page
    assert "not recommended for deployment" in page
    # The verdict's words in the page's unit (model.json and the exports keep ASCII "um").
    assert "of 1 held-out run(s) compensating improves 0 beyond the +/-0.10 µm" in page
    assert (
        "It worsens &lt;E2&gt; (worst &lt;E2&gt;: largest |deviation| +0.50 µm, 50% of its" in page
    )
    assert " um" not in page
    assert "decoupling &lt;b&gt;halves&lt;/b&gt; the error" in page and ">holds<" in page
    # The best model's mean RMSE, in full precision for the sort and rounded for reading.
    assert re.search(r'data-value="1\.0">1\.00</td>', page)
    assert 'href="figures/f.pdf"' in page and 'src="figures/f.png"' in page
    assert "<script src" not in page and '<link rel="stylesheet"' not in page


def test_without_a_claims_table_the_page_says_nothing_about_claims():
    assert "claims" not in _page().lower()


def test_the_page_is_the_same_bytes_for_the_same_tables_in_separate_processes():
    """Two interpreters with different string-hash seeds: a page that followed the order of
    a set or of a dict built from one would differ between them."""
    script = (
        "import sys; sys.path[:0] = ['tests', 'tests/unit']; "
        "from test_index_page import _page; sys.stdout.buffer.write(_page().encode())"
    )
    procs = [
        subprocess.Popen([sys.executable, "-c", script], cwd=REPO, stdout=subprocess.PIPE,
                         env={**os.environ, "PYTHONHASHSEED": seed})
        for seed in ("1", "2")
    ]  # fmt: skip
    pages = [proc.communicate(timeout=120)[0] for proc in procs]
    assert [proc.returncode for proc in procs] == [0, 0]
    assert pages[0] and pages[0] == pages[1]
    assert pages[0].decode() == _page()


def test_the_results_page_links_each_dataset_with_its_best_model():
    summary = pd.DataFrame({"dataset": ["a<", "b"], "data": ["simulated", "measured"],
                            "approach": ["decoupled", "pointwise"], "algorithm": ["mlr", "svr"],
                            "n_folds": [4, 6], "mean_rmse_um": [1.234, 3.0], "mean_max_abs_um": [2.0, 4.0],
                            "worst_max_abs_um": [3.0, 5.0]})  # fmt: skip
    page = render_results_index(summary, {"b": "b/index.html"}, "_datasets/heldout_error.png")
    assert '<a href="b/index.html">b</a>' in page
    assert "<li>a&lt; (SIMULATED)" in page  # no page for a: named, escaped, not linked
    assert "mean RMSE of 1.23 µm over 4 held-out runs" in page
    assert "SIMULATED DATA" in page


def test_the_answers_table_names_the_deployed_model_as_its_verdict_allows():
    summary = pd.DataFrame({"dataset": ["a", "b", "c"], "data": ["simulated"] * 3})
    answers = {
        "a": {"candidate": "super learner", "recommended": True, "by_config": False,
              "rmse_um": 0.5, "paper_rmse_um": 1.0, "outcome": "recommended"},
        "b": {"candidate": "super learner", "recommended": False, "by_config": False,
              "rmse_um": 2.0, "paper_rmse_um": 1.0, "outcome": "not_recommended"},
        "c": {"candidate": "paper", "recommended": False, "by_config": True,
              "rmse_um": 1.7, "paper_rmse_um": 1.7, "outcome": "not_established"},
    }  # fmt: skip
    table = answers_table(summary, answers).set_index("dataset")
    assert table["deployed model"].to_dict() == {
        "a": "super learner",
        "b": "none (closest: super learner)",
        "c": "paper (set by config)",
    }
    assert table.loc["c", "held-out RMSE, µm"] == 1.7
