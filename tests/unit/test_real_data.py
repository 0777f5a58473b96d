"""Measured data: cleaning that keeps real trends, gap messages, the table importer, the
embedded record."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers import DEFAULTS
from thermaxis.cleaning.run import clean_and_assemble_run, model_inputs
from thermaxis.cleaning.signals import signals_on_grid
from thermaxis.cleaning.temperatures import clean_temperatures
from thermaxis.cleaning.windows import gap_overlaps
from thermaxis.config import Settings, load_config
from thermaxis.dataset.import_parsing import measurements_of
from thermaxis.dataset.importer import import_dataset
from thermaxis.dataset.plausibility import signal_coverage
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.errors import DataError
from thermaxis.method.folds import evaluate_configuration, select_for_fold

REPO = Path(__file__).resolve().parents[2]
FL_THERMAL = REPO / "data" / "raw" / "fl_thermal"


def _log(minutes, values):
    t0 = pd.Timestamp("2024-01-01T00:00:00")
    return pd.DataFrame(
        {"time": t0 + pd.to_timedelta(np.asarray(minutes, float), unit="min"), "T1": values}
    )


def test_a_record_that_ends_early_is_named_as_such_with_its_file():
    # The sensor stops at minute 50; a measurement runs from 58 to 59 min: 9 min after the
    # last sample, more than max_gap_s / 2 = 5 min, though less than max_gap_s = 10 min.
    minutes = np.arange(0.0, 50.5, 0.5)
    cleaned = clean_temperatures(
        {"box": _log(minutes, 20.0 + 0.01 * minutes)},
        {},
        replace(DEFAULTS.cleaning.temperatures, interval_s=30.0, max_gap_s=600.0),
        start="2024-01-01T00:00:00",
        end="2024-01-01T01:00:00",
    )
    assert cleaned.gaps["kind"].tolist() == ["record end"]
    windows = pd.DataFrame(
        {
            "measurement": [1],
            "start": [pd.Timestamp("2024-01-01T00:58:00")],
            "end": [pd.Timestamp("2024-01-01T00:59:00")],
        }
    )
    (overlap,) = gap_overlaps(
        cleaned.gaps,
        windows,
        max_gap_s=600.0,
        files={"T1": "data/raw/x/R1/temperatures/box.csv"},
    )
    message = overlap.text
    assert message.startswith(
        "data/raw/x/R1/temperatures/box.csv: sensor T1 has no reading after 2024-01-01T00:50:00"
    )
    assert (
        "record ends too early" in message
        and "max_gap_s / 2" in message
        and "measurement 1" in message
    )


def _wide_record(path: Path) -> Path:
    """A 3-block record every 60 s: rest 5 min, run 10 min, rest 5 min, ..., with a known error."""
    seconds = np.arange(0, 3 * 20 * 60, 60.0)
    phase = (seconds // 60) % 20
    rpm = np.where((phase >= 5) & (phase < 15), 1000.0 * (1 + seconds // 1200), 0.0)
    table = pd.DataFrame(
        {
            "t (s)": seconds,
            "speed": rpm,
            "temp A": 20.0 + seconds / 600.0,
            "temp B": 21.0 + np.sin(seconds / 500.0),
            "disp": 3.0 + seconds / 100.0,  # zeroed once at 3.0 um, 0.01 um/s
        }
    )
    table.to_csv(path, index=False)
    return path


def _mapping(tmp_path: Path, **changes) -> Path:
    mapping = {
        "name": "wide",
        "source": "wide.csv",
        "description": "A generated wide record.",
        "provenance": {"kind": "measured", "citation": "tests", "licence": "CC0"},
        "axis": {"name": "Z"},
        "time": {"column": "t (s)", "start": "2030-01-01T00:00:00"},
        "sensors": [{"column": "temp A", "id": "TA"}, {"column": "temp B", "id": "TB"}],
        "signals": [{"column": "speed", "id": "spindle_rpm", "unit": "rpm"}],
        "errors": {
            "columns": [{"column": "disp", "position_mm": 0}],
            "every_s": 300,
            "rereference": "run_start",
        },
        "split": {"by": "signal", "signal": "spindle_rpm", "rest": 0},
        "runs": [
            {"name": f"B{i}", "condition": f"{1000 * i} rpm", "description": "block"}
            for i in (1, 2, 3)
        ],
        **changes,
    }
    _wide_record(tmp_path / "wide.csv")
    path = tmp_path / "wide.yaml"
    path.write_text(yaml.safe_dump(mapping, allow_unicode=True))
    return path


def test_importer_splits_by_signal_rereferences_and_states_its_assumptions(tmp_path):
    out = import_dataset(_mapping(tmp_path), tmp_path / "raw" / "wide").out
    dataset = load_dataset(out)
    assert dataset.run_ids == ("B1", "B2", "B3")
    # Run 1 keeps the record's start (0 s); runs 2 and 3 start at their first active sample:
    # 1500 s and 2700 s.
    errors = pd.read_csv(out / "B2" / "errors.csv")
    assert errors["time"].iloc[0] == "2030-01-01T00:25:00"
    # Re-referenced to the run's first sample, 0.01 um/s: measurements every 300 s are
    # 0, 3, 6, ... um.
    np.testing.assert_allclose(errors["error_um"].to_numpy(), 3.0 * np.arange(len(errors)))
    assert len(errors) == 4  # 1500 .. 2640 s: samples at 1500, 1800, 2100, 2400
    description = dataset.meta["description"]
    assert "invented by the import" in description and "re-referenced" in description
    assert dataset.signals == ("spindle_rpm",)
    raw = read_run(dataset, "B2")
    assert raw.signals["logger"]["spindle_rpm"].max() == 2000.0


def test_importer_refuses_a_wrong_run_count_and_leaves_nothing(tmp_path):
    mapping = _mapping(tmp_path, runs=[{"name": "B1", "condition": "a", "description": "x"}])
    with pytest.raises(DataError, match="found 3 run\\(s\\) but the mapping lists 1"):
        import_dataset(mapping, tmp_path / "raw" / "wide")
    assert not (tmp_path / "raw").exists() or not any((tmp_path / "raw").iterdir())


def test_a_speed_that_is_never_exactly_zero_at_rest_splits_with_a_tolerance(tmp_path):
    path = _mapping(tmp_path)
    table = pd.read_csv(tmp_path / "wide.csv")
    # A logged standstill of 0.4 to 1.6 rpm: no sample is exactly 0, so without a tolerance
    # the record is one active block.
    at_rest = table["speed"] == 0
    table.loc[at_rest, "speed"] = 0.4 + 1.2 * (np.arange(at_rest.sum()) % 2)
    table.to_csv(tmp_path / "wide.csv", index=False)
    with pytest.raises(
        DataError, match="found 1 run\\(s\\) but the mapping lists 3; .*set split.tolerance"
    ):
        import_dataset(path, tmp_path / "raw" / "wide")
    mapping = yaml.safe_load(path.read_text())
    mapping["split"]["tolerance"] = 2.0
    path.write_text(yaml.safe_dump(mapping))
    out = import_dataset(path, tmp_path / "raw" / "wide").out
    # The same cut as exactly 0 at rest: run 2 starts at 1500 s.
    assert pd.read_csv(out / "B2" / "errors.csv")["time"].iloc[0] == "2030-01-01T00:25:00"


def test_a_signal_noisy_at_rest_is_named_when_it_cuts_too_many_runs(tmp_path):
    path = _mapping(tmp_path)
    table = pd.read_csv(tmp_path / "wide.csv")
    table.loc[[2, 40], "speed"] = 3.0  # two blips at standstill: two more rest-to-active steps
    table.to_csv(tmp_path / "wide.csv", index=False)
    with pytest.raises(
        DataError,
        match="found 5 run\\(s\\) but the mapping lists 3; expected one entry in runs per "
        "rest-to-active step; a signal that is not exactly 0 at rest\\? set split.tolerance",
    ):
        import_dataset(path, tmp_path / "raw" / "wide")


def test_importer_names_a_missing_column(tmp_path):
    mapping = _mapping(tmp_path, sensors=[{"column": "temp C", "id": "TC"}])
    with pytest.raises(DataError, match=r"wide.csv: missing column 'temp C'"):
        import_dataset(mapping, tmp_path / "raw" / "wide")


def test_measurements_are_the_first_samples_at_each_interval():
    rows = pd.DataFrame({"_t": [100.0, 115.0, 130.0, 400.0, 405.0, 700.0]})
    assert measurements_of(rows, 300.0)["_t"].tolist() == [100.0, 400.0, 700.0]


@pytest.mark.skipif(not FL_THERMAL.is_dir(), reason="data/raw/fl_thermal is not imported")
def test_fl_thermal_pointwise_mlr_equals_plain_least_squares():
    """The embedded measured record: held-out run R6, all 16 sensors plus a constant, by numpy."""
    dataset = load_dataset(FL_THERMAL)
    config = load_config()
    tables = [
        clean_and_assemble_run(
            dataset, read_run(dataset, run), Settings.from_config(config).cleaning
        )
        for run in dataset.run_ids
    ]
    X, Y = model_inputs(
        pd.concat([t.errors for t in tables], ignore_index=True),
        pd.concat([t.temperatures for t in tables], ignore_index=True),
    )
    sensors = tuple(c for c in X.columns if c.startswith("T"))
    assert len(sensors) == 16 and Y.shape[1] == 1
    fold = "R6_variable"
    selection = select_for_fold(
        X, Y, fold, replace(DEFAULTS.selection, method="all"), 1, decoupled=False
    )
    result = evaluate_configuration(X, Y, fold, "pointwise", "mlr", selection, DEFAULTS.models, 1)

    first = (
        X.sort_values("measurement").groupby("run")[list(sensors)].transform("first").loc[X.index]
    )
    T = X[list(sensors)].to_numpy(float) - first.to_numpy(float)
    train = (X["run"] != fold).to_numpy()
    A = np.column_stack([np.ones(train.sum()), T[train]])
    coef, *_ = np.linalg.lstsq(A, Y.to_numpy(float)[train, 0], rcond=None)
    expected = np.column_stack([np.ones((~train).sum()), T[~train]]) @ coef
    np.testing.assert_allclose(
        result.error_predictions["predicted"].to_numpy(), expected, atol=1e-6
    )


def test_signals_are_held_as_steps_on_the_grid():
    t0 = pd.Timestamp("2024-01-01T00:00:00")
    log = pd.DataFrame(
        {"time": t0 + pd.to_timedelta([0, 95, 200], unit="s"), "rpm": [0.0, 3000.0, 0.0]}
    )
    grid = t0 + pd.to_timedelta(np.arange(-20, 240, 20), unit="s")
    held = signals_on_grid({"plc": log}, {}, grid)
    # Before the first sample: its value; from 95 s to 200 s: 3000; no ramp in between.
    assert held["rpm"].tolist() == [0, 0, 0, 0, 0, 0, 3000, 3000, 3000, 3000, 3000, 0, 0]


def _signal_run(rpm):
    """A run whose only signal log (plc.csv, one reading a minute) reads ``rpm``."""
    t0 = pd.Timestamp("2024-01-01T00:00:00")
    times = t0 + pd.to_timedelta(60 * np.arange(len(rpm)), unit="s")
    log = pd.DataFrame({"time": times, "rpm": np.asarray(rpm, dtype=float)})
    windows = pd.DataFrame({"start": [times[0]], "end": [times[-1]]})
    dataset = SimpleNamespace(root=Path("/data/d"), clock_offsets_s=lambda: {})
    return dataset, SimpleNamespace(run="R1", signals={"plc": log}), windows, log


def test_a_signal_reading_no_signal_reaches_is_missing_and_named():
    dataset, raw, windows, log = _signal_run([0.0, 3000.0, 1e300, 3000.0, 0.0])
    (note,) = signal_coverage(dataset, raw, windows, hold_s=300.0)
    assert note == (
        "run R1: /data/d/R1/signals/plc.csv: signal rpm: 1 reading(s) beyond ±1e+09 (the first, "
        "1e+300, at 2024-01-01 00:02:00) treated as missing, the reading before each held: a "
        "logger's overflow or fault value, not an operating state"
    )
    # On a grid every 30 s the 1e300 at 120 s is skipped: 3000 from 60 s holds until 240 s.
    grid = log["time"].iloc[0] + pd.to_timedelta(np.arange(0, 271, 30), unit="s")
    held = signals_on_grid(raw.signals, {}, grid)
    assert held["rpm"].tolist() == [0, 0, 3000, 3000, 3000, 3000, 3000, 3000, 0, 0]


def test_a_signal_with_no_usable_reading_is_refused_in_one_line():
    dataset, raw, windows, _ = _signal_run([-2e9, np.nan, 5e9])
    with pytest.raises(DataError) as refused:
        signal_coverage(dataset, raw, windows, hold_s=300.0)
    assert str(refused.value) == (
        "/data/d/R1/signals/plc.csv: column 'rpm': every reading is beyond ±1e+09 (the first, "
        "-2e+09, at 2024-01-01 00:00:00); expected the signal in the unit dataset.yaml declares "
        "for it"
    )


def test_importer_takes_one_file_per_run_without_a_time_column(tmp_path):
    # Two runs in their own tables, no time column: row i is i x 30 s after the start.
    for name, slope in (("a.csv", 0.01), ("b.csv", 0.02)):
        rows = np.arange(20)
        pd.DataFrame(
            {"temp A": 20 + 0.1 * rows, "temp B": 21 + 0.05 * rows, "disp": slope * 30 * rows}
        ).to_csv(tmp_path / name, index=False)
    mapping = _mapping(
        tmp_path,
        source=".",
        time={"interval_s": 30, "start": "2030-01-01T00:00:00"},
        signals=[],
        split={"by": "files"},
        errors={"columns": [{"column": "disp", "position_mm": 0}], "every_s": 150},
        runs=[
            {"name": "A", "condition": "a", "description": "x", "file": "a.csv"},
            {"name": "B", "condition": "b", "description": "y", "file": "b.csv"},
        ],  # fmt: skip
    )
    dataset = load_dataset(import_dataset(mapping, tmp_path / "raw" / "files").out)
    errors = pd.read_csv(dataset.root / "B" / "errors.csv")
    # Samples every 30 s, a measurement every 150 s: rows 0, 5, 10, 15 -> 0, 3, 6, 9 um at
    # 0.02 um/s.
    np.testing.assert_allclose(errors["error_um"], [0.0, 3.0, 6.0, 9.0])
    assert errors["time"].tolist()[1] == "2030-01-01T00:02:30"
    assert "an invented clock" in dataset.meta["description"]


def test_importer_cuts_explicit_time_ranges(tmp_path):
    mapping = _mapping(
        tmp_path,
        split={"by": "ranges"},
        runs=[
            {"name": "early", "condition": "a", "description": "x", "start_s": 0, "end_s": 1200},
            {"name": "late", "condition": "b", "description": "y", "start_s": 2400, "end_s": 3600},
        ],  # fmt: skip
    )
    dataset = load_dataset(import_dataset(mapping, tmp_path / "raw" / "ranges").out)
    late = pd.read_csv(dataset.root / "late" / "errors.csv")
    assert (
        late["time"].iloc[0] == "2030-01-01T00:40:00" and len(late) == 4
    )  # 2400 .. 3540 s every 300 s
