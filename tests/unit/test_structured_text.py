"""The generated Structured Text block, read back by a real IEC 61131-3 parser (blark).

The constants are taken from blark's parse tree, evaluated, and the TwinCAT values they
encode are computed from them with plain numpy; they must equal Compensator's to 1e-9.
"""

import copy
import math

import numpy as np
import pandas as pd
import pytest

from helpers.builders import lagged_model, logged_run
from helpers.plc import parsed_constants, st_twincat
from thermaxis.compensation.exports import twincat
from thermaxis.compensation.model import CONVENTION, combined_record, model_record, validate_model
from thermaxis.compensation.plc import st_real, structured_text
from thermaxis.compensation.runtime import Compensator
from thermaxis.config import FallbackSettings
from thermaxis.method.estimators import DecoupledAxisModel, PointwiseAxisModel

TARGETS = np.array([185.0 + 20.0 * i for i in range(14)])
RAMP = FallbackSettings(1.5, (-10.0, 90.0), 0.25, 30.0, "ramp_to_zero", 20.0)


def exact_runs(wobble_um: float = 0.0):
    """k = -300 + 13 T1 [um/m] on absolute T1, b = -0.5 - 11 dT2 [um] on T2's rise; noise-free
    unless wobbled."""
    rows, curves = [], []
    for r in range(3):
        for m in range(6):
            t1 = 28.0 + r + 0.8 * m + 0.3 * m * m
            rise = 0.5 * m + 0.05 * r * m
            rows.append(
                {
                    "run": f"R{r}",
                    "measurement": m + 1,
                    "time_min": 20.0 * m,
                    "T1": t1,
                    "T2": 25.0 + 0.4 * r + rise,
                }
            )
            k = -300.0 + 13.0 * t1 + 10.0 * wobble_um * np.cos(5.0 * m + r)
            b = -0.5 - 11.0 * rise + wobble_um * np.sin(7.0 * m + 3.0 * r)
            curves.append(k * (TARGETS - 185.0) / 1000.0 + b)
    return pd.DataFrame(rows), pd.DataFrame(curves, columns=TARGETS)


@pytest.fixture(scope="module")
def exported():
    X, Y = exact_runs()
    estimator = DecoupledAxisModel(("T1",), ("T2",), algorithm="mlr").fit(X, Y)
    model = model_record(
        estimator, "decoupled", "mlr", X, RAMP, {"T2": 0.125, "T9": 1.0}, dataset="exact"
    )
    source = structured_text(model, "SIMULATED test data.")
    return model, Compensator(model), source, parsed_constants(source)


def test_constants_read_back_exactly(exported):
    model, _, _, c = exported
    assert c["N_SENSORS"] == 2 and c["N_INPUTS"] == 2 and c["N_REGRESSIONS"] == 2
    assert c["INPUT_SENSOR"] == [1, 2] and c["INPUT_RELATIVE"] == [False, True]
    assert c["INPUT_MIN"] == [i["training_min_c"] for i in model["inputs"]]
    assert c["INPUT_MAX"] == [i["training_max_c"] for i in model["inputs"]]
    assert c["LINE_B"] + c["LINE_K"] == [w for row in model["line_weights"] for w in row]
    assert c["P0_MM"] == 185.0
    assert (
        c["RANGE_MARGIN"],
        c["PLAUSIBLE_MIN"],
        c["PLAUSIBLE_MAX"],
        c["MAX_RATE"],
        c["MAX_AGE"],
    ) == (1.5, -10.0, 90.0, 0.25, 30.0)
    assert c["POLICY_RAMP"] is True and c["RAMP_TIME"] == 1200.0
    # Each sensor's log noise in sensor order; a sensor the training logs did not give: 0.
    assert model["noise_c"] == {"T1": 0.0, "T2": 0.125}
    assert c["SENSOR_NOISE"] == [0.0, 0.125]


@pytest.mark.parametrize(
    "now, ref",
    [((32.0, 26.5), (30.0, 25.0)), ((29.25, 24.1), (30.5, 25.3)), ((30.0, 25.0), (30.0, 25.0))],
)
def test_st_values_equal_compensator(exported, now, ref):
    _, comp, _, c = exported
    expected = {
        row[0]: row[2]
        for row in twincat(
            comp.parameters(
                dict(zip(("T1", "T2"), now, strict=True)), dict(zip(("T1", "T2"), ref, strict=True))
            )
        )
    }
    got = st_twincat(c, np.array(now), np.array(ref))
    for parameter, value in expected.items():
        assert got[parameter] == pytest.approx(value, abs=1e-9), parameter


