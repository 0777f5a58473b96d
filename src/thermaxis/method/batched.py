"""A fold's linear evaluations for many sets of sensitive points at once, through the numpy core.

:func:`thermaxis.method.folds.evaluate_configuration` fits one scikit-learn pipeline per
target (k, b, c2, c3, or each position) for one set of sensitive points.  For mlr, ridge
and pls at fixed strengths the same metrics follow from
:func:`thermaxis.method.linear.subset_fit`: every point set of a fold is solved from the
fold's Gram matrices in one call, and all held-out measurements are predicted in one
product.  The numbers are scikit-learn's to 1e-9 (relative; the core refits any ill-
conditioned set with scikit-learn itself), checked by ``tests/unit/test_batched.py``
against ``evaluate_configuration`` on the same data.

What is not batched stays with ``evaluate_configuration``: the kernel models, a searched
strength (its inner search), operating signals, and missing error readings (a position's
fit then skips rows, so its rows differ from the other positions').
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from thermaxis.config import ModelSettings
from thermaxis.method import linear
from thermaxis.method.decouple import compose_curve
from thermaxis.method.folds import _split_fold, sensor_columns
from thermaxis.method.metrics import prediction_metrics
from thermaxis.method.models import _KB_COLUMNS, _positions_of, decouple_rows, relative_temperatures

__all__ = ["batchable", "decoupled_metrics", "pointwise_metrics"]


def batchable(algorithm: str, model: ModelSettings, Y: pd.DataFrame) -> bool:
    """Whether ``evaluate_configuration``'s fits of ``algorithm`` can come from the linear core."""
    return (
        algorithm in linear.ALGORITHMS
        and model.search_grid_for(algorithm) is None
        and not model.signals
        and bool(np.isfinite(Y.to_numpy(dtype=float)).all())
    )


def _core_parameters(algorithm: str, model: ModelSettings) -> dict:
    """The configured strength (ridge ``alpha``, pls ``n_components``) as the core takes it."""
    return dict(model.params_for(algorithm) or {})


def _predict_sets(train, targets, test, sets, algorithm, parameters) -> dict[tuple, np.ndarray]:
    """Held-out predictions (rows, outputs) of each set of column indices, one core call per set size."""
    by_size: dict[int, list[tuple]] = {}
    for chosen in dict.fromkeys(sets):
        by_size.setdefault(len(chosen), []).append(chosen)
    out = {}
    for group in by_size.values():
        fit = linear.subset_fit(
            train, targets, np.array(group), algorithm, X_new=test, **parameters
        )
        out.update({chosen: fit.predictions[:, i, :] for i, chosen in enumerate(group)})
    return out


def _used(X: pd.DataFrame, named: Sequence[str]) -> list[str]:
    """The sensors the point sets use, in X's column order: the core needs only their columns
    (and only theirs must be finite, as for the one-by-one fits)."""
    named = set(named)
    return [s for s in sensor_columns(X) if s in named]


def _features(X: pd.DataFrame, sensors: list[str], temperature: str) -> np.ndarray:
    if temperature == "absolute":
        return X[sensors].to_numpy(dtype=float)
    return relative_temperatures(X, sensors).to_numpy(dtype=float)


def _frame(label: dict, rows: list[tuple[str, np.ndarray, np.ndarray]]) -> pd.DataFrame:
    return pd.DataFrame(
        [{**label, "target": target, **prediction_metrics(m, p)} for target, m, p in rows]
    )


def decoupled_metrics(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: str,
    algorithm: str,
    model: ModelSettings,
    degree: int,
    point_sets: Sequence[tuple[tuple[str, ...], tuple[str, ...]]],
) -> list[pd.DataFrame]:
    """``evaluate_configuration(..., "decoupled", ...).metrics`` for each (k points, b points).

    As :class:`thermaxis.method.models.DecoupledAxisModel`: k (and c2, c3) on the absolute
    temperatures of the k points, b on the rise of the b points since each run's first
    measurement, each coefficient its own standardised regression (Eq. 9).
    """
    X_train, Y_train, X_test, Y_test = _split_fold(X, Y, fold)
    sensors = _used(X, [s for pair in point_sets for points in pair for s in points])
    index = {s: i for i, s in enumerate(sensors)}
    positions = _positions_of(X_train, Y_train)
    kb_train = decouple_rows(X_train, Y_train, degree)
    kb_test = decouple_rows(X_test, Y_test, degree)
    shape = [_KB_COLUMNS["k"], *(_KB_COLUMNS[f"c{p}"] for p in range(2, degree + 1))]
    parameters = _core_parameters(algorithm, model)
    k_sets = [tuple(index[s] for s in k) for k, _ in point_sets]
    b_sets = [tuple(index[s] for s in b) for _, b in point_sets]
    shape_predicted = _predict_sets(
        _features(X_train, sensors, "absolute"),
        kb_train[shape].to_numpy(dtype=float),
        _features(X_test, sensors, "absolute"),
        k_sets,
        algorithm,
        parameters,
    )
    b_predicted = _predict_sets(
        _features(X_train, sensors, "relative"),
        kb_train[[_KB_COLUMNS["b"]]].to_numpy(dtype=float),
        _features(X_test, sensors, "relative"),
        b_sets,
        algorithm,
        parameters,
    )
    label = {"fold": fold, "approach": "decoupled", "algorithm": algorithm}
    measured = Y_test.to_numpy(dtype=float)
    frames = []
    for k_set, b_set in zip(k_sets, b_sets, strict=True):
        k_and_shape, b = shape_predicted[k_set], b_predicted[b_set][:, 0]
        # Eq. 7's ascending powers: b, k, c2, c3.
        curve = compose_curve(np.column_stack([b, k_and_shape]), positions, float(positions[0]))
        frames.append(
            _frame(
                label,
                [
                    ("k", kb_test[_KB_COLUMNS["k"]].to_numpy(), k_and_shape[:, 0]),
                    ("b", kb_test[_KB_COLUMNS["b"]].to_numpy(), b),
                    ("error", measured, curve),
                ],
            )
        )
    return frames


def pointwise_metrics(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: str,
    algorithm: str,
    model: ModelSettings,
    point_sets: Sequence[tuple[str, ...]],
) -> list[pd.DataFrame]:
    """``evaluate_configuration(..., "pointwise", ...).metrics`` for each set of points.

    As :class:`thermaxis.method.models.PointwiseAxisModel` (Eq. 8): each position's error
    its own standardised regression on the points' rise since each run's first measurement.
    """
    X_train, Y_train, X_test, Y_test = _split_fold(X, Y, fold)
    sensors = _used(X, [s for points in point_sets for s in points])
    index = {s: i for i, s in enumerate(sensors)}
    sets = [tuple(index[s] for s in points) for points in point_sets]
    predicted = _predict_sets(
        _features(X_train, sensors, "relative"),
        Y_train.to_numpy(dtype=float),
        _features(X_test, sensors, "relative"),
        sets,
        algorithm,
        _core_parameters(algorithm, model),
    )
    label = {"fold": fold, "approach": "pointwise", "algorithm": algorithm}
    measured = Y_test.to_numpy(dtype=float)
    return [_frame(label, [("error", measured, predicted[s])]) for s in sets]
