"""The `sweep` target end to end: its rows for the main configuration equal the main workflow's metrics."""

from __future__ import annotations

import pandas as pd
import pytest
import yaml

from conftest import run_snakemake, workflow_workdir, write_dataset
from thermaxis.evaluate import METRIC_COLUMNS

pytestmark = pytest.mark.slow


def test_sweep_target_matches_the_main_workflow_for_the_main_configuration(tmp_path):
    dataset = write_dataset(tmp_path / "lines", runs=("R1", "R2", "R3"), sensors=("S1", "S2", "S3", "S4"),
                            name="lines", n_measurements=5)  # fmt: skip
    work = workflow_workdir(tmp_path)
    main_models = {"algorithms": ["mlr", "svr"], "svr_grid": {"C": [1.0, 10.0], "epsilon": [0.1], "gamma": ["scale"]}}
    config = {
        "dataset": str(dataset),
        "ambient_sensor": "S1",
        "selection": {"n_clusters": 2},
        "models": main_models,
        "sweep": {"methods": ["fuzzy_grey", "correlation"], "n_clusters": [2, 3], "similarity": ["pearson"],
                  "grade": ["deng", "absolute"], "degrees": [1, 2], "algorithms": ["mlr", "svr"],
                  "svr_grid": "models"},  # fmt: skip
        "figures": {"formats": ["png"]},
    }
    path = work / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(work, "--configfile", str(path), "--", "results/lines/tables/metrics.csv", "sweep")
    assert "sweep batch 2/2: 100%" in proc.stderr

    out = work / "results" / "lines"
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

    ranking = pd.read_csv(out / "sweep" / "ranking.csv")
    assert ranking["main_config"].sum() == 2 * 2  # decoupled d1 + pointwise, mlr + svr
    html = (out / "sweep" / "sweep_report.html").read_text()
    assert "SIMULATED" in html and "Ranking" in html
    rerun = run_snakemake(work, "--configfile", str(path), "-n", "--", "sweep")
    assert "Nothing to be done" in rerun.stdout + rerun.stderr
