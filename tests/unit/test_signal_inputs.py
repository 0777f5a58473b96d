"""Operating signals as deployable inputs: model.json, the Compensator and the Structured Text block.

The data are noise-free: at targets 0, 500 and 1000 mm the error is
1, 2, 3 um per degC of T1's rise plus 0, 0.001, 0.002 um per rpm of the spindle speed,
so every controller value below is worked out by hand.
"""

import copy
import math
import re

import numpy as np
import pandas as pd
import pytest

from helpers.plc import parsed_constants, st_twincat
from thermaxis.compensation.exports import twincat
from thermaxis.compensation.model import model_record, validate_model
from thermaxis.compensation.plc import structured_text
from thermaxis.compensation.runtime import Compensator
from thermaxis.config import FallbackSettings
from thermaxis.method.estimators import DecoupledAxisModel, PointwiseAxisModel

TARGETS = np.array([0.0, 500.0, 1000.0])
PER_C = np.array([1.0, 2.0, 3.0])
PER_RPM = np.array([0.0, 0.001, 0.002])
TAU_S = 1800.0
RAMP = FallbackSettings(1.5, (-10.0, 90.0), 0.25, 30.0, "ramp_to_zero", 20.0)


def _runs(signal="spindle"):
    rows, curves = [], []
    for r in range(3):
        for m in range(8):
            t1 = 22.0 + r + 0.6 * m + 0.05 * m * m
            speed = [1000.0, 2500.0, 4000.0][(m + r) % 3]
            rows.append({"run": f"R{r}", "measurement": m + 1, "time_min": 15.0 * m,
                         "T1": t1, signal: speed})  # fmt: skip
            rise = t1 - (22.0 + r)
            curves.append(PER_C * rise + PER_RPM * speed + 0.7)
    return pd.DataFrame(rows), pd.DataFrame(curves, columns=TARGETS)


@pytest.fixture(scope="module")
def fitted():
    X, Y = _runs()
    estimator = PointwiseAxisModel(sensors=("T1",), algorithm="mlr", signals=("spindle",))
    model = model_record(estimator.fit(X, Y), "pointwise", "mlr", X, RAMP, dataset="exact")
    validate_model(model)
    return model


def test_a_signal_is_an_input_of_its_own_kind_with_its_logged_range(fitted):
    assert fitted["sensors"] == ["T1", "spindle"] and fitted["signals"] == ["spindle"]
    kinds = [(i["sensor"], i["temperature"]) for i in fitted["inputs"]]
    assert kinds == [("T1", "relative"), ("spindle", "signal")]
    assert (fitted["inputs"][1]["training_min_c"], fitted["inputs"][1]["training_max_c"]) == (
        1000.0,
        4000.0,
    )
    for record, per_c, per_rpm in zip(fitted["regressions"], PER_C, PER_RPM, strict=True):
        assert record["inputs"] == [0, 1]
        assert record["coefficients"] == pytest.approx([per_c, per_rpm], abs=1e-9)


def test_the_compensation_follows_the_signal_change_since_homing(fitted):
    # dT1 = +4 C, speed 1000 -> 3000 rpm: changes 4, 10, 16 um; the line through them is
    # b = 4 um at P0 = 0 and k = 12 um/m, so K0 = -0.004 mm and tan(beta) = -12e-6.
    p = Compensator(fitted).parameters({"T1": 26.0, "spindle": 3000.0},
                                       {"T1": 22.0, "spindle": 1000.0})  # fmt: skip
    assert p.k0_mm == pytest.approx(-0.004, abs=1e-12)
    assert p.tan_beta == pytest.approx(-12e-6, abs=1e-15)
    assert p.curve_um == pytest.approx((-4.0, -10.0, -16.0), abs=1e-9)


def test_a_signal_has_no_temperature_range_but_must_be_present(fitted):
    c = Compensator(fitted)
    home = {"T1": 22.0, "spindle": 1000.0}
    # 9000 rpm lies outside the plausible degC range (-10 ... 90) and the training range.
    assert c.faults({"T1": 23.0, "spindle": 9000.0}, home) == ()
    assert c.faults({"T1": 23.0, "spindle": math.nan}, home) == ("spindle: missing",)
    assert c.faults({"T1": 23.0, "spindle": 2000.0}, {"T1": 22.0}) == (
        "spindle: reference value missing",
    )
    assert c.faults({"T1": 95.0, "spindle": 2000.0}, home) == (
        "T1: implausible 95 C (plausible -10 ... 90 C)",
    )