def test_evidence_ridge_block_equals_compensator():
    # The evidence ridge is affine: its block carries constants and coefficients like MLR's,
    # its standardisation folded in, and the parsed block must give Compensator's values.
    X, Y = exact_runs(wobble_um=0.3)
    estimator = DecoupledAxisModel(("T1",), ("T2",), algorithm="bayesridge").fit(X, Y)
    model = model_record(estimator, "decoupled", "bayesridge", X, RAMP, dataset="exact")
    assert {r["form"] for r in model["regressions"]} == {"affine"}
    c = parsed_constants(structured_text(model, "SIMULATED test data."))
    comp = Compensator(model)
    now, ref = (32.0, 26.5), (30.0, 25.0)
    expected = {
        row[0]: row[2]
        for row in twincat(
            comp.parameters({"T1": now[0], "T2": now[1]}, {"T1": ref[0], "T2": ref[1]})
        )
    }
    got = st_twincat(c, np.array(now), np.array(ref))
    for parameter, value in expected.items():
        assert got[parameter] == pytest.approx(value, abs=1e-9), parameter


def test_hand_worked_signs(exported):
    # T1 30 -> 32: k rises 26 um/m; T2 rises 1.5: b falls 16.5 um. Compensation = -change:
    # offset_0 = +16.5 um = 165 (0.1 um), coefficient = -26 um/m,
    # position_0 = 185 mm = 1850000 (0.1 um).
    _, _, source, c = exported
    got = st_twincat(c, np.array([32.0, 26.5]), np.array([30.0, 25.0]))
    assert got == pytest.approx(
        {"P-AXIS-00272": 1_850_000.0, "P-AXIS-00273": 165.0, "P-AXIS-00274": -26.0}, abs=1e-6
    )
    assert CONVENTION in source and "P-AXIS-00273 temp_comp_offset_0 [0.1 um]" in source
    assert "SIMULATED" in source


def test_single_position_block_has_no_slope():
    X, Y = exact_runs()
    Y = Y[[TARGETS[3]]]
    estimator = PointwiseAxisModel(("T2",), algorithm="mlr").fit(X, Y)
    c = parsed_constants(
        structured_text(model_record(estimator, "pointwise", "mlr", X, RAMP), "SIMULATED")
    )
    assert c["LINE_K"] == [0.0] and c["LINE_B"] == [1.0] and c["P0_MM"] == TARGETS[3]


@pytest.mark.parametrize("algorithm", ["svr", "gpr"])
def test_kernel_blocks_equal_compensator(algorithm):
    # A little scatter keeps the GPR's weights moderate (noise-free data would drive them to ~1e6).
    X, Y = exact_runs(wobble_um=0.3)
    grid = {"C": [10.0], "epsilon": [0.05], "gamma": ["scale"]}
    estimator = DecoupledAxisModel(("T1",), ("T2",), algorithm=algorithm, svr_grid=grid).fit(X, Y)
    model = model_record(estimator, "decoupled", algorithm, X, RAMP)
    comp = Compensator(model)
    c = parsed_constants(structured_text(model, "SIMULATED"))
    assert "COEFF" not in c and c["R1_GAMMA"] == model["regressions"][0]["gamma"]
    for now, ref in (((32.0, 26.5), (30.0, 25.0)), ((29.25, 24.1), (30.5, 25.3))):
        expected = {
            row[0]: row[2]
            for row in twincat(
                comp.parameters(
                    dict(zip(("T1", "T2"), now, strict=True)),
                    dict(zip(("T1", "T2"), ref, strict=True)),
                )
            )
        }
        got = st_twincat(c, np.array(now), np.array(ref))
        assert got == pytest.approx(expected, abs=1e-9)
        assert abs(got["P-AXIS-00274"]) > 1.0  # a real slope, not an empty model


def test_literals_keep_every_bit():
    for value in (1e-05, -7.417, 0.1 + 0.2, 185.0, -2.5e-300):
        text = st_real(value)
        assert "." in text.split("E")[0] and float(text) == value


def st_lags(c: dict, times, readings) -> list[np.ndarray]:
    """The block's lag filters run on its own constants (LAG_SENSOR, LAG_TAU), cycle by cycle:
    the exact response of tau y' = u - y to u linear over the cycle, e = y - u,
    e := a e - (1 - a) / x (u - u_previous), a = exp(-x), x = dt / tau; a missing reading
    (NaN) feeds the last one; each filter starts steady at its sensor's first reading."""
    sensor, tau = np.asarray(c["LAG_SENSOR"]) - 1, np.asarray(c["LAG_TAU"])
    u = e = None
    out = []
    for k, reading in enumerate(readings):
        fed = np.asarray(reading, dtype=float)[sensor]
        if u is None:
            u, e = fed, np.zeros_like(fed)
        else:
            fed = np.where(np.isnan(fed), u, fed)
            x = (times[k] - times[k - 1]) / tau
            one_minus_a = -np.array([math.expm1(-v) for v in x])
            e = np.exp(-x) * e - one_minus_a / x * (fed - u)
            u = fed
        out.append(u + e)
    return out


