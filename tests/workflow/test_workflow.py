"""End-to-end: the Snakemake workflow on small datasets written from known truth."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from conftest import run_snakemake, set_csv_cell, write_dataset
from conftest import workflow_workdir as workdir

pytestmark = pytest.mark.slow

def tiny_config(work: Path, dataset: Path, **extra) -> Path:
    # Two algorithms and one figure algorithm keep the end-to-end runs short; the
    # full algorithm set is exercised by the unit tests and `make results`.
    config = {
        "dataset": str(dataset),
        "ambient_sensor": "S1",
        "selection": {"n_clusters": 2},
        "models": {"algorithms": ["mlr", "svr"], "svr_grid": {"C": [1.0, 10.0], "epsilon": [0.1], "gamma": ["scale"]}},
        "figures": {"algorithms": ["mlr"]},
        "reports": {"model_algorithms": ["mlr"]},
    }
    config.update(extra)
    path = work / "test_config.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


# k and b of each (run, measurement): exact lines the pipeline must recover.
def k_true(r, m):
    return -10.0 + 0.5 * m + r + 0.1 * m * m


def b_true(r, m):
    return -0.7 * m - 0.1 * r + 0.05 * r * m


def exact_line(r, m, x):
    return k_true(r, m) * (x - x[0]) / 1000.0 + b_true(r, m)


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("e2e")
    dataset = write_dataset(tmp / "lines", runs=("R1", "R2", "R3"), curve=exact_line, name="lines", n_measurements=5)
    work = workdir(tmp)
    config = tiny_config(work, dataset)
    run_snakemake(work, "--configfile", str(config))
    return work, dataset, config


def test_tables_exist_and_decouple_exact_lines(finished_run):
    work, _, _ = finished_run
    tables = work / "results" / "lines" / "tables"
    for name in ("dataset_summary.csv", "cleaning_qc.csv", "table5_slope_intercept.csv", "metrics.csv",
                 "coefficients.csv", "sensitive_points.csv"):
        assert (tables / name).is_file(), name
    # The dataset does not declare that it reproduces the paper: no audit against it.
    assert not (tables / "paper_comparison.csv").exists()
    kb = pd.read_csv(tables / "table5_slope_intercept.csv")
    assert list(kb.columns) == ["run", "measurement", "time_min", "k_um_per_m", "b_um", "r2", "rms_um"]
    assert len(kb) == 15
    r = kb["run"].str[1:].astype(int) - 1
    m = kb["measurement"] - 1
    # The CSV carries 4 decimals; exactness to 1e-9 is tested on the library below.
    np.testing.assert_allclose(kb["k_um_per_m"], k_true(r, m), atol=1e-4)
    np.testing.assert_allclose(kb["b_um"], b_true(r, m), atol=1e-4)
    np.testing.assert_allclose(kb["time_min"], m * 20.0)


def test_metrics_cover_every_fold_approach_algorithm(finished_run):
    work, _, _ = finished_run
    metrics = pd.read_csv(work / "results" / "lines" / "tables" / "metrics.csv")
    assert list(metrics.columns) == ["fold", "approach", "algorithm", "target", "rmse", "max_abs", "mae", "residual_min", "residual_max"]
    combos = set(zip(metrics["fold"], metrics["approach"], metrics["algorithm"]))
    assert combos == {(f, a, g) for f in ("R1", "R2", "R3") for a in ("decoupled", "pointwise") for g in ("mlr", "svr")}
    decoupled = metrics[metrics["approach"] == "decoupled"]
    assert set(decoupled["target"]) == {"k", "b", "error"}
    assert (metrics["rmse"] <= metrics["max_abs"] + 1e-12).all()


def test_noop_rerun_has_nothing_to_do(finished_run):
    work, _, config = finished_run
    proc = run_snakemake(work, "--configfile", str(config), "-n")
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
    assert not (work / "results" / "bad" / "clean" / "R2").exists() or not any((work / "results" / "bad" / "clean" / "R2").iterdir())
    assert not (work / "results" / "bad" / "tables" / "table5_slope_intercept.csv").exists()


def test_bad_sheet_stops_before_any_job(tmp_path):
    dataset = write_dataset(tmp_path / "sheet", name="sheet")
    (dataset / "runs.tsv").write_text((dataset / "runs.tsv").read_text().replace("R2\t2\t2000", "R2\t2\tx"))
    work = workdir(tmp_path)
    proc = run_snakemake(work, "--configfile", str(tiny_config(work, dataset)), check=False)
    assert proc.returncode != 0
    assert f"thermaxis error: {dataset / 'runs.tsv'}: line 3, column 'feed_mm_min': expected a finite number, got 'x'" in proc.stderr
    assert not (work / "results").exists()


def test_bad_config_value_is_rejected_by_schema(tmp_path):
    dataset = write_dataset(tmp_path / "cfg", name="cfg")
    work = workdir(tmp_path)
    config = tiny_config(work, dataset, decoupling={"degree": 7})
    proc = run_snakemake(work, "--configfile", str(config), "-n", check=False)
    assert proc.returncode != 0
    assert "7 is greater than the maximum of 3" in proc.stdout + proc.stderr


def digest_tree(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def test_two_cold_runs_are_byte_identical(finished_run, tmp_path):
    work_a, dataset, _ = finished_run
    work_b = workdir(tmp_path)
    run_snakemake(work_b, "--configfile", str(tiny_config(work_b, dataset)))
    a = digest_tree(work_a / "results" / "lines")
    b = digest_tree(work_b / "results" / "lines")
    assert a.keys() == b.keys()
    differing = [name for name in a if a[name] != b[name]]
    assert differing == []
    assert any(name.endswith(".png") for name in a) and any(name.endswith(".pdf") for name in a)


def test_plot_option_reruns_only_figure_rules(finished_run):
    work, _, config = finished_run
    changed = work / "changed_config.yaml"
    doc = yaml.safe_load(config.read_text())
    doc["figures"] = {**doc["figures"], "dpi": 150}
    changed.write_text(yaml.safe_dump(doc))
    proc = run_snakemake(work, "--configfile", str(changed), "-n")
    rules = set(re.findall(r"^(?:local)?rule (\w+):", proc.stdout + proc.stderr, flags=re.M))
    assert rules, proc.stdout
    # Reports embed the figures and the index links them, so they follow; nothing upstream does.
    # provenance.json records the hash of the effective config, so it is rewritten too.
    assert all(r.startswith("fig") or r.endswith("_report") or r in ("all", "index", "provenance") for r in rules), rules
    assert "fig_data" in rules


def test_editing_a_module_selection_imports_indirectly_reruns_selection(finished_run):
    """models.py is named in no rule; select.py reaches it through experiment.select_for_fold.

    Snakemake compares checksums of inputs newer than the outputs, so the edit must
    change the file's content; it is restored byte for byte afterwards.
    """
    import os

    import thermaxis.models

    work, _, config = finished_run
    module = Path(thermaxis.models.__file__)
    original, stat = module.read_bytes(), module.stat()
    try:
        module.write_bytes(original + b"\n# an edit of the method\n")
        dry = run_snakemake(work, "--configfile", str(config), "-n")
    finally:
        module.write_bytes(original)
        os.utime(module, (stat.st_atime, stat.st_mtime))
    assert re.search(r"rule select_sensitive_points:", dry.stdout)
    assert not re.search(r"rule clean_run:", dry.stdout)
