"""QC of the displacement channel: generated runs with known knocked readings and gauge resets."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS
from helpers.builders import write_dataset
from thermaxis.cleaning.displacement import apply_findings, displacement_findings
from thermaxis.cleaning.run import clean_and_assemble_run
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.errors import DataError

QC = DEFAULTS.cleaning.displacement
TARGETS = np.arange(0.0, 701.0, 50.0)
T0 = pd.Timestamp("2024-03-01T08:00:00")


def drift(minutes, targets, tau_min=60.0):
    """An unzeroed drift that heats fast and then settles: slope and intercept both saturate, µm."""
    heat = 1.0 - np.exp(-np.asarray(minutes, dtype=float)[:, None] / tau_min)
    return -40.0 * heat * targets[None, :] / 1000.0 - 12.0 * heat


def run_curves(errors, targets=TARGETS):
    return [pd.Series(row, index=pd.Index(targets, name="position_mm")) for row in errors]


def findings(errors, interval_min=15.0, targets=TARGETS, outliers="warn", steps="warn"):
    times = T0 + pd.to_timedelta(np.arange(len(errors)) * interval_min, unit="min")
    return displacement_findings(
        times,
        run_curves(errors, targets),
        threshold=QC.threshold,
        min_um=QC.min_deviation_um,
        outliers=outliers,
        steps=steps,
    )


def noisy(errors, seed=0, sigma=0.3):
    return errors + np.random.default_rng(seed).normal(0.0, sigma, errors.shape)


@pytest.mark.parametrize("tau_min", [10.0, 30.0, 120.0, 1e6])
@pytest.mark.parametrize("interval_min", [5.0, 15.0, 30.0])
def test_a_smooth_drift_is_never_flagged(tau_min, interval_min):
    minutes = np.arange(16) * interval_min
    errors = noisy(drift(minutes, TARGETS, tau_min), seed=int(tau_min) % 97)
    assert findings(errors, interval_min).empty


def test_a_long_pause_between_measurements_is_no_step():
    # 90 minutes instead of 10 while the axis heats fast: the level changes by ~10 µm
    # over the pause, far more than over its neighbouring intervals, at the same rate.
    minutes = np.array([0, 10, 20, 30, 120, 130, 140, 150, 160, 170], dtype=float)
    errors = noisy(drift(minutes, TARGETS, tau_min=200.0), seed=5)
    level = np.median(errors, axis=1)
    assert level[3] - level[4] > 4 * (level[2] - level[3])
    times = T0 + pd.to_timedelta(minutes, unit="min")
    found = displacement_findings(
        times, run_curves(errors), threshold=QC.threshold, min_um=QC.min_deviation_um,
        outliers="warn", steps="warn",
    )  # fmt: skip
    assert found.empty


def test_a_knocked_reading_is_an_outlier_at_its_measurement_and_target():
    minutes = np.arange(12) * 15.0
    clean = noisy(drift(minutes, TARGETS))
    errors = clean.copy()
    errors[4, 6] += 30.0  # measurement 5, target 300 mm
    found = findings(errors)
    assert found[["measurement", "position_mm", "finding"]].values.tolist() == [
        [5, 300.0, "outlier"]
    ]
    # The size is how far it lies beyond the nearer of its neighbouring readings.
    beyond = errors[4, 6] - max(errors[3, 6], errors[5, 6])
    assert found.loc[0, "size_um"] == pytest.approx(beyond)
    assert "knocked" in found.loc[0, "cause"] and found.loc[0, "action"] == "warn"


def test_a_gauge_reset_is_a_step_at_the_measurement_after_it():
    minutes = np.arange(12) * 15.0
    errors = noisy(drift(minutes, TARGETS), seed=1)
    errors[6:] -= 18.0  # re-zeroed before measurement 7
    errors[9, 2] += 25.0  # and a knocked reading later on
    found = findings(errors)
    assert found[["measurement", "finding"]].values.tolist() == [[7, "step"], [10, "outlier"]]
    step = found.iloc[0]
    assert np.isnan(step["position_mm"]) and "re-zeroed" in step["cause"]
    # The jump of the run's level (the median over targets) between measurements 6 and 7.
    jump = np.median(errors[6]) - np.median(errors[5])
    assert step["size_um"] == pytest.approx(jump)
    assert -20.0 < jump < -16.0


def test_a_single_position_record_gets_the_same_qc():
    minutes = np.arange(40) * 10.0
    errors = noisy(drift(minutes, np.array([0.0]), tau_min=90.0), seed=4, sigma=0.5)
    errors[12, 0] -= 40.0
    errors[25:, 0] += 22.0
    found = findings(errors, 10.0, targets=np.array([0.0]))
    assert found[["measurement", "finding"]].values.tolist() == [[13, "outlier"], [26, "step"]]


def test_a_temporary_offset_is_two_steps_not_outliers():
    minutes = np.arange(14) * 15.0
    errors = noisy(drift(minutes, TARGETS), seed=2)
    errors[5:8] += 20.0  # three measurements off, then back
    found = findings(errors)
    assert found[["measurement", "finding"]].values.tolist() == [[6, "step"], [9, "step"]]


def test_drop_removes_only_the_outlier():
    minutes = np.arange(10) * 15.0
    errors = noisy(drift(minutes, TARGETS), seed=3)
    errors[3, 1] -= 35.0
    curves = run_curves(errors)
    found = findings(errors, outliers="drop")
    dropped = np.vstack([c.to_numpy() for c in apply_findings(curves, found)])
    assert np.isnan(dropped[3, 1]) and np.isnan(dropped).sum() == 1
    np.testing.assert_array_equal(np.nan_to_num(dropped), np.where(np.isnan(dropped), 0, errors))


# --------------------------------------------------------------------------- in the run's cleaning


def knocked_and_reset(r, m, x):
    """Exact lines, with a knocked reading in run 1's measurement 4 and a reset of run 2 at 6."""
    e = (-10.0 + 0.5 * m + r) * (x - x[0]) / 1000.0 + (-0.7 * m - 0.1 * r)
    if r == 0 and m == 3:
        e = e.copy()
        e[2] += 30.0
    if r == 1 and m >= 5:
        e = e - 20.0
    return e


