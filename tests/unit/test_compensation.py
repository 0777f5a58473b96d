"""Compensation: K0/tan(beta)/P0 from k and b worked by hand, the fallback policy, the residual
tables."""

import json
import math

import numpy as np
import pandas as pd
import pytest

from helpers.builders import HOLD, TARGETS, hand_model
from thermaxis.compensation.exports import siemens_840d, twincat
from thermaxis.compensation.held_out import held_out_tables, largest_steps, step_noise
from thermaxis.compensation.model import line_weights, model_record
from thermaxis.compensation.runtime import Compensator, ControllerParameters, Step
from thermaxis.config import FallbackSettings
from thermaxis.method.estimators import DecoupledAxisModel, PointwiseAxisModel

REF = {"T1": 30.0, "T2": 25.0}
WARM = {"T1": 32.0, "T2": 26.5}


def test_k0_tan_beta_p0_from_k_and_b_by_hand():
    # T1 30 -> 32: delta k = 13 * 2 = 26 um/m; T2 rises 1.5: delta b = -11 * 1.5 = -16.5 um.
    # Predicted change e(x) = 26 (x - 185)/1000 - 16.5 um; compensation = -e:
    # K0 = +16.5 um = 0.0165 mm, tan(beta) = -26e-6, P0 = 185 mm.
    p = Compensator(hand_model()).parameters(WARM, REF)
    assert p.k0_mm == pytest.approx(0.0165, abs=1e-12)
    assert p.tan_beta == pytest.approx(-26e-6, abs=1e-15)
    assert p.p0_mm == 185.0
    # At 445 mm: e = 26 * 0.26 - 16.5 = -9.74 um, so the controller adds +9.74 um.
    assert p.at([445.0])[0] == pytest.approx(9.74, abs=1e-9)
    assert p.curve_um[-1] == pytest.approx(9.74, abs=1e-9)
    assert p.line_gap_um == pytest.approx(0.0, abs=1e-12)


def test_controller_units_by_hand():
    p = Compensator(hand_model()).parameters(WARM, REF)
    siemens = {row[0]: (row[2], row[3]) for row in siemens_840d(p)}
    assert siemens["SD43900"] == (pytest.approx(0.0165), "mm")
    assert siemens["SD43910"][0] == pytest.approx(-26e-6)
    assert siemens["SD43920"] == (185.0, "mm")
    tc = {row[0]: (row[2], row[3]) for row in twincat(p)}
    assert tc["P-AXIS-00272"] == (pytest.approx(1_850_000.0), "0.1 um")  # 185 mm in 0.1 um
    assert tc["P-AXIS-00273"] == (pytest.approx(165.0), "0.1 um")  # 16.5 um
    assert tc["P-AXIS-00274"] == (pytest.approx(-26.0), "um/m")


def test_reference_state_needs_no_compensation():
    p = Compensator(hand_model()).parameters(REF, REF)
    assert (p.k0_mm, p.tan_beta) == (0.0, 0.0)


def test_shifted_origin_of_another_stroke():
    # Stroke 50 ... 150 mm: P0 = 50 mm; the same changes give K0 = 0.0165 mm at 50 mm.
    positions = [50.0, 100.0, 150.0]
    p = Compensator(hand_model(positions=positions)).parameters(WARM, REF)
    assert p.p0_mm == 50.0
    # At 150 mm: e = 26 * 0.1 - 16.5 = -13.9 um -> compensation +13.9 um.
    assert p.at([150.0])[0] == pytest.approx(13.9, abs=1e-9)


def test_line_weights_of_a_straight_model_pick_k_and_b():
    s = (np.asarray(TARGETS) - 185.0) / 1000.0
    weights = line_weights(TARGETS, 185.0, np.column_stack([s, np.ones_like(s)]))
    np.testing.assert_allclose(weights, [[0.0, 1.0], [1.0, 0.0]], atol=1e-12)


