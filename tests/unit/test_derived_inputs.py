"""Time-aware inputs of a real run of the twin, against closed forms of the lag filter."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from thermaxis.cleaning.run import clean_and_assemble_run, derived_inputs, model_inputs
from thermaxis.config import Settings
from thermaxis.dataset.reader import load_dataset, read_run

REPO = Path(__file__).resolve().parents[2]

DATASET = load_dataset(REPO / "data" / "raw" / "twin")
TABLES = clean_and_assemble_run(DATASET, read_run(DATASET, "E2"), Settings.from_config({}).cleaning)


def at_mid(series: pd.DataFrame, column: str) -> np.ndarray:
    """The cleaned series interpolated at each measurement window's middle (plain numpy)."""
    w = TABLES.windows
    mid = (
        (w["start"] + (w["end"] - w["start"]) / 2)
        .to_numpy()
        .astype("datetime64[ns]")
        .astype(np.int64)
    )
    t = series["time"].to_numpy().astype("datetime64[ns]").astype(np.int64)
    return np.interp(mid, t, series[column].to_numpy(dtype=float))


def values(frame, name):
    return frame.loc[frame["input"] == name].sort_values("measurement")["value"].to_numpy()


def test_a_short_lag_is_the_temperature_and_a_long_one_the_start():
    frame = derived_inputs(TABLES, [1e-4, 1e7], [])
    series = TABLES.series
    # tau -> 0: the filter follows the input; tau -> infinity: it holds its start value.
    # (within a lag of tau x the change over one 10 s grid step: 6e-4 x 0.03 C)
    np.testing.assert_allclose(values(frame, "T1@lag0.006s"), at_mid(series, "T1"), atol=1e-4)
    np.testing.assert_allclose(values(frame, "T1@lag10000000min"), series["T1"].iloc[0], atol=1e-3)
    assert set(frame["run"]) == {"E2"} and len(frame) == 2 * 12 * len(TABLES.windows)


def test_the_rate_of_a_window_is_the_temperature_change_over_it():
    frame = derived_inputs(TABLES, [], [20])
    series = TABLES.series
    w = TABLES.windows
    mid = w["start"] + (w["end"] - w["start"]) / 2
    t = series["time"].to_numpy().astype("datetime64[ns]").astype(np.int64)
    u = series["T5"].to_numpy(dtype=float)
    now = np.interp(mid.to_numpy().astype("datetime64[ns]").astype(np.int64), t, u)
    before = np.interp(
        (mid - pd.Timedelta(minutes=20)).to_numpy().astype("datetime64[ns]").astype(np.int64), t, u
    )
    np.testing.assert_allclose(
        values(frame, "T5@rate20min"), (now - before) / 20.0, rtol=1e-9, atol=1e-12
    )


def test_no_time_constants_give_no_rows_and_model_inputs_join_the_columns():
    assert derived_inputs(TABLES, [], []).empty
    frame = derived_inputs(TABLES, [30], [])
    X, _ = model_inputs(TABLES.errors, TABLES.temperatures, inputs=frame)
    assert [c for c in X.columns if "@" in c] == [f"T{i}@lag30min" for i in range(1, 13)]
    assert X["T3@lag30min"].to_numpy() == pytest.approx(values(frame, "T3@lag30min"))
