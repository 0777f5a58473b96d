"""The `sweep` target end to end: its rows for the main configuration equal the main
workflow's metrics, and their MLR rows numpy least squares on the exact lines."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers.truth import lines_mlr_residuals
from thermaxis.method.metrics import METRIC_COLUMNS


def test_sweep_target_matches_the_main_workflow_for_the_main_configuration(lines_run):
    """The sweep on the session's `lines_run`, whose config carries the sweep grid
    (helpers.runs.LINES_SWEEP)."""
    path, out = lines_run.config, lines_run.out
    config = yaml.safe_load(path.read_text())
    assert config["selection"] == {"n_clusters": 2} and config["models"]["algorithms"] == [
        "mlr",
        "svr",
    ]
    assert config["sweep"]["svr_grid"] == "models"
    proc = lines_run.snakemake("--configfile", str(path), "--", "sweep")
    assert "sweep batch 2/2: 100%" in proc.stderr

    for name in ("summary.csv", "ranking.csv", "factor_effects.csv", "sweep_report.html",
                 "figures/sweep_heatmap.png", "figures/sweep_factor_effects.png"):  # fmt: skip
        assert (out / "sweep" / name).is_file(), name
    summary = pd.read_csv(out / "sweep" / "summary.csv", dtype=str, keep_default_na=False)
    # 3 folds x (fuzzy 2 x 2 + correlation 2 = 6 settings) x (2 degrees + pointwise) x 2 algorithms.
    assert summary["config_id"].nunique() == 6 * 3 * 2
    ours = summary[(summary["method"] == "fuzzy_grey") & (summary["n_clusters"] == "2")
                   & (summary["similarity"] == "pearson") & (summary["grade"] == "deng")
                   & summary["degree"].isin(["1", ""])]  # fmt: skip
    keys = ["fold", "approach", "algorithm", "target"]
    columns = [*keys, *METRIC_COLUMNS]
    theirs = pd.read_csv(out / "tables" / "metrics.csv", dtype=str, keep_default_na=False)
    ours = ours[columns].sort_values(keys, ignore_index=True)
    theirs = theirs[columns].sort_values(keys, ignore_index=True)
    assert len(theirs) == 3 * (2 * 3 + 2 * 1)
    pd.testing.assert_frame_equal(ours, theirs)
    # And its MLR rows against numpy least squares on the exact lines (6 decimals).
    mlr = ours[ours["algorithm"] == "mlr"].set_index(["fold", "approach", "target"])
    for fold, residuals in lines_mlr_residuals(out).items():
        for (approach, target), residual in residuals.items():
            row = mlr.loc[(fold, approach, target)]
            assert float(row["rmse"]) == pytest.approx(np.sqrt(np.mean(residual**2)), abs=1e-6)
            assert float(row["max_abs"]) == pytest.approx(np.abs(residual).max(), abs=1e-6)

    ranking = pd.read_csv(out / "sweep" / "ranking.csv")
    assert ranking["main_config"].sum() == 2 * 2  # decoupled d1 + pointwise, mlr + svr
    html = (out / "sweep" / "sweep_report.html").read_text()
    assert "SIMULATED" in html and "Ranking" in html
    rerun = lines_run.snakemake("--configfile", str(path), "-n", "--", "sweep")
    assert "Nothing to be done" in rerun.stdout + rerun.stderr
