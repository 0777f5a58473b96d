"""End-to-end: the Snakemake workflow on small datasets written from known truth."""

from __future__ import annotations

import os
import re

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers.truth import b_true, k_true, lines_mlr_residuals
from helpers.workflow import planned_rules


def test_tables_exist_and_decouple_exact_lines(lines_run):
    tables = lines_run.out / "tables"
    for name in (
        "dataset_summary.csv",
        "cleaning_qc.csv",
        "table5_slope_intercept.csv",
        "metrics.csv",
        "coefficients.csv",
        "sensitive_points.csv",
    ):
        assert (tables / name).is_file(), name
    # The dataset does not declare that it reproduces the paper: no audit against it.
    assert not (tables / "paper_comparison.csv").exists()
    kb = pd.read_csv(tables / "table5_slope_intercept.csv")
    assert list(kb.columns) == [
        "run",
        "measurement",
        "time_min",
        "k_um_per_m",
        "b_um",
        "r2",
        "rms_um",
    ]
    assert len(kb) == 15
    r = kb["run"].str[1:].astype(int) - 1
    m = kb["measurement"] - 1
    # The CSV carries 4 decimals; exactness to 1e-9 is tested on the library below.
    np.testing.assert_allclose(kb["k_um_per_m"], k_true(r, m), atol=1e-4)
    np.testing.assert_allclose(kb["b_um"], b_true(r, m), atol=1e-4)
    np.testing.assert_allclose(kb["time_min"], m * 20.0)


def test_metrics_cover_every_fold_approach_algorithm(lines_run):
    metrics = pd.read_csv(lines_run.out / "tables" / "metrics.csv")
    assert list(metrics.columns) == [
        "fold",
        "approach",
        "algorithm",
        "target",
        "rmse",
        "rmse_lo",
        "rmse_hi",
        "max_abs",
        "max_abs_lo",
        "max_abs_hi",
        "mae",
        "mae_lo",
        "mae_hi",
        "residual_min",
        "residual_max",
    ]
    for metric in ("rmse", "max_abs", "mae"):
        assert (metrics[f"{metric}_lo"] <= metrics[metric] + 1e-6).all()
        assert (metrics[metric] <= metrics[f"{metric}_hi"] + 1e-6).all()
    combos = set(zip(metrics["fold"], metrics["approach"], metrics["algorithm"], strict=True))
    assert combos == {
        (f, a, g)
        for f in ("R1", "R2", "R3")
        for a in ("decoupled", "pointwise")
        for g in ("mlr", "svr")
    }
    decoupled = metrics[metrics["approach"] == "decoupled"]
    assert set(decoupled["target"]) == {"k", "b", "error"}
    assert (metrics["rmse"] <= metrics["max_abs"] + 1e-12).all()
    # The MLR rows by hand, against the exact lines (the CSV carries 6 decimals).
    rows = metrics.set_index(["fold", "approach", "algorithm", "target"])
    for fold, residuals in lines_mlr_residuals(lines_run.out).items():
        for (approach, target), residual in residuals.items():
            row = rows.loc[(fold, approach, "mlr", target)]
            assert row["rmse"] == pytest.approx(np.sqrt(np.mean(residual**2)), abs=1e-6)
            assert row["max_abs"] == pytest.approx(np.abs(residual).max(), abs=1e-6)


