"""End-to-end: the Snakemake workflow on small datasets written from known truth."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers import REPO
from helpers.builders import set_csv_cell, write_dataset
from helpers.locks import library_lock
from helpers.truth import b_true, k_true
from helpers.workflow import planned_rules, run_snakemake, tiny_config
from helpers.workflow import workflow_workdir as workdir
from thermaxis.config import merge
from thermaxis.errors import DataError
from thermaxis.pipeline.preflight import check_before_jobs


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
    assert (
        comparisons["p_permutation_holm"].dropna() >= comparisons["p_permutation"].dropna()
    ).all()
    stability = pd.read_csv(tables / "selection_stability.csv")
    # Three runs: each fold's selection sees two, so two leave-one-run-out subsets.
    assert set(stability["n_subsets"]) == {2}
    assert stability["frequency"].between(0.0, 1.0).all()


def test_noop_rerun_has_nothing_to_do(lines_run, library_unchanged):
    proc = run_snakemake(lines_run.work, "--configfile", str(lines_run.config), "-n")
    assert "Nothing to be done" in proc.stdout + proc.stderr


def test_bad_input_stops_with_one_line_and_leaves_no_output(tmp_path):
    dataset = write_dataset(tmp_path / "bad", name="bad")
    path = dataset / "R2" / "errors" / "M02.csv"
    set_csv_cell(path, 3, 2, "n/a")
    work = workdir(tmp_path)
    proc = run_snakemake(work, "--configfile", str(tiny_config(work, dataset)), check=False)
    assert proc.returncode != 0
    expected = f"thermaxis error: {path}: line 4, column 'error_um': expected a number, got 'n/a'"
    assert expected in proc.stderr
    assert not (work / "results" / "bad" / "clean" / "R2").exists() or not any(
        (work / "results" / "bad" / "clean" / "R2").iterdir()
    )
    assert not (work / "results" / "bad" / "tables" / "table5_slope_intercept.csv").exists()


def _parse_time_check(work: Path, config: Path):
    """What the workflow checks while Snakemake parses it (common.smk calls the same function)."""
    with open(REPO / "config" / "config.yaml", encoding="utf-8") as fh:
        base = yaml.safe_load(fh)
    return check_before_jobs(merge(base, yaml.safe_load(config.read_text())))


def test_bad_sheet_stops_before_any_job(tmp_path):
    dataset = write_dataset(tmp_path / "sheet", name="sheet")
    (dataset / "runs.tsv").write_text(
        (dataset / "runs.tsv").read_text().replace("R2\t2\t2000", "R2\t2\tx")
    )
    work = workdir(tmp_path)
    with pytest.raises(DataError) as refused:
        _parse_time_check(work, tiny_config(work, dataset))
    expected = (
        f"{dataset / 'runs.tsv'}: line 3, column 'feed_mm_min': expected a finite number, got 'x'"
    )
    assert str(refused.value) == expected
    assert not (work / "results").exists()


def test_bad_config_value_is_rejected_by_schema(tmp_path):
    dataset = write_dataset(tmp_path / "cfg", name="cfg")
    work = workdir(tmp_path)
    with pytest.raises(
        ValueError, match="config decoupling/degree: 7 is greater than the maximum of 3"
    ):
        _parse_time_check(work, tiny_config(work, dataset, decoupling={"degree": 7}))


def test_plot_option_reruns_only_figure_rules(lines_run, library_unchanged):
    changed = lines_run.work / "changed_config.yaml"
    doc = yaml.safe_load(lines_run.config.read_text())
    doc["figures"] = {**doc["figures"], "dpi": 150}
    changed.write_text(yaml.safe_dump(doc))
    proc = run_snakemake(lines_run.work, "--configfile", str(changed), "-n")
    rules = planned_rules(proc)
    assert rules, proc.stdout
    # Reports embed the figures and the index links them, so they follow; nothing upstream does.
    # provenance.json (written with the index) records the hash of the effective config.
    assert all(
        r.startswith("fig") or r.endswith("_report") or r in ("all", "index") for r in rules
    ), rules
    assert "fig_data" in rules


def test_editing_a_module_selection_imports_indirectly_reruns_selection(
    lines_run, tmp_path_factory
):
    """method/estimators.py is named in no rule; the models rule's script reaches it through
    method.folds.

    Snakemake compares checksums of inputs newer than the outputs, so the edit must
    change the file's content; it is restored byte for byte afterwards.
    """
    import os

    import thermaxis.method.estimators

    work, config = lines_run.work, lines_run.config
    module = Path(thermaxis.method.estimators.__file__)
    original, stat = module.read_bytes(), module.stat()
    with library_lock(tmp_path_factory, exclusive=True):  # other workers' dry runs wait
        try:
            module.write_bytes(original + b"\n# an edit of the method\n")
            dry = run_snakemake(work, "--configfile", str(config), "-n")
        finally:
            module.write_bytes(original)
            os.utime(module, (stat.st_atime, stat.st_mtime))
    assert re.search(r"rule models:", dry.stdout)
    assert not re.search(r"rule clean:", dry.stdout)
