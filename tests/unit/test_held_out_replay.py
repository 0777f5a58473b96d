"""The held-out replay of a compensation with a time-aware input: the run's cleaned log,
cycle by cycle, homed at the first measurement."""

import numpy as np
import pandas as pd
import pytest

from helpers.builders import hand_model, lagged_model
from thermaxis.compensation.held_out import measurement_cycles, replay
from thermaxis.compensation.runtime import Compensator

START = pd.Timestamp("2026-01-05 08:00:00")
TAU_S = 1800.0  # lagged_model's T2@lag30min
RISE = 0.002  # C/s of T2


def _log(stop_s=3600.0, step_s=10.0):
    t = np.arange(0.0, stop_s + step_s / 2, step_s)
    return pd.DataFrame(
        {"time": START + pd.to_timedelta(t, unit="s"), "T1": 30.0, "T2": 25.0 + RISE * t}
    )


def _windows(starts_s=(600.0, 1800.0, 3000.0), width_s=45.0):
    return pd.DataFrame(
        {
            "measurement": range(1, len(starts_s) + 1),
            "start": [START + pd.Timedelta(seconds=s) for s in starts_s],
            "end": [START + pd.Timedelta(seconds=s + width_s) for s in starts_s],
        }
    )


def _lag_of_ramp(t):
    """The first-order lag of 25 + r t, steady at 25 at t = 0: 25 + r (t - tau (1 - e^(-t/tau)))."""
    t = np.asarray(t, dtype=float)
    return 25.0 + RISE * (t - TAU_S * (1.0 - np.exp(-t / TAU_S)))


def test_the_cycles_are_the_log_up_to_the_last_measurement_and_each_measurements_middle():
    times, samples, rows = measurement_cycles(_log(), _windows(), ["T1", "T2"])
    mids = [622.5, 1822.5, 3022.5]
    assert [times[r] for r in rows] == mids
    assert times[-1] == 3022.5  # nothing after the last measurement
    assert np.all(np.diff(times) > 0)
    # 0, 10, ..., 3020 s: 303 samples on the 10 s grid, and the three mids between them.
    assert len(times) == 303 + 3
    for r, mid in zip(rows, mids, strict=True):
        assert samples[r]["T2"] == pytest.approx(25.0 + RISE * mid, abs=1e-12)


def test_a_gap_in_the_log_is_bridged_linearly():
    log = _log()
    log.loc[100:110, "T2"] = np.nan  # 1000-1100 s
    times, samples, _ = measurement_cycles(log, _windows(), ["T1", "T2"])
    at = times.index(1050.0)
    assert samples[at]["T2"] == pytest.approx(25.0 + RISE * 1050.0, abs=1e-12)


def test_each_measurement_gets_the_lag_of_the_whole_history_since_the_log_started():
    model = Compensator(lagged_model())
    X_run = pd.DataFrame({"measurement": [1, 2, 3], "time_min": [0.0, 20.0, 40.0],
                          "T1": 30.0, "T2": 0.0})  # fmt: skip
    cycles = measurement_cycles(_log(), _windows(), ["T1", "T2"])
    steps, values = replay(model, X_run, cycles)
    lag = _lag_of_ramp([622.5, 1822.5, 3022.5])
    # b = -0.5 - 11 (lag - lag at homing), k constant (T1 constant): the controller undoes
    # the change of b, K0 = 11 (lag - lag at homing) / 1000 mm.
    expected = 11.0 * (lag - lag[0]) / 1000.0
    assert [s.status for s in steps] == ["ok", "ok", "ok"]
    np.testing.assert_allclose([s.parameters.k0_mm for s in steps], expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose([v.k0_mm for v in values], expected, rtol=0, atol=1e-9)
    assert [s.parameters.tan_beta for s in steps] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)


def test_a_model_without_time_aware_inputs_is_replayed_one_measurement_at_a_time():
    model = Compensator(hand_model())
    X_run = pd.DataFrame({"measurement": [2, 1], "time_min": [30.0, 0.0],
                          "T1": [31.0, 30.0], "T2": [27.0, 25.0]})  # fmt: skip
    steps, values = replay(model, X_run)
    # Time order; k = -300 + 13 T1 and b = -0.5 - 11 dT2, undone: b changes by -22 um at
    # measurement 2, so K0 = +0.022 mm; k by +13 um/m, so tan(beta) = -13e-6.
    assert [s.time_s for s in steps] == [0.0, 1800.0]
    assert steps[1].parameters.k0_mm == pytest.approx(0.022, abs=1e-12)
    assert steps[1].parameters.tan_beta == pytest.approx(-13e-6, abs=1e-15)
    assert values[1] == steps[1].parameters


def test_fallback_warnings_are_one_line_per_fold_and_status():
    from thermaxis.compensation.held_out import fallback_summary
    from thermaxis.compensation.runtime import ControllerParameters, Step

    p = ControllerParameters(0.0, 0.0, 0.0, (0.0,), 0.0, True)
    steps = [
        Step(0.0, p, "ok"),
        Step(60.0, p, "hold", ("T16: changes 0.6 C/min (limit 0.5 C/min)",)),
        Step(120.0, p, "hold", ("T16: changes 0.9 C/min (limit 0.5 C/min)", "T5: stale")),
        Step(180.0, p, "ok"),
    ]
    assert fallback_summary("R1", steps) == [
        "fold R1: hold on 2 of 4 cycles (t=60 to 120 s): first T16: changes 0.6 C/min "
        "(limit 0.5 C/min) at t=60 s; T5: stale at t=120 s"
    ]