def test_claims_and_comparisons_are_tables_of_verdicts_and_intervals(lines_run):
    tables = lines_run.out / "tables"
    claims = pd.read_csv(tables / "claims.csv", keep_default_na=False, na_values=[""])
    assert list(claims.columns) == ["claim", "dataset", "effect", "lo", "hi", "p_value", "verdict"]
    assert set(claims["verdict"]) <= {"holds", "reversed", "not resolved"}
    done = claims.dropna(subset=["effect"])
    assert ((done["lo"] <= done["effect"] + 1e-6) & (done["effect"] <= done["hi"] + 1e-6)).all()
    assert (tables / "claims.md").read_text(encoding="utf-8").startswith("# The paper's claims")
    comparisons = pd.read_csv(tables / "comparisons.csv")
    # 2 approaches x 2 algorithms: 6 pairs, and the recommendation against the paper's.
    assert len(comparisons) == 7
    # Holm by hand over the 7 p-values: the i-th smallest times (7 - i), running maximum.
    p = comparisons["p_permutation"].to_numpy()
    order = np.argsort(p, kind="stable")
    holm = np.minimum(1.0, np.maximum.accumulate(p[order] * (len(p) - np.arange(len(p)))))
    np.testing.assert_allclose(comparisons["p_permutation_holm"].to_numpy()[order], holm, atol=1e-6)
    # Decoupled against point-by-point MLR: the mean over folds of each fold's error RMSE,
    # by hand; the claim's effect is the point-by-point RMSE minus the decoupled one.
    mean_rmse = {
        approach: np.mean([np.sqrt(np.mean(r[(approach, "error")] ** 2))
                           for r in lines_mlr_residuals(lines_run.out).values()])
        for approach in ("decoupled", "pointwise")
    }  # fmt: skip
    pair = comparisons.set_index(["a", "b"]).loc[("decoupled mlr", "pointwise mlr")]
    assert pair["rmse_a"] == pytest.approx(mean_rmse["decoupled"], abs=1e-6)
    assert pair["rmse_b"] == pytest.approx(mean_rmse["pointwise"], abs=1e-6)
    effect = claims.set_index("claim").loc[
        "decoupled modelling predicts the error better than point-by-point (MLR)", "effect"
    ]
    assert effect == pytest.approx(mean_rmse["pointwise"] - mean_rmse["decoupled"], abs=2e-6)
    stability = pd.read_csv(tables / "selection_stability.csv")
    # Three runs: each fold's selection sees two, so two leave-one-run-out subsets.
    assert set(stability["n_subsets"]) == {2}
    assert stability["frequency"].between(0.0, 1.0).all()


def test_noop_rerun_has_nothing_to_do(lines_run):
    proc = lines_run.snakemake("--configfile", str(lines_run.config), "-n")
    assert "Nothing to be done" in proc.stdout + proc.stderr


def test_plot_option_reruns_only_figure_rules(lines_run):
    changed = lines_run.work / "changed_config.yaml"
    doc = yaml.safe_load(lines_run.config.read_text())
    doc["figures"] = {**doc["figures"], "dpi": 150}
    changed.write_text(yaml.safe_dump(doc))
    proc = lines_run.snakemake("--configfile", str(changed), "-n")
    rules = planned_rules(proc)
    assert rules, proc.stdout
    # Reports embed the figures and the index links them, so they follow; nothing upstream does.
    # provenance.json (written with the index) records the hash of the effective config.
    assert all(
        r.startswith("fig") or r.endswith("_report") or r in ("all", "index") for r in rules
    ), rules
    assert "fig_data" in rules


def test_editing_a_module_selection_imports_indirectly_reruns_selection(lines_run):
    """method/estimators.py is named in no rule; the models rule's script reaches it through
    method.folds.

    The edit is made in the run's own copy of the library (``lines_run.library``), never in
    the checkout. Snakemake compares checksums of inputs newer than the outputs, so the edit
    must change the file's content; it is restored byte for byte afterwards.
    """
    module = lines_run.library / "method" / "estimators.py"
    original, stat = module.read_bytes(), module.stat()
    try:
        module.write_bytes(original + b"\n# an edit of the method\n")
        dry = lines_run.snakemake("--configfile", str(lines_run.config), "-n")
    finally:
        module.write_bytes(original)
        os.utime(module, (stat.st_atime, stat.st_mtime))
    assert re.search(r"rule models:", dry.stdout)
    assert not re.search(r"rule clean:", dry.stdout)