def test_the_block_reads_the_signal_channel_as_the_compensator_does(fitted):
    c = parsed_constants(structured_text(fitted, "SIMULATED test data."))
    assert c["SENSOR_SIGNAL"] == [False, True]
    assert c["INPUT_SENSOR"] == [1, 2] and c["INPUT_RELATIVE"] == [True, False]
    now, home = {"T1": 26.0, "spindle": 3000.0}, {"T1": 22.0, "spindle": 1000.0}
    expected = {row[0]: row[2] for row in twincat(Compensator(fitted).parameters(now, home))}
    got = st_twincat(c, np.array([26.0, 3000.0]), np.array([22.0, 1000.0]))
    # The predicted change b = 4 um, k = 12 um/m: offset -b * 10 = -40 [0.1 um], coefficient -k.
    assert got["P-AXIS-00273"] == pytest.approx(-40.0, abs=1e-9)
    assert got["P-AXIS-00274"] == pytest.approx(-12.0, abs=1e-9)
    for parameter in ("P-AXIS-00272", "P-AXIS-00273", "P-AXIS-00274"):
        assert got[parameter] == pytest.approx(expected[parameter], abs=1e-9)


def test_a_lag_of_the_signal_follows_the_closed_form_step_response(fitted):
    # The same model on a 30 min lag of the speed. The controller's samples: 1000 rpm at
    # t = 0, 3000 rpm from t = dt on; the filter, exact for input linear between cycles,
    # gives y(t) = 3000 - 2000 (tau / dt) (e^(dt/tau) - 1) e^(-t/tau) for t >= dt.
    model = {**fitted, "inputs": [dict(i) for i in fitted["inputs"]]}
    model["inputs"][1]["sensor"] = "spindle@lag30min"
    dt = 10.0
    t = np.arange(0.0, 7200.0 + dt / 2, dt)
    samples = [{"T1": 22.0, "spindle": 1000.0 if k == 0 else 3000.0} for k in range(t.size)]
    steps = Compensator(model).run(t, samples, samples[0])
    lag = 3000.0 - 2000.0 * (TAU_S / dt) * np.expm1(dt / TAU_S) * np.exp(-t[1:] / TAU_S)
    # T1 does not move, so the curve is the lag's change times 0, 0.001, 0.002 um per rpm.
    assert all(s.status == "ok" for s in steps)
    curves = np.array([s.parameters.curve_um for s in steps[1:]])
    assert curves == pytest.approx(-np.outer(lag - 1000.0, PER_RPM), abs=1e-9)


def test_a_derived_input_carries_its_definition_and_a_false_one_is_refused():
    X, Y = _runs()
    # Any values will do for the lag column: the test reads the record, not the fit.
    X["spindle@lag30min"] = np.linspace(900.0, 3100.0, len(X)) ** 1.1
    estimator = PointwiseAxisModel(
        sensors=("T1",), algorithm="mlr", signals=("spindle", "spindle@lag30min")
    )
    model = model_record(estimator.fit(X, Y), "pointwise", "mlr", X, RAMP, dataset="exact")
    assert "definition" not in model["inputs"][1]
    definition = model["inputs"][2]["definition"]
    assert (definition["of"], definition["kind"], definition["seconds"]) == (
        "spindle",
        "lag",
        1800.0,
    )
    assert "1800 s * dy/dt = spindle - y" in definition["formula"]
    validate_model(model)
    model["inputs"][2]["definition"] = {**definition, "seconds": 600.0}
    with pytest.raises(
        ValueError, match=r"^model.json: inputs/2/definition: does not match .*'spindle@lag30min'"
    ):
        validate_model(model)