@pytest.fixture
def faulty(tmp_path):
    root = write_dataset(tmp_path / "faulty", curve=knocked_and_reset, n_measurements=8)
    return load_dataset(root)


def _clean(dataset, run, **displacement):
    cleaning = replace(
        DEFAULTS.cleaning, displacement=replace(DEFAULTS.cleaning.displacement, **displacement)
    )
    return clean_and_assemble_run(dataset, read_run(dataset, run), cleaning)


def test_findings_are_in_the_qc_table_and_on_the_terminal(faulty):
    tables = _clean(faulty, "R1")
    rows = tables.qc[tables.qc["sensor"] == "error_um"]
    assert rows[["run", "measurement", "position_mm", "finding", "action"]].values.tolist() == [
        ["R1", 4, 100.0, "outlier", "warn"]
    ]
    assert rows["size_um"].iloc[0] == pytest.approx(30.0 - 0.5 * 100.0 / 1000.0 - 0.7, abs=0.2)
    note = next(n for n in tables.notes if "outlier" in n)
    assert "M04.csv" in note and "100 mm" in note and "kept" in note
    # The temperature rows have no finding; the sensors' rows are all still there.
    assert tables.qc["finding"].isna().sum() == 3


def test_dropping_the_outlier_leaves_the_target_without_a_reading(faulty):
    tables = _clean(faulty, "R1", outliers="drop")
    errors = tables.errors.set_index(["measurement", "position_mm"])["error_um"]
    assert np.isnan(errors.loc[(4, 100.0)]) and errors.notna().sum() == 8 * 4 - 1


def test_a_refused_step_names_the_file_and_the_measurement(faulty):
    with pytest.raises(DataError, match=r"M06\.csv: step: every target jumps by -20\.\d µm"):
        _clean(faulty, "R2", steps="refuse")
    # warn keeps the run as it is, and says so.
    tables = _clean(faulty, "R2")
    assert tables.qc.loc[tables.qc["finding"] == "step", "measurement"].tolist() == [6]
