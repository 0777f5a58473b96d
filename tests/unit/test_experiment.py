"""The shared fold evaluation: no leakage into selection, the paper's fixed points recover Eq. 9."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS
from helpers.builders import synthetic_temperatures
from helpers.truth import EQ9_B, EQ9_K, POSITIONS, eq9_errors
from thermaxis.method.folds import (
    evaluate_configuration,
    fold_metrics,
    select_for_fold,
    selection_from_dict,
    selection_table,
    selection_to_dict,
)

SMALL_SVR = replace(
    DEFAULTS.models, svr_grid=(("C", (1.0, 10.0)), ("epsilon", (0.1,)), ("gamma", ("scale",)))
)


@pytest.fixture(scope="module")
def eq9_data():
    X = synthetic_temperatures()
    X.insert(2, "time_min", (X["measurement"] - 1) * 23.0)
    Y = eq9_errors(X).reset_index(drop=True)
    # Smooth, position-dependent noise so that selection has something to choose between.
    rng = np.random.default_rng(7)
    Y = Y + rng.normal(0.0, 0.05, Y.shape)
    return X.reset_index(drop=True), Y


def perturb_run(Y: pd.DataFrame, X: pd.DataFrame, run: str) -> pd.DataFrame:
    rng = np.random.default_rng(99)
    out = Y.copy()
    rows = (X["run"] == run).to_numpy()
    out.loc[rows] = out.loc[rows] + rng.normal(0.0, 5.0, (rows.sum(), Y.shape[1]))
    return out


def test_selection_ignores_the_held_out_run(eq9_data):
    X, Y = eq9_data
    settings = DEFAULTS.selection
    before = select_for_fold(X, Y, "E4", settings, 1)
    after = select_for_fold(X, perturb_run(Y, X, "E4"), "E4", settings, 1)
    assert selection_to_dict(before) == selection_to_dict(after)
    # ...but the paper's way (scope all) does look at it.
    all_before = select_for_fold(X, Y, "E4", replace(DEFAULTS.selection, scope="all"), 1)
    all_after = select_for_fold(
        X, perturb_run(Y, X, "E4"), "E4", replace(DEFAULTS.selection, scope="all"), 1
    )
    assert selection_to_dict(all_before) != selection_to_dict(all_after)


@pytest.mark.parametrize("approach", ["decoupled", "pointwise"])
@pytest.mark.parametrize("algorithm", ["mlr", "svr"])
def test_fold_models_ignore_the_held_out_errors(eq9_data, approach, algorithm):
    X, Y = eq9_data
    selection = select_for_fold(X, Y, "E2", DEFAULTS.selection, 1)
    a = evaluate_configuration(X, Y, "E2", approach, algorithm, selection, SMALL_SVR, 1)
    Y2 = perturb_run(Y, X, "E2")
    b = evaluate_configuration(
        X,
        Y2,
        "E2",
        approach,
        algorithm,
        select_for_fold(X, Y2, "E2", DEFAULTS.selection, 1),
        SMALL_SVR,
        1,
    )
    pd.testing.assert_frame_equal(a.coefficients, b.coefficients)
    np.testing.assert_array_equal(
        a.error_predictions["predicted"], b.error_predictions["predicted"]
    )
    assert not np.allclose(a.error_predictions["measured"], b.error_predictions["measured"])


@pytest.mark.parametrize(
    "approach, algorithm", [("decoupled", "gpr"), ("decoupled", "svr"), ("pointwise", "gpr")]
)
def test_fold_metrics_are_the_metrics_of_the_full_evaluation(eq9_data, approach, algorithm):
    X, Y = eq9_data
    selection = select_for_fold(X, Y, "E2", DEFAULTS.selection, 2)
    full = evaluate_configuration(X, Y, ["E2", "E3"], approach, algorithm, selection, SMALL_SVR, 2)
    metrics = fold_metrics(X, Y, ["E2", "E3"], approach, algorithm, selection, SMALL_SVR, 2)
    pd.testing.assert_frame_equal(metrics, full.metrics)
    # Run by run: each run's RMSE of its own residuals, in plain numpy.
    by_run = fold_metrics(X, Y, ["E2", "E3"], approach, algorithm, selection, SMALL_SVR, 2, True)
    errors = by_run[by_run["target"] == "error"].set_index("fold")
    table = full.error_predictions
    for run in ("E2", "E3"):
        rows = table[table["run"] == run]
        residual = rows["measured"].to_numpy() - rows["predicted"].to_numpy()
        assert errors.loc[run, "rmse"] == np.sqrt(np.mean(residual**2))
        assert errors.loc[run, "max_abs"] == np.abs(residual).max()


def test_fixed_paper_points_recover_eq9(eq9_data):
    X, _ = eq9_data
    Y = eq9_errors(X).reset_index(drop=True)  # exact, noise-free
    fixed = (
        ("b", ("T2", "T7", "T11")),
        ("k", ("T1", "T6", "T12")),
        ("pointwise", ("T1", "T11", "T12")),
    )
    selection = select_for_fold(
        X, Y, "E4", replace(DEFAULTS.selection, method="fixed", fixed=fixed), 1
    )
    assert selection.k_sensors == ("T1", "T6", "T12") and selection.b_sensors == ("T2", "T7", "T11")
    result = evaluate_configuration(X, Y, "E4", "decoupled", "mlr", selection, DEFAULTS.models, 1)
    coef = result.coefficients.set_index(["target", "term"])["value"]
    for term, value in EQ9_K.items():
        assert coef[("k", term)] == pytest.approx(value, abs=1e-6)
    for term, value in EQ9_B.items():
        assert coef[("b", term)] == pytest.approx(value, abs=1e-6)
    metrics = result.metrics.set_index("target")
    assert metrics.loc["error", "max_abs"] < 1e-6
    assert list(result.metrics["target"]) == ["k", "b", "error"]


def test_fixed_selection_names_an_unknown_sensor(eq9_data):
    X, Y = eq9_data
    fixed = (("b", ("T2",)), ("k", ("T99",)), ("pointwise", ("T1",)))
    with pytest.raises(ValueError) as refused:
        select_for_fold(X, Y, "E4", replace(DEFAULTS.selection, method="fixed", fixed=fixed), 1)
    assert str(refused.value) == (
        "config selection.fixed.k: sensor 'T99' is not a candidate; expected one of T1, T2, T3, "
        "T4, T5, T6, T7, T8, T9, T10, T11, T12 (a sensor that is not in dataset.yaml, or that "
        "lacks a reading in some measurement, is none)"
    )


def test_selection_round_trips_through_json_and_tables(eq9_data):
    X, Y = eq9_data
    selection = select_for_fold(X, Y, "E1", replace(DEFAULTS.selection, n_clusters=4), 1)
    again = selection_from_dict(selection_to_dict(selection))
    assert selection_to_dict(again) == selection_to_dict(selection)
    table = selection_table(selection)
    assert set(table["target"]) == {"k", "b", "error", "pointwise_common"}
    assert table.loc[table["target"] == "k", "cluster"].nunique() == 4
    assert set(table.loc[(table["target"] == "k") & table["selected"], "sensor"]) == set(
        selection.k_sensors
    )
    assert table.loc[table["target"] == "error", "position_mm"].nunique() == len(POSITIONS)
    assert len(selection.pointwise) == 3


def test_single_position_runs_pointwise_only(eq9_data):
    X, Y = eq9_data
    Y1 = Y[[Y.columns[0]]]
    selection = select_for_fold(X, Y1, "E3", DEFAULTS.selection, 1, decoupled=False)
    assert selection.k is None and selection.b is None and len(selection.pointwise) == 3
    result = evaluate_configuration(X, Y1, "E3", "pointwise", "mlr", selection, DEFAULTS.models, 1)
    assert list(result.metrics["target"]) == ["error"]
    assert len(result.error_predictions) == 8