def test_single_position_is_offset_only():
    weights = line_weights([300.0], 300.0, np.array([[1.0]]))
    np.testing.assert_array_equal(weights, [[1.0], [0.0]])
    p = ControllerParameters(0.002, 0.0, 300.0, (2.0,), 0.0, offset_only=True)
    assert [row[0] for row in siemens_840d(p)] == ["SD43900"]


# --------------------------------------------------------------------------- fallback policy


def test_out_of_range_holds_the_last_good_value_and_says_why():
    comp = Compensator(hand_model())
    # T1 training range 28 ... 34, margin 2: 36.5 is out. Samples 10 min apart, slow changes.
    steps = comp.run([0.0, 600.0, 1200.0], [REF, WARM, {"T1": 36.5, "T2": 26.5}], REF)
    assert [s.status for s in steps] == ["ok", "ok", "hold"]
    assert steps[2].parameters == steps[1].parameters
    assert "T1 (absolute)" in steps[2].reasons[0] and "training range" in steps[2].reasons[0]


def test_stale_and_missing_sensors_hold():
    comp = Compensator(hand_model())
    ages = [{}, {"T2": 120.0}, {}]
    steps = comp.run(
        [0.0, 600.0, 1200.0], [WARM, WARM, {"T1": math.nan, "T2": 26.5}], REF, ages_s=ages
    )
    assert [s.status for s in steps] == ["ok", "hold", "hold"]
    assert "stale" in steps[1].reasons[0] and "missing" in steps[2].reasons[0]
    assert steps[2].parameters.k0_mm == pytest.approx(0.0165)


def test_rate_limit():
    comp = Compensator(hand_model())
    # 1 C in 10 min = 0.1 C/min is fine; 1 C in 1 min exceeds 0.5 C/min.
    samples = [REF, {"T1": 31.0, "T2": 25.0}, {"T1": 32.0, "T2": 25.0}]
    steps = comp.run([0.0, 600.0, 660.0], samples, REF)
    assert [s.status for s in steps] == ["ok", "ok", "hold"]
    assert "T1: changes 1 C/min" in steps[2].reasons[0]


def test_a_step_within_the_training_logs_noise_is_no_rate_fault():
    # A 0.1 C display step in a 10 s log is 0.6 C/min, over the 0.5 C/min limit: with the
    # sensor's noise from training (noise_c 0.1 C) it passes; 0.1 C beyond the noise in
    # 10 s (0.6 C/min) is still a fault, and a model without noise_c allows nothing.
    samples = [REF, {"T1": 30.1, "T2": 25.0}, {"T1": 30.3, "T2": 25.0}]
    times = [0.0, 10.0, 20.0]
    quiet = Compensator({**hand_model(), "noise_c": {"T1": 0.1, "T2": 0.1}}).run(
        times, samples, REF
    )
    assert [s.status for s in quiet] == ["ok", "ok", "hold"]
    assert "T1: changes 0.6 C/min beyond its 0.1 C log noise" in quiet[2].reasons[0]
    strict = Compensator(hand_model()).run(times, samples, REF)
    assert [s.status for s in strict] == ["ok", "hold", "hold"]
    assert "T1: changes 0.6 C/min (limit 0.5 C/min)" in strict[1].reasons[0]


def test_the_noise_of_the_training_runs_is_their_largest_log_step():
    logs = {
        "R1": pd.DataFrame({"time": [0, 10, 20, 30], "elapsed_min": [0, 1, 2, 3],
                            "T1": [20.0, 20.1, 20.1, 20.3], "T2": [21.0, np.nan, 21.5, 21.4]}),
        "R2": pd.DataFrame({"time": [0, 10], "elapsed_min": [0, 1],
                            "T1": [22.0, 22.1], "T2": [np.nan, 23.0]}),
    }  # fmt: skip
    steps = {run: largest_steps(frame) for run, frame in logs.items()}
    # R1: T1 steps 0.1, 0, 0.2; T2 skips the gap: 0.5, 0.1. R2: T1 0.1; T2 one sample.
    assert steps["R1"] == pytest.approx({"T1": 0.2, "T2": 0.5})
    assert steps["R2"] == pytest.approx({"T1": 0.1, "T2": 0.0})
    assert step_noise(steps, ["R2"]) == pytest.approx({"T1": 0.1, "T2": 0.0})
    assert step_noise(steps, ["R1", "R2"]) == pytest.approx({"T1": 0.2, "T2": 0.5})