def test_a_decoupled_model_reads_the_signal_in_both_its_slope_and_its_intercept():
    # k = -300 + 13 T1 + 0.01 speed [um/m] (absolute T1), b = -0.5 - 11 dT2 + 0.002 speed
    # [um] (T2's rise); homed at T1 = 30, T2 = 25, 1000 rpm, now T1 = 32, T2 = 26, 3000 rpm:
    # dk = 26 + 20 = 46 um/m, db = -11 + 4 = -7 um, so K0 = +0.007 mm, tan(beta) = -46e-6.
    rows, curves = [], []
    for r in range(3):
        for m in range(8):
            t1, rise = 28.0 + r + 0.7 * m + 0.04 * m * m, 0.3 * m + 0.02 * r * m
            speed = [1000.0, 2500.0, 4000.0][(m + 2 * r) % 3]
            rows.append({"run": f"R{r}", "measurement": m + 1, "time_min": 15.0 * m,
                         "T1": t1, "T2": 25.0 + r + rise, "spindle": speed})  # fmt: skip
            k = -300.0 + 13.0 * t1 + 0.01 * speed
            b = -0.5 - 11.0 * rise + 0.002 * speed
            curves.append(k * TARGETS / 1000.0 + b)
    X, Y = pd.DataFrame(rows), pd.DataFrame(curves, columns=TARGETS)
    estimator = DecoupledAxisModel(("T1",), ("T2",), algorithm="mlr", signals=("spindle",))
    model = model_record(estimator.fit(X, Y), "decoupled", "mlr", X, RAMP, dataset="exact")
    kinds = [(i["sensor"], i["temperature"]) for i in model["inputs"]]
    assert kinds == [("T1", "absolute"), ("T2", "relative"), ("spindle", "signal")]
    # k on T1 and the speed, b on T2's rise and the speed, in physical units.
    assert [(r["target"], r["inputs"]) for r in model["regressions"]] == [
        ("k", [0, 2]),
        ("b", [1, 2]),
    ]
    assert model["regressions"][0]["coefficients"] == pytest.approx([13.0, 0.01], abs=1e-8)
    assert model["regressions"][1]["coefficients"] == pytest.approx([-11.0, 0.002], abs=1e-8)
    p = Compensator(model).parameters({"T1": 32.0, "T2": 26.0, "spindle": 3000.0},
                                      {"T1": 30.0, "T2": 25.0, "spindle": 1000.0})  # fmt: skip
    assert p.k0_mm == pytest.approx(0.007, abs=1e-9)
    assert p.tan_beta == pytest.approx(-46e-6, abs=1e-12)


@pytest.mark.parametrize(
    "edit, message",
    [
        # Python's JSON reader turns NaN, Infinity and 1e999 into floats a controller would apply.
        (lambda m: m["regressions"][0].update(constant=math.inf),
         "regressions/0/constant: expected a finite number, got inf"),
        (lambda m: m["regressions"][1]["coefficients"].__setitem__(1, math.nan),
         "regressions/1/coefficients/1: expected a finite number, got nan"),
        # The fixture's regressions read inputs 0 and 1 of its 2.
        (lambda m: m["regressions"][0].update(inputs=[0, 2]),
         "regressions/0/inputs: index 2 is beyond the model's 2 inputs (expected 0 to 1)"),
        (lambda m: m["regressions"][2].update(coefficients=[1.0]),
         "regressions/2/coefficients: 1 number(s) for 2 input(s); expected one per input"),
        (lambda m: m["inputs"][0].update(sensor="T9"),
         "inputs/0/sensor: 'T9' is not of a sensor the model reads (expected one of T1, spindle)"),
        (lambda m: m["inputs"][1].update(training_min_c=5000.0),
         "inputs/1: training_min_c 5000 is above training_max_c 4000; expected the training "
         "range low to high"),
        (lambda m: m["fallback"].update(plausible_c=[90.0, -10.0]),
         "fallback/plausible_c: expected [low, high] with low < high, got [90, -10]"),
        # Three targets, three regressions: a 3 x 3 basis; one row short.
        (lambda m: m["curve_basis"].pop(),
         "curve_basis: expected 3 row(s) of 3 number(s) (one per regression), got 2 row(s) of 3"),
    ],
    ids=["infinite_constant", "nan_coefficient", "input_beyond", "coefficient_missing",
         "unknown_sensor", "training_range_reversed", "plausible_range_reversed",
         "curve_basis_short"],
)  # fmt: skip
def test_a_model_a_controller_could_not_apply_is_refused_in_one_line(fitted, edit, message):
    model = copy.deepcopy(fitted)
    edit(model)
    with pytest.raises(ValueError, match=f"^{re.escape('model.json: ' + message)}$"):
        validate_model(model)
