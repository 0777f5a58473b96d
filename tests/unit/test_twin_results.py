"""thermaxis.twin.results: the held-out slope RMSE the calibration aims at, by hand."""

from __future__ import annotations

import numpy as np
import pytest

from thermaxis.twin.results import FoldData, held_out_slope_rmse, result_targets

SENSORS = ("T1", "T2", "T6", "T7", "T11", "T12")


def _fold(train: np.ndarray, test: np.ndarray, k: np.ndarray, test_k: np.ndarray) -> FoldData:
    empty = np.zeros((len(train), 1))
    return FoldData(
        sensors=SENSORS,
        positions_mm=np.array([185.0, 445.0]),
        absolute=train,
        relative=train - train[:1],
        k=k,
        b=np.zeros(len(train)),
        curves=empty,
        test_absolute=test,
        test_relative=test - test[:1],
        test_curves=np.zeros((len(test), 1)),
        test_k=test_k,
    )


def test_the_slope_rmse_is_the_held_out_runs_departure_from_an_exact_linear_law():
    # k = 1 + 2 T1 - T6 + 0.5 T12 exactly on the training rows, so MLR on Table 6's
    # k-points (T1, T6, T12) recovers it; the held-out k departs by +0.3 and -0.4:
    # RMSE sqrt((0.09 + 0.16) / 2) = 0.353553...
    rng = np.random.default_rng(3)
    train = rng.normal(30.0, 1.0, size=(8, len(SENSORS)))
    test = rng.normal(30.0, 1.0, size=(2, len(SENSORS)))

    def law(t):
        return 1.0 + 2.0 * t[:, 0] - t[:, 2] + 0.5 * t[:, 5]

    targets = result_targets()
    assert targets.k_points == ("T1", "T6", "T12")
    data = _fold(train, test, law(train), law(test) + np.array([0.3, -0.4]))
    assert held_out_slope_rmse(data, targets) == pytest.approx(np.sqrt(0.125), abs=1e-9)


def test_the_slope_target_is_table_7s_k_rmse():
    assert result_targets().slope_rmse_um_per_m == 2.6