def test_ramp_to_zero_and_recovery():
    ramp = FallbackSettings(2.0, (-20.0, 120.0), 0.5, 60.0, "ramp_to_zero", 30.0)
    comp = Compensator(hand_model(ramp))
    bad = {"T1": 200.0, "T2": 26.5}  # implausible
    steps = comp.run([0.0, 600.0, 1500.0, 3000.0, 3600.0], [WARM, bad, bad, bad, WARM], REF)
    assert [s.status for s in steps] == ["ok", "ramp", "ramp", "ramp", "ok"]
    # Fault starts at 600 s: full value there, half at +15 min, zero after 30 min.
    assert [s.parameters.k0_mm for s in steps[1:4]] == pytest.approx([0.0165, 0.00825, 0.0])
    assert steps[2].parameters.tan_beta == pytest.approx(-13e-6)
    assert "implausible" in steps[1].reasons[0]


def test_no_good_sample_yet_means_zero():
    steps = Compensator(hand_model()).run([0.0], [{"T1": math.nan, "T2": 25.0}], REF)
    assert steps[0].status == "hold" and steps[0].parameters.k0_mm == 0.0


def test_bad_model_json_is_one_line(tmp_path):
    path = tmp_path / "model.json"
    model = hand_model()
    del model["regressions"]
    path.write_text(json.dumps(model))
    with pytest.raises(
        ValueError, match=r"model.json: top level: 'regressions' is a required property"
    ):
        Compensator.from_json(path)


# ----------------------------------------------------------------- JSON evaluation vs estimator


def _training_data():
    rng = np.random.default_rng(3)
    rows, curves = [], []
    x = np.asarray(TARGETS)
    for r in range(3):
        for m in range(6):
            t1 = 28.0 + r + 0.8 * m + rng.normal(0, 0.05)
            t2 = 25.0 + 0.3 * r + 0.5 * m + rng.normal(0, 0.05)
            rows.append(
                {"run": f"R{r}", "measurement": m + 1, "time_min": 20.0 * m, "T1": t1, "T2": t2}
            )
            k = -300.0 + 13.0 * t1 + 0.4 * np.sin(t1)
            b = -11.0 * (0.5 * m + rng.normal(0, 0.05))
            curves.append(k * (x - x[0]) / 1000.0 + b)
    return pd.DataFrame(rows), pd.DataFrame(curves, columns=x)


