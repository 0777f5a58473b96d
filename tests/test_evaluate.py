"""Tests of thermaxis.evaluate: metrics by hand, folds by hand, fold isolation."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.base import BaseEstimator, RegressorMixin

from thermaxis.evaluate import METRICS_CSV_COLUMNS, loco_folds, loco_predict, prediction_metrics


def test_metrics_match_hand_computation_and_skip_nan_pairs():
    measured = [1.0, 2.0, 3.0, np.nan, 4.0]
    predicted = [1.5, 1.0, 3.0, 7.0, np.nan]
    # residuals measured - predicted: -0.5, 1.0, 0.0 (the NaN pairs drop out)
    metrics = prediction_metrics(measured, predicted)
    assert metrics["rmse"] == pytest.approx(np.sqrt(1.25 / 3))
    assert metrics["max_abs"] == pytest.approx(1.0)
    assert metrics["mae"] == pytest.approx(0.5)
    assert metrics["residual_min"] == pytest.approx(-0.5)
    assert metrics["residual_max"] == pytest.approx(1.0)


def test_metrics_pool_all_cells_of_error_curves():
    measured = np.array([[0.0, 2.0], [1.0, -1.0]])
    predicted = np.array([[1.0, 2.0], [-1.0, -1.0]])
    # residuals -1, 0, 2, 0: rmse sqrt(5/4), mae 3/4
    metrics = prediction_metrics(measured, predicted)
    assert metrics == pytest.approx(
        {"rmse": np.sqrt(1.25), "max_abs": 2.0, "mae": 0.75, "residual_min": -1.0, "residual_max": 2.0}
    )
    assert METRICS_CSV_COLUMNS[4:] == tuple(metrics)


def test_metrics_reject_bad_input():
    with pytest.raises(ValueError, match="shape"):
        prediction_metrics([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="NaN"):
        prediction_metrics([np.nan, 1.0], [1.0, np.nan])


def test_loco_folds_one_per_run_sorted_with_positional_indices():
    X = pd.DataFrame(
        {"run": ["E2", "E1", "E2", "E3", "E1"], "measurement": [1, 1, 2, 1, 2]}, index=[9, 8, 7, 6, 5]
    )
    folds = loco_folds(X)
    assert [f[0] for f in folds] == ["E1", "E2", "E3"]
    expected = {"E1": ([0, 2, 3], [1, 4]), "E2": ([1, 3, 4], [0, 2]), "E3": ([0, 1, 2, 4], [3])}
    for fold, train, test in folds:
        assert train.tolist() == expected[fold][0]
        assert test.tolist() == expected[fold][1]


def test_loco_folds_need_two_runs():
    with pytest.raises(ValueError, match="at least 2 runs"):
        loco_folds(pd.DataFrame({"run": ["E1", "E1"], "measurement": [1, 2]}))


class _RunRecorder(RegressorMixin, BaseEstimator):
    """Predicts the mean training target; remembers which runs it saw."""

    def fit(self, X, Y):
        self.fit_runs_ = sorted(set(X["run"]))
        self.mean_ = Y.to_numpy().mean(axis=0)
        return self

    def predict(self, X):
        self.predict_runs_ = sorted(set(X["run"]))
        return np.tile(self.mean_, (len(X), 1))


def test_loco_predict_fits_without_and_predicts_only_the_held_out_run():
    X = pd.DataFrame({"run": ["A", "A", "B", "B", "C"], "measurement": [1, 2, 1, 2, 1]})
    Y = pd.DataFrame({185.0: [1.0, 2.0, 10.0, 20.0, 100.0]})
    results = loco_predict(_RunRecorder(), X, Y)
    assert [r.fold for r in results] == ["A", "B", "C"]
    for r in results:
        assert r.fold not in r.model.fit_runs_
        assert r.model.predict_runs_ == [r.fold]
    # held-out A: mean of B and C rows = (10 + 20 + 100) / 3
    np.testing.assert_allclose(results[0].predicted, [[130 / 3], [130 / 3]])
    assert results[2].test.tolist() == [4]
