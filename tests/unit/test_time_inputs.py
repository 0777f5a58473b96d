"""Tests of thermaxis.method.inputs against closed forms that do not use its recurrence."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from thermaxis.method.inputs import (
    LagState,
    RateState,
    input_name,
    inputs_at_measurements,
    lag_filter,
    lag_name,
    parse_input_name,
    rate_name,
    rate_of_change,
)

T0 = pd.Timestamp("2022-05-10T09:00:00")


def irregular(n: int, seed: int, mean_step_s: float = 40.0) -> np.ndarray:
    """Strictly increasing times from 0 with steps from 0.01 s to several minutes."""
    rng = np.random.default_rng(seed)
    steps = rng.exponential(mean_step_s, n - 1) + 0.01
    return np.concatenate([[0.0], np.cumsum(steps)])


def grid(kind: str, n: int, seed: int, mean_step_s: float = 40.0) -> np.ndarray:
    """Sample times: irregular, or evenly spaced (a logger's usual record, which
    lag_filter runs as a constant-pole IIR filter)."""
    return irregular(n, seed, mean_step_s) if kind == "irregular" else np.arange(n) * mean_step_s


GRIDS = ["irregular", "even"]


# ----------------------------------------------------------------------------- lag


@pytest.mark.parametrize("kind", GRIDS)
@pytest.mark.parametrize("tau", [7.0, 600.0, 1800.0, 5e4])
def test_step_response_is_one_minus_exp(tau, kind):
    # A unit step at t = 0 onto a filter at rest: u is 1 throughout, the filter starts at 0.
    t = grid(kind, 400, seed=1)
    y = lag_filter(t, np.ones_like(t), tau, initial=0.0)
    np.testing.assert_allclose(y, 1.0 - np.exp(-t / tau), rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", GRIDS)
@pytest.mark.parametrize("tau", [30.0, 1800.0])
def test_ramp_response_is_exact_on_any_grid(tau, kind):
    # u = r t from rest: y = r (t - tau (1 - exp(-t / tau))), the solution of
    # tau y' = r t - y, y(0) = 0.
    t = grid(kind, 500, seed=2)
    r = 0.013  # degC per second
    y = lag_filter(t, r * t, tau)
    truth = r * (t - tau * -np.expm1(-t / tau))
    np.testing.assert_allclose(y, truth, rtol=1e-12, atol=1e-12)


def test_result_does_not_depend_on_how_finely_a_piecewise_linear_signal_is_sampled():
    knots = irregular(30, seed=3, mean_step_s=300.0)
    values = np.random.default_rng(3).normal(20.0, 2.0, knots.size)
    fine = np.union1d(knots, np.random.default_rng(4).uniform(0, knots[-1], 3000))
    coarse_y = lag_filter(knots, values, 900.0)
    fine_y = lag_filter(fine, np.interp(fine, knots, values), 900.0)
    np.testing.assert_allclose(fine_y[np.searchsorted(fine, knots)], coarse_y, rtol=0, atol=1e-11)


def test_starts_at_the_first_value_and_a_constant_stays_constant():
    t = irregular(50, seed=5)
    np.testing.assert_allclose(
        lag_filter(t, np.full(t.size, 21.5), 600.0), 21.5, rtol=0, atol=1e-12
    )


@pytest.mark.parametrize("kind", GRIDS)
def test_filters_columns_independently(kind):
    t = grid(kind, 200, seed=6)
    u = np.random.default_rng(6).normal(size=(t.size, 3)).cumsum(axis=0)
    initial = np.array([1.0, -2.0, 0.5])
    y = lag_filter(t, u, 300.0, initial=initial)
    for j in range(3):
        np.testing.assert_array_equal(y[:, j], lag_filter(t, u[:, j], 300.0, initial=initial[j]))


@pytest.mark.parametrize("kind", GRIDS)
@pytest.mark.parametrize("initial", [None, 3.0])
def test_online_lag_equals_offline(initial, kind):
    # A clock that does not start at 0; the online filter steps sample by sample.
    t = 1.7e4 + grid(kind, 2000, seed=7, mean_step_s=5.0)
    u = 20.0 + np.random.default_rng(7).normal(0, 0.3, t.size).cumsum()
    offline = lag_filter(t, u, 1200.0, initial=initial)
    state = LagState(1200.0, initial=initial)
    online = np.array([state.update(ti, ui) for ti, ui in zip(t, u, strict=True)])
    np.testing.assert_allclose(online, offline, rtol=0, atol=1e-9)
    assert state.y == pytest.approx(offline[-1], abs=1e-9)


# ----------------------------------------------------------------------------- rate


@pytest.mark.parametrize("window", [600.0, 437.5])
def test_rate_of_a_ramp_is_its_slope_per_minute_after_one_window(window):
    t = irregular(300, seed=8)
    slope = 0.004  # degC per second
    r = rate_of_change(t, 18.0 + slope * t, window)
    full = t >= window
    np.testing.assert_allclose(r[full], slope * 60.0, rtol=1e-9)
    # Before one window has passed, the start's value stands in for u(t - w): the rate
    # grows linearly from 0.
    np.testing.assert_allclose(r[~full], slope * 60.0 * t[~full] / window, rtol=1e-9, atol=1e-15)


def test_online_rate_equals_offline():
    t = 500.0 + irregular(1500, seed=9, mean_step_s=7.0)
    u = np.random.default_rng(9).normal(0, 0.2, t.size).cumsum()
    for window in (60.0, 600.0, 1e6):
        state = RateState(window)
        online = np.array([state.update(ti, ui) for ti, ui in zip(t, u, strict=True)])
        np.testing.assert_allclose(online, rate_of_change(t, u, window), rtol=0, atol=1e-9)


def test_online_rate_keeps_only_one_window_of_history():
    state = RateState(100.0)
    for k in range(1000):
        state.update(10.0 * k, float(k))
    assert len(state.history) == 11  # 100 s at 10 s steps, plus the sample at t - w
    assert state.update(10_000.0, 1000.0) == pytest.approx(6.0)  # 1 per 10 s = 6 per minute


# ----------------------------------------------------------------------------- refusals


def test_refusals_of_the_filters():
    t = np.array([0.0, 10.0, 20.0])
    with pytest.raises(ValueError, match=r"sample 1 \(t = 10 s\) is NaN"):
        lag_filter(t, [1.0, np.nan, 2.0], 60.0)
    with pytest.raises(ValueError, match=r"sample 2 \(t = 20 s\) is NaN"):
        rate_of_change(t, np.array([[1.0, 1.0], [1.0, 1.0], [1.0, np.nan]]), 60.0)
    with pytest.raises(ValueError, match="increase strictly: sample 2"):
        lag_filter([0.0, 10.0, 10.0], [1.0, 2.0, 3.0], 60.0)
    with pytest.raises(ValueError, match="one row per time"):
        rate_of_change(t, [1.0, 2.0], 60.0)
    for bad in (0.0, -5.0, np.inf, np.nan, "x"):
        with pytest.raises(ValueError, match="seconds"):
            lag_filter(t, [1.0, 2.0, 3.0], bad)
        with pytest.raises(ValueError, match="seconds"):
            RateState(bad)
    state = LagState(60.0)
    state.update(5.0, 1.0)
    with pytest.raises(ValueError, match="increase strictly"):
        state.update(5.0, 1.0)
    with pytest.raises(ValueError, match="NaN"):
        state.update(6.0, np.nan)
    rate = RateState(60.0)
    rate.update(0.0, 1.0)
    with pytest.raises(ValueError, match="increase strictly"):
        rate.update(-1.0, 1.0)


# ----------------------------------------------------------------------------- names


def test_names():
    assert lag_name("T5", 1800) == "T5@lag30min"
    assert rate_name("T5", 600) == "T5@rate10min"
    assert lag_name("T5", 45) == "T5@lag45s"
    assert lag_name("T5", 90.0) == "T5@lag90s"
    assert lag_name("T5", 3600) == "T5@lag60min"
    assert rate_name("spindle_rpm", 0.5) == "spindle_rpm@rate0.5s"
    assert parse_input_name("T5@lag30min") == ("T5", "lag", 1800.0)
    assert parse_input_name("T5@rate45s") == ("T5", "rate", 45.0)


@pytest.mark.parametrize("seconds", [1, 45, 60, 90, 600, 1800, 7200, 12.25, 86400 * 3])
@pytest.mark.parametrize("kind", ["lag", "rate"])
def test_names_round_trip(kind, seconds):
    name = input_name("T12 spindle", kind, seconds)
    assert parse_input_name(name) == ("T12 spindle", kind, float(seconds))


@pytest.mark.parametrize(
    "name",
    [
        "T5",
        "T5@lag",
        "T5@lag30",
        "T5@lag1800s",
        "T5@lag030min",
        "T5@lag0min",
        "T5@lag-30min",
        "T5@lag30minx",
        "@lag30min",
        "T@5@lag30min",
        "T5@delay30min",
        "T5@lag1.5min",
        "T5@lag1e3s",
        "",
    ],
)
def test_parse_refuses_anything_else(name):
    with pytest.raises(ValueError):
        parse_input_name(name)


def test_parse_names_the_canonical_form():
    with pytest.raises(ValueError, match="expected 'T5@lag30min'"):
        parse_input_name("T5@lag1800s")


def test_naming_refusals():
    for base in ("", "T@5", None):
        with pytest.raises(ValueError, match="signal name"):
            lag_name(base, 60)
    for seconds in (0, -60, np.inf, np.nan, 1e-7):
        with pytest.raises(ValueError):
            rate_name("T5", seconds)
    with pytest.raises(ValueError, match="kind"):
        input_name("T5", "mean", 60)


# ----------------------------------------------------------------------------- at measurements


def ramp_frame(step_s: float = 10.0, hours: float = 3.0) -> pd.DataFrame:
    seconds = np.arange(0.0, hours * 3600 + step_s / 2, step_s)
    return pd.DataFrame(
        {
            "time": T0 + pd.to_timedelta(seconds, unit="s"),
            "T1": 20.0 + 0.002 * seconds,  # a ramp: closed forms for both inputs
            "T2": np.full(seconds.size, 25.0),
        }
    )


def ramp_lag(seconds, tau, c=20.0, r=0.002):
    return c + r * (seconds - tau * -np.expm1(-seconds / tau))


def windows(starts_s, ends_s) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "measurement": np.arange(len(starts_s)),
            "start": T0 + pd.to_timedelta(np.asarray(starts_s, dtype=float), unit="s"),
            "end": T0 + pd.to_timedelta(np.asarray(ends_s, dtype=float), unit="s"),
        }
    )


@pytest.mark.parametrize("at, pick", [("end", 1), ("start", 0), ("mid", None)])
def test_inputs_at_measurements_equal_closed_forms(at, pick):
    # Windows not on the 10 s grid and given out of time order; the result keeps their order.
    starts, ends = [5000.0, 123.4, 3000.0], [5400.0, 500.7, 3000.0]
    out = inputs_at_measurements(ramp_frame(), windows(starts, ends), [1800, 45], [600], at=at)
    instants = np.array(
        [
            (a, b)[pick] if pick is not None else (a + b) / 2
            for a, b in zip(starts, ends, strict=True)
        ]
    )
    assert list(out.columns) == [
        "measurement", "start", "end", "time",
        "T1@lag30min", "T1@lag45s", "T1@rate10min", "T2@lag30min", "T2@lag45s", "T2@rate10min",
    ]  # fmt: skip
    assert list(out["measurement"]) == [0, 1, 2]
    np.testing.assert_allclose((out["time"] - T0).dt.total_seconds(), instants, rtol=0, atol=1e-6)
    np.testing.assert_allclose(out["T1@lag30min"], ramp_lag(instants, 1800.0), rtol=0, atol=1e-9)
    np.testing.assert_allclose(out["T1@lag45s"], ramp_lag(instants, 45.0), rtol=0, atol=1e-9)
    np.testing.assert_allclose(
        out["T1@rate10min"], 0.002 * 60 * np.minimum(instants, 600) / 600, atol=1e-12
    )
    np.testing.assert_allclose(out[["T2@lag30min", "T2@lag45s"]], 25.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out["T2@rate10min"], 0.0, atol=1e-12)


def test_inputs_at_instants_and_chosen_columns():
    instants = list(T0 + pd.to_timedelta([600.0, 3605.0], unit="s"))
    out = inputs_at_measurements(ramp_frame(), instants, [900], columns=["T1"])
    assert list(out.columns) == ["time", "T1@lag15min"]
    np.testing.assert_allclose(
        out["T1@lag15min"], ramp_lag(np.array([600.0, 3605.0]), 900.0), atol=1e-9
    )


def test_a_gap_after_the_last_measurement_is_harmless_and_one_before_is_refused():
    frame = ramp_frame()
    seconds = (frame["time"] - T0).dt.total_seconds().to_numpy()
    frame.loc[seconds > 2000.0, "T2"] = np.nan
    out = inputs_at_measurements(frame, windows([100.0], [1995.0]), [600])
    assert np.isfinite(out["T2@lag10min"]).all()
    with pytest.raises(
        ValueError, match=r"signal 'T2' has no value at 2022-05-10 09:33:30.*measurement 1 "
    ):
        inputs_at_measurements(
            frame, windows([100.0, 1000.0, 2500.0], [1995.0, 2005.0, 2600.0]), [600]
        )


def test_refusals_at_measurements():
    frame = ramp_frame(hours=1.0)
    with pytest.raises(ValueError, match="outside the temperature table"):
        inputs_at_measurements(frame, windows([3000.0], [3700.0]), [600])
    with pytest.raises(ValueError, match="at must be"):
        inputs_at_measurements(frame, windows([0.0], [10.0]), [600], at="mean")
    with pytest.raises(ValueError, match="ends before it starts"):
        inputs_at_measurements(frame, windows([100.0], [10.0]), [600])
    with pytest.raises(ValueError, match="no derived input"):
        inputs_at_measurements(frame, windows([0.0], [10.0]))
    with pytest.raises(ValueError, match="configured twice"):
        inputs_at_measurements(frame, windows([0.0], [10.0]), [1800, 1800.0])
    with pytest.raises(ValueError, match="missing column 'time'"):
        inputs_at_measurements(frame.drop(columns="time"), windows([0.0], [10.0]), [600])
    with pytest.raises(ValueError, match="no column 'T9'"):
        inputs_at_measurements(frame, windows([0.0], [10.0]), [600], columns=["T9"])