@pytest.mark.parametrize("algorithm", ["mlr", "pls", "bayesridge", "svr", "gpr"])
def test_model_json_predicts_what_the_estimator_predicts(algorithm):
    X, Y = _training_data()
    grid = {"C": [10.0], "epsilon": [0.05], "gamma": ["scale"]}
    estimator = DecoupledAxisModel(("T1",), ("T2",), algorithm=algorithm, svr_grid=grid).fit(X, Y)
    comp = Compensator(
        json.loads(json.dumps(model_record(estimator, "decoupled", algorithm, X, HOLD)))
    )
    run = X[X["run"] == "R1"].reset_index(drop=True)
    predicted = estimator.predict(run)
    reference = {"T1": run.loc[0, "T1"], "T2": run.loc[0, "T2"]}
    for i in range(len(run)):
        now = {"T1": run.loc[i, "T1"], "T2": run.loc[i, "T2"]}
        np.testing.assert_allclose(
            comp.predicted_change(now, reference), predicted[i] - predicted[0], atol=1e-9
        )
    if algorithm == "mlr":
        # By hand: k on absolute T1 and b on T2's rise, numpy least squares on the
        # measurements' least-squares lines; a change of temperature moves the curve by
        # dk x + db.
        x_m = (np.asarray(TARGETS) - TARGETS[0]) / 1000.0
        k, b = np.polyfit(x_m, Y.to_numpy().T, 1)
        rise = X["T2"] - X.groupby("run")["T2"].transform("first")
        slope_k = np.linalg.lstsq(np.column_stack([np.ones(len(X)), X["T1"]]), k, rcond=None)[0][1]
        slope_b = np.linalg.lstsq(np.column_stack([np.ones(len(X)), rise]), b, rcond=None)[0][1]
        for i in range(len(run)):
            now = {"T1": run.loc[i, "T1"], "T2": run.loc[i, "T2"]}
            by_hand = (slope_k * (now["T1"] - reference["T1"]) * x_m
                       + slope_b * (now["T2"] - reference["T2"]))  # fmt: skip
            np.testing.assert_allclose(comp.predicted_change(now, reference), by_hand, atol=1e-9)


def test_pointwise_curve_gets_a_fitted_line_and_its_gap():
    X, Y = _training_data()
    Y = Y + 0.02 * ((np.asarray(TARGETS) - 315.0) ** 2 / 100.0) * (
        X["T2"].to_numpy()[:, None] - 25.0
    )  # a bow
    estimator = PointwiseAxisModel(("T2",), algorithm="mlr").fit(X, Y)
    comp = Compensator(json.loads(json.dumps(model_record(estimator, "pointwise", "mlr", X, HOLD))))
    p = comp.parameters({"T1": 30.0, "T2": 27.0}, {"T1": 29.0, "T2": 25.0})
    curve = np.asarray(p.curve_um)
    slope, intercept = np.polyfit(
        (np.asarray(TARGETS) - 185.0) / 1000.0, curve, 1
    )  # plain numpy line
    assert p.k0_mm * 1000.0 == pytest.approx(intercept, abs=1e-9)
    assert p.tan_beta * 1e6 == pytest.approx(slope, abs=1e-7)
    line = intercept + slope * (np.asarray(TARGETS) - 185.0) / 1000.0
    assert p.line_gap_um == pytest.approx(np.max(np.abs(curve - line)), abs=1e-9)
    assert p.line_gap_um > 0.1


# --------------------------------------------------------------------------- residual tables


def test_residuals_and_summary_by_hand():
    # Targets 0 and 100 mm. Measurement 1 (reference): up 0, 2; down 0, 0 -> pitch table 0, 1.
    # Measurement 2: up -1, 3; down -1, 1 -> drift up -1, 2; down -1, 0.
    # Compensation K0 = 0.001 mm, tan(beta) = -1e-5, P0 = 0: +1 um at 0 mm, 0 um at 100 mm.
    # After: up 0, 2; down 0, 0. Largest |.|: 2 before and after; E: 3 before, 2 after.
    zero = ControllerParameters(0.0, 0.0, 0.0, (0.0, 0.0), 0.0, False)
    comp = ControllerParameters(0.001, -1e-5, 0.0, (1.0, 0.0), 0.0, False)
    deviations = {
        1: {"+": np.array([0.0, 2.0]), "-": np.array([0.0, 0.0])},
        2: {"+": np.array([-1.0, 3.0]), "-": np.array([-1.0, 1.0])},
    }
    tables = held_out_tables(
        "E9",
        [Step(0.0, zero, "ok"), Step(600.0, comp, "ok")],
        [0.0, 10.0],
        deviations,
        [0.0, 100.0],
        [zero, comp],
    )
    res = tables["residuals"]
    m2 = res[res["measurement"] == 2].set_index(["direction", "position_mm"])
    assert m2.loc[("+", 100.0), "uncompensated_um"] == pytest.approx(2.0)
    assert m2.loc[("-", 0.0), "compensation_um"] == pytest.approx(1.0)
    assert m2["residual_um"].tolist() == pytest.approx([0.0, 2.0, 0.0, 0.0])
    summary = tables["summary"].set_index("measurement")
    assert summary.loc[2, "largest_abs_uncompensated_um"] == pytest.approx(2.0)
    assert summary.loc[2, "largest_abs_compensated_um"] == pytest.approx(2.0)
    assert summary.loc[2, "E_uncompensated_um"] == pytest.approx(3.0)
    assert summary.loc[2, "E_compensated_um"] == pytest.approx(2.0)
    # The reference measurement keeps its reversal: drift up 0, 1; down 0, -1 -> B = 2.
    iso = tables["iso230_2"].set_index(["measurement", "quantity"])
    assert iso.loc[(1, "B"), "uncompensated_um"] == pytest.approx(2.0)
    assert not iso.loc[(1, "R"), "computed"]
    siemens = tables["siemens_840d"].set_index(["measurement", "parameter"])
    assert siemens.loc[(2, "SD43910"), "value"] == pytest.approx(-1e-5)
    assert (
        tables["twincat"]
        .set_index(["measurement", "parameter"])
        .loc[(2, "P-AXIS-00273"), "register"]
        == 10
    )


