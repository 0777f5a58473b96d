"""The workflow on a measured-like dataset the twin does not resemble.

Three runs of unequal length with long names, one target position, no ambient sensor,
an operating signal, one errors.csv per run: the workflow must run end to end to its
tables, figures and an offset-only compensation with time-aware inputs, draw against time,
and make no paper audit.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers.builders import write_dataset
from helpers.workflow import run_snakemake, workflow_workdir

RUNS = ("cold_start_morning_1250rpm", "warm_afternoon_2500rpm", "night_cooldown_variable")


def _drift(r, m):
    """The error of run index r at measurement index m: a first-order rise, no slope."""
    return -1.5 * (1 + r) * (1 - np.exp(-m / 8.0))


def _measured_like(root):
    def curve(r, m, x):
        return np.full(x.shape, _drift(r, m))

    write_dataset(
        root,
        runs=RUNS,
        n_measurements=(9, 14, 6),
        positions=(0.0,),
        curve=curve,
        two_passes=False,
        kind="measured",
    )
    meta = yaml.safe_load((root / "dataset.yaml").read_text())
    meta["signals"] = [{"id": "spindle_rpm", "unit": "rpm", "source": "box"}]
    (root / "dataset.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    (root / "runs.tsv").write_text(
        "run\tcondition\tdescription\n"
        + "".join(f"{r}\t{r.split('_')[-1]}\trun {r}\n" for r in RUNS)
    )
    for i, run in enumerate(RUNS):
        folder = root / run
        frames = []
        for f in sorted((folder / "errors").glob("*.csv")):
            frames.append(pd.read_csv(f, dtype=str).assign(measurement=f.stem))
            f.unlink()
        (folder / "errors").rmdir()
        pd.concat(frames).to_csv(folder / "errors.csv", index=False)
        log = pd.read_csv(folder / "temperatures" / "box.csv", usecols=["time"])
        (folder / "signals").mkdir()
        log.assign(
            spindle_rpm=np.where(np.arange(len(log)) < len(log) // 2, 1250.0 * (i + 1), 0.0)
        ).to_csv(folder / "signals" / "box.csv", index=False)
    return root


def test_single_position_unequal_runs_end_to_end(tmp_path):
    work = workflow_workdir(tmp_path)
    _measured_like(work / "data" / "measured")
    out = work / "results" / "tiny"
    targets = [
        f"results/tiny/{p}"
        for p in (
            "tables/metrics.csv",
            "tables/sensitive_points.csv",
            "figures/fig5_unzeroed.png",
            "figures/fig9_other_runs.png",
            "figures/fig10_temperature_rise.png",
            "figures/fold_comparison.png",
            f"figures/error_prediction_{RUNS[1]}_pointwise_mlr.png",
            "compensation/siemens_840d.csv",
            "compensation/twincat.csv",
            "compensation/ThermalCompensation.st",
        )
    ]
    # A time-aware candidate with the operating signal, deployed by name: its held-out
    # replay reads the temperature and signal logs.
    lagged = work / "lagged.yaml"
    # The figures as PNG at 60 dpi: drawing them is most of a figure job.
    lagged.write_text(yaml.safe_dump({"recommend": {"lags_min": [30]},
                                      "compensation": {"model": "pointwise-pls-all+lags"},
                                      "figures": {"algorithms": ["mlr"], "formats": ["png"],
                                                  "dpi": 60}}))  # fmt: skip
    proc = run_snakemake(
        work,
        "--configfile",
        "config/config.yaml",
        str(lagged),
        "--config",
        "dataset=data/measured",
        "models={algorithms: [mlr], signals: [spindle_rpm]}",
        "--",
        *targets,
    )
    # What a single position leaves out is said once, as not applying: nothing the run
    # prints calls a part of the method skipped.
    printed = f"{proc.stdout}\n{proc.stderr}".splitlines()
    said = [line for line in printed if line.startswith("thermaxis")]
    assert any("decoupled (slope/intercept) branch does not apply" in line for line in said), said
    assert not [line for line in said if "skipped" in line], said
    metrics = pd.read_csv(out / "tables" / "metrics.csv")
    assert set(metrics["approach"]) == {"pointwise"}
    assert sorted(metrics["fold"]) == sorted(RUNS)
    predictions = pd.read_csv(out / "models" / RUNS[1] / "error_predictions.csv")
    assert len(predictions) == 14  # every measurement of the 14-measurement run, none padded
    coefficients = pd.read_csv(out / "models" / RUNS[1] / "coefficients.csv")
    assert "spindle_rpm" in set(coefficients["term"])
    for target in targets:
        assert (work / target).stat().st_size > 0
    for r, run in enumerate(RUNS):
        # The measured errors are the drift the dataset was written from (6 decimals), and
        # each fold's metrics the RMSE and largest |residual| of its predictions.
        fold = pd.read_csv(out / "models" / run / "error_predictions.csv")
        fold = fold[fold["algorithm"] == "mlr"]
        truth = _drift(r, fold["measurement"].to_numpy() - 1)
        np.testing.assert_allclose(fold["measured"], truth, atol=1e-6)
        residual = truth - fold["predicted"].to_numpy()
        row = metrics[(metrics["fold"] == run) & (metrics["algorithm"] == "mlr")].iloc[0]
        assert row["rmse"] == pytest.approx(np.sqrt(np.mean(residual**2)), abs=1e-5)
        assert row["max_abs"] == pytest.approx(np.abs(residual).max(), abs=1e-5)
        replay = pd.read_csv(out / "compensation" / "folds" / run / "summary.csv")
        np.testing.assert_allclose(replay["largest_abs_uncompensated_um"],
                                   np.abs(_drift(r, replay["measurement"].to_numpy() - 1)),
                                   atol=1e-9)  # fmt: skip
    # One position: the compensation is an offset only, point by point.
    comp = out / "compensation"
    model = json.loads((comp / "model.json").read_text())
    assert model["approach"] == "pointwise"
    assert model["deployment"]["candidate"] == "pointwise-pls-all+lags"
    inputs = [(i["sensor"], i["temperature"]) for i in model["inputs"]]
    # Every sensor and its lag (selection "all"), then the signal and its lag, as logged.
    temperatures = ["S1", "S2", "S3", "S1@lag30min", "S2@lag30min", "S3@lag30min"]
    signals = ["spindle_rpm", "spindle_rpm@lag30min"]
    assert inputs == [(s, "relative") for s in temperatures] + [(s, "signal") for s in signals]
    assert model["signals"] == ["spindle_rpm"]
    assert (
        "SENSOR_SIGNAL : ARRAY[1..4] OF BOOL := [FALSE, FALSE, FALSE, TRUE];"
        in (comp / "ThermalCompensation.st").read_text()
    )
    for run, n in zip(RUNS, (9, 14, 6), strict=True):
        summary = pd.read_csv(comp / "folds" / run / "summary.csv")
        assert len(summary) == n and summary["largest_abs_compensated_um"].notna().all()
    siemens = pd.read_csv(comp / "siemens_840d.csv", comment="#")
    assert set(siemens["parameter"]) == {"SD43900"}
    twincat = pd.read_csv(comp / "twincat.csv", comment="#")
    assert (twincat.loc[twincat["parameter"] == "P-AXIS-00274", "value"] == 0).all()
    assert not (out / "tables" / "paper_comparison.csv").exists()
    dry = run_snakemake(work, "-n", "--config", "dataset=data/measured")
    assert "paper_comparison" not in dry.stdout and "fig3_ambient" not in dry.stdout
    assert "fig8_rezeroed" not in dry.stdout and "fig7_error_surface" not in dry.stdout
