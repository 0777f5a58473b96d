"""A time-aware input in model.json, computed by the Compensator cycle by cycle."""

import numpy as np
import pytest

from helpers.builders import lagged_model, logged_run
from thermaxis.compensation.runtime import Compensator
from thermaxis.method.inputs import LagState, lag_filter


def test_the_lag_carried_cycle_by_cycle_equals_the_offline_filter():
    t, samples, t2 = logged_run()
    compensator = Compensator(lagged_model())
    assert compensator.sensors == ("T1", "T2")  # the controller reads the logged sensors
    online = [d["T2@lag30min"] for d in compensator.derived_inputs(t, samples)]
    np.testing.assert_allclose(online, lag_filter(t, t2, 1800.0), rtol=0, atol=1e-9)


def test_each_cycle_uses_the_lag_and_its_value_at_homing():
    t, samples, t2 = logged_run()
    compensator = Compensator(lagged_model())
    steps = compensator.run(t, samples, samples[0])
    lag = lag_filter(t, t2, 1800.0)
    for k in (0, 60, 239):
        # b = -0.5 - 11 x (lag now - lag at homing), k = -300 + 13 T1: as parameters() computes it.
        expected = compensator.parameters(
            {**samples[k], "T2@lag30min": lag[k]}, {**samples[0], "T2@lag30min": lag[0]}
        )
        assert steps[k].status == "ok"
        assert steps[k].parameters.k0_mm == pytest.approx(expected.k0_mm, abs=1e-12)
        assert steps[k].parameters.tan_beta == pytest.approx(expected.tan_beta, abs=1e-15)
    # Hand check at the last cycle: the compensation undoes the change of b since homing,
    # delta b = -11 (lag - lag at homing) um, so K0 = -delta b / 1000 mm.
    delta_b = -11.0 * (lag[-1] - lag[0])
    assert steps[-1].parameters.k0_mm == pytest.approx(-delta_b / 1000.0, abs=1e-12)


def test_a_missing_reading_feeds_the_last_good_one_to_the_filter():
    t, samples, t2 = logged_run(n=20)
    broken = [dict(s) for s in samples]
    broken[10]["T2"] = float("nan")
    held = t2.copy()
    held[10] = held[9]
    online = [d["T2@lag30min"] for d in Compensator(lagged_model()).derived_inputs(t, broken)]
    np.testing.assert_allclose(online, lag_filter(t, held, 1800.0), rtol=0, atol=1e-9)


def test_a_sensor_without_readings_yet_starts_its_lag_at_its_first_reading():
    t, samples, t2 = logged_run(n=30)
    t1 = np.array([s["T1"] for s in samples])
    model = lagged_model()
    model["inputs"][0]["sensor"] = "T1@lag30min"  # both inputs lags of 30 min
    late = [dict(s) for s in samples]
    for s in late[:5]:
        del s["T1"]  # T1 logs nothing in the first five cycles
    derived = Compensator(model).derived_inputs(t, late)
    # T2's lag runs from the first cycle; T1's is undefined until its first reading and
    # starts there, steady, as the offline filter started at that sample.
    np.testing.assert_allclose([d["T2@lag30min"] for d in derived], lag_filter(t, t2, 1800.0),
                               rtol=0, atol=1e-9)  # fmt: skip
    lag1 = [d["T1@lag30min"] for d in derived]
    assert np.isnan(lag1[:5]).all()
    np.testing.assert_allclose(lag1[5:], lag_filter(t[5:], t1[5:], 1800.0), rtol=0, atol=1e-9)


def test_a_lag_state_fed_several_signals_equals_one_state_per_signal():
    t, samples, t2 = logged_run(n=50)
    t1 = np.array([s["T1"] for s in samples])
    together, alone = LagState(600.0), [LagState(600.0), LagState(600.0)]
    for k in range(t.size):
        both = together.update(t[k], np.array([t1[k], t2[k]]))
        each = [state.update(t[k], u) for state, u in zip(alone, (t1[k], t2[k]), strict=True)]
        assert both.tolist() == each  # the same arithmetic, bit for bit