def test_pass_deviations_split_the_passes_per_measurement():
    from thermaxis.compensation.held_out import pass_deviations
    from thermaxis.dataset.reader import RawRun

    def measurement(start, up, down):
        times = pd.date_range(start, periods=4, freq="5s")
        return pd.DataFrame(
            {
                "time": times,
                "position_mm": [0.0, 100.0, 100.0, 0.0],
                "error_um": [up[0], up[1], down[1], down[0]],
                "direction": ["+", "+", "-", "-"],
            }
        )

    raw = RawRun(
        run="R",
        sources={},
        measurements={
            "M1": measurement("2022-01-01T09:00", (0.0, 2.0), (0.5, 1.5)),
            "M2": measurement("2022-01-01T09:20", (1.0, 3.0), (1.5, 2.5)),
        },
    )
    out = pass_deviations(raw, [0.0, 100.0], max_missing_fraction=0.2)
    np.testing.assert_array_equal(out[1]["+"], [0.0, 2.0])
    np.testing.assert_array_equal(out[1]["-"], [0.5, 1.5])
    np.testing.assert_array_equal(out[2]["-"], [1.5, 2.5])


def test_held_out_accuracy_reads_a_candidates_loco_rows_and_the_configured_metrics_alike():
    from thermaxis.compensation.held_out import (
        candidate_accuracy,
        configured_accuracy,
        held_out_accuracy,
    )

    metrics = dict(rmse=1.5, max_abs=3.0, mae=1.0, residual_min=-3.0, residual_max=2.0)
    scores = pd.DataFrame(
        [
            {"kind": "loco", "fold": "10", "candidate": "a", "held_out": "10", **metrics},
            {"kind": "inner", "fold": "10", "candidate": "a", "held_out": "2", **metrics},
            {"kind": "loco", "fold": "10", "candidate": "b", "held_out": "10", **metrics},
        ]
    )
    table = pd.DataFrame(
        [
            {"fold": "R1", "approach": "decoupled", "algorithm": "mlr", "target": "k", **metrics},
            {"fold": "R1", "approach": "pointwise", "algorithm": "mlr", "target": "k", **metrics},
        ]
    )
    # Only candidate a's leave-one-condition-out row, of the whole error curve.
    assert held_out_accuracy(candidate_accuracy(scores, "a")) == [
        {"fold": "10", "target": "error", **metrics}
    ]
    assert held_out_accuracy(configured_accuracy(table, "decoupled", "mlr")) == [
        {"fold": "R1", "target": "k", **metrics}
    ]
    with pytest.raises(ValueError, match="no rows for approach 'decoupled' and algorithm 'svr'"):
        configured_accuracy(table, "decoupled", "svr")