def test_lag_block_equals_compensator_cycle_by_cycle():
    # k on a 600 min lag of T1 (dt/tau ~ 3e-4: the block's series for 1 - a) and b on a
    # 30 min lag of T2's rise (dt/tau ~ 6e-3: EXP); one reading of T2 missing mid-run.
    model = lagged_model()
    model["inputs"][0]["sensor"] = "T1@lag600min"
    model["inputs"][0]["training_max_c"] = 40.0
    t, samples, _ = logged_run()
    samples[120] = {**samples[120], "T2": math.nan}
    steps = Compensator(copy.deepcopy(model)).run(t, samples, samples[0])
    c = parsed_constants(structured_text(model, "SIMULATED test data."))
    assert (c["N_LAGS"], c["LAG_SENSOR"], c["LAG_TAU"]) == (2, [1, 2], [36000.0, 1800.0])
    assert c["INPUT_LAG"] == [1, 2]
    readings = [[s["T1"], s["T2"]] for s in samples]
    lags = st_lags(c, t, readings)
    checked = 0
    for k, step in enumerate(steps):
        if step.status != "ok":
            continue
        expected = {row[0]: row[2] for row in twincat(step.parameters)}
        got = st_twincat(c, np.array(readings[k]), np.array(readings[0]), (lags[k], lags[0]))
        for parameter in ("P-AXIS-00273", "P-AXIS-00274"):
            assert got[parameter] == pytest.approx(expected[parameter], abs=1e-9), (k, parameter)
        checked += 1
    assert steps[120].status != "ok" and checked == len(t) - 1
    # The lags moved: b's 30 min lag of a 0.002 C/s ramp is far from its homing value.
    assert abs(expected["P-AXIS-00273"]) > 100.0


def test_a_block_without_lags_declares_none(exported):
    _, _, source, c = exported
    assert "N_LAGS" not in c and "aLag" not in source


def test_a_rate_input_is_refused_by_name():
    model = lagged_model()
    model["inputs"][1]["sensor"] = "T2@rate10min"
    with pytest.raises(ValueError, match=r"'T2@rate10min'.*lag inputs only"):
        structured_text(model, "SIMULATED")


def test_a_combination_is_the_weighted_sum_of_its_members_in_one_block():
    # The super learner deploys its members as one linear model.json: decoupled MLR on T1
    # (k) and T2 (b), and a point-by-point ridge on both rises, weighted 0.3 and 0.7.
    X, Y = exact_runs(wobble_um=0.3)
    decoupled = DecoupledAxisModel(("T1",), ("T2",), algorithm="mlr").fit(X, Y)
    pointwise = PointwiseAxisModel(("T1", "T2"), algorithm="ridge").fit(X, Y)
    members = [
        ("paper", 0.3, model_record(decoupled, "decoupled", "mlr", X, RAMP, {"T2": 0.125})),
        ("ridge", 0.7, model_record(pointwise, "pointwise", "ridge", X, RAMP, {"T1": 0.25})),
        ("unused", 0.0, model_record(pointwise, "pointwise", "ridge", X, RAMP)),
    ]
    model = combined_record(members, dataset="exact")
    validate_model(model)
    # Inputs merged: T1 absolute (decoupled k), T2 relative (both), T1 relative (pointwise).
    assert [(i["sensor"], i["temperature"]) for i in model["inputs"]] == [
        ("T1", "absolute"), ("T2", "relative"), ("T1", "relative"),
    ]  # fmt: skip
    assert len(model["regressions"]) == 2 + TARGETS.size
    assert [(m["candidate"], m["weight"]) for m in model["members"]] == [
        ("paper", 0.3), ("ridge", 0.7),
    ]  # fmt: skip
    assert model["noise_c"] == {"T1": 0.25, "T2": 0.125}
    combined = Compensator(model)
    alone = [Compensator(record) for _, _, record in members[:2]]
    c = parsed_constants(structured_text(model, "SIMULATED test data."))
    for now, ref in [((32.0, 26.5), (30.0, 25.0)), ((29.25, 24.1), (30.5, 25.3))]:
        state, home = (
            dict(zip(("T1", "T2"), now, strict=True)),
            dict(zip(("T1", "T2"), ref, strict=True)),
        )
        # The members' compensations (minus their predicted changes), weighted by hand in numpy.
        expected = 0.3 * np.array(alone[0].parameters(state, home).curve_um) + 0.7 * np.array(
            alone[1].parameters(state, home).curve_um
        )
        got = combined.parameters(state, home)
        np.testing.assert_allclose(got.curve_um, expected, rtol=1e-12, atol=1e-9)
        # The least-squares line of that curve, by hand, is what the controllers get.
        design = np.column_stack([np.ones(TARGETS.size), (TARGETS - 185.0) / 1000.0])
        (b, k), *_ = np.linalg.lstsq(design, expected, rcond=None)
        assert got.k0_mm == pytest.approx(b / 1000.0, abs=1e-12)
        assert got.tan_beta == pytest.approx(k * 1e-6, abs=1e-15)
        # The Structured Text block gives the Compensator's values.
        values = {row[0]: row[2] for row in twincat(got)}
        block = st_twincat(c, np.array(now), np.array(ref))
        for parameter, value in values.items():
            assert block[parameter] == pytest.approx(value, abs=1e-9), parameter
