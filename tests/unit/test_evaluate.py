"""Tests of thermaxis.method.metrics: metrics by hand, folds by hand, fold isolation."""

from __future__ import annotations

import numpy as np
import pytest

from thermaxis.method.metrics import METRICS_CSV_COLUMNS, prediction_metrics


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
        {
            "rmse": np.sqrt(1.25),
            "max_abs": 2.0,
            "mae": 0.75,
            "residual_min": -1.0,
            "residual_max": 2.0,
        }
    )
    assert METRICS_CSV_COLUMNS[4:] == tuple(metrics)


def test_metrics_reject_bad_input():
    with pytest.raises(ValueError, match="shape"):
        prediction_metrics([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="NaN"):
        prediction_metrics([np.nan, 1.0], [1.0, np.nan])
