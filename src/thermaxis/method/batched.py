"""A fold's linear evaluations for many sets of sensitive points at once, through the numpy core.

:func:`thermaxis.method.folds.evaluate_configuration` fits one scikit-learn pipeline per
target (k, b, c2, c3, or each position) for one set of sensitive points.  For mlr, ridge
and pls at fixed strengths the same metrics follow from
:func:`thermaxis.method.linear.subset_fit`: every point set of a fold is solved from the
fold's Gram matrices in one call, and all held-out measurements are predicted in one
product.  The numbers are scikit-learn's to 1e-9 (relative; the core refits any ill-
conditioned set with scikit-learn itself), checked by ``tests/unit/test_batched.py``
against ``evaluate_configuration`` on the same data.

A searched strength (ridge ``alpha``, pls ``n_components``, config ``models.searched``)
is chosen as :func:`thermaxis.method.search.fit_by_group_search` chooses it: the same
inner split of the training runs, RMSE of each held-out group, the first best grid point;
every grid point's held-out predictions come from one leave-one-group-out call of the
core (:func:`thermaxis.method.linear.loco_fit`, the Gram matrices downdated by each
group), for every output at once; a ridge's whole strength grid comes from one SVD per
inner group (:func:`_ridge_inner_rmse`).

Operating signals (``models.signals``) join every point set as logged, after the
temperatures, as the estimators add them.  What is not batched stays with
``evaluate_configuration``: the kernel models and lasso, and missing error readings (a position's fit then skips rows, so its
rows differ from the other positions').
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from sklearn.model_selection import ParameterGrid

from thermaxis.config import ModelSettings
from thermaxis.method import linear
from thermaxis.method.decouple import compose_curve
from thermaxis.method.estimators import _features, _positions_of
from thermaxis.method.features import KB_COLUMNS as _KB_COLUMNS
from thermaxis.method.features import decouple_rows
from thermaxis.method.folds import _split_fold, fold_name, sensor_columns
from thermaxis.method.metrics import metric_frame
from thermaxis.method.regressors import pls_fits
from thermaxis.method.search import (
    inner_group_splitter,
    ridge_grid_predictions,
    standardised_split,
)

__all__ = [
    "batchable",
    "decoupled_metrics",
    "pointwise_metrics",
    "decoupled_curves",
    "pointwise_curves",
]


def batchable(algorithm: str, model: ModelSettings, Y: pd.DataFrame) -> bool:
    """Whether ``evaluate_configuration``'s fits of ``algorithm`` can come from the linear core."""
    return algorithm in linear.ALGORITHMS and bool(np.isfinite(Y.to_numpy(dtype=float)).all())


def _core(parameters: dict) -> dict:
    """A strength as the core takes it (pls components as the integer scikit-learn gets)."""
    return {k: int(v) if k == "n_components" else float(v) for k, v in parameters.items()}


class _Fitter:
    """The fits of one fold's training rows: fixed strengths, or each output's searched one."""

    def __init__(self, algorithm: str, model: ModelSettings, runs: np.ndarray):
        self.algorithm, self.runs = algorithm, runs
        grid = model.search_grid_for(algorithm)
        self.grid = None if grid is None else [_core(p) for p in ParameterGrid(grid)]
        self.fixed = _core(model.params_for(algorithm) or {})
        self.inner = model.inner_search

    def predict_sets(self, train, targets, test, sets) -> dict[tuple, np.ndarray]:
        """Held-out predictions (rows, outputs) of each set of column indices."""
        if self.grid is None:
            return _subset_predictions(train, targets, test, sets, self.algorithm, self.fixed)
        return {
            chosen: self._searched(train[:, list(chosen)], targets, test[:, list(chosen)])
            for chosen in dict.fromkeys(sets)
        }

    def _searched(self, train, targets, test) -> np.ndarray:
        """Each output's grid point chosen by the inner search, then refitted on every row."""
        chosen = np.zeros(targets.shape[1], dtype=int)  # one group: the first grid point
        if np.unique(self.runs).size >= 2:
            splitter = inner_group_splitter(self.runs, *self.inner)
            held = np.empty(self.runs.size, dtype=int)
            for g, (_, rows) in enumerate(splitter.split(train, targets[:, 0], self.runs)):
                held[rows] = g
            if self.algorithm == "ridge":
                scores = _ridge_inner_rmse(train, targets, held, [p["alpha"] for p in self.grid])
            else:
                scores = np.array([self._inner_rmse(train, targets, held, p) for p in self.grid])
            # The first best grid point, NaN last, as GridSearchCV ranks them.
            chosen = np.argmin(np.where(np.isnan(scores), np.inf, scores), axis=0)
        out = np.empty((test.shape[0], targets.shape[1]))
        every_column = tuple(range(train.shape[1]))
        for c in np.unique(chosen):
            outputs = chosen == c
            out[:, outputs] = _subset_predictions(
                train, targets[:, outputs], test, [every_column], self.algorithm, self.grid[c]
            )[every_column]
        return out

    def _inner_rmse(self, train, targets, held, parameters) -> np.ndarray:
        """Mean over the inner groups of each output's held-out RMSE (fit_by_group_search's score)."""
        groups = np.unique(held)
        if self.algorithm == "pls" and not all(
            pls_fits(parameters["n_components"], np.count_nonzero(held != g), train.shape[1])
            for g in groups
        ):
            return np.full(targets.shape[1], np.nan)
        _, fit = linear.loco_fit(train, targets, held, None, self.algorithm, **parameters)
        residual = targets - fit.predictions[:, 0, :]
        rmse = [np.sqrt(np.mean(residual[held == g] ** 2, axis=0)) for g in groups]
        return np.mean(rmse, axis=0)


def _ridge_inner_rmse(train, targets, held, alphas) -> np.ndarray:
    """``_inner_rmse`` of ridge at every strength: (strengths, outputs).

    Each inner split is standardised as the pipeline does
    (:func:`thermaxis.method.search.standardised_split`) and solved for the whole strength
    grid and every output from one SVD
    (:func:`thermaxis.method.search.ridge_grid_predictions`), instead of one eigensystem
    per strength, and one scikit-learn refit per strength where that system was ill-
    conditioned (many lagged inputs, few training rows).
    """
    groups = np.unique(held)
    rmse = np.empty((len(groups), len(alphas), targets.shape[1]))
    for i, group in enumerate(groups):
        fit, out = held != group, held == group
        X_fit, X_out, y_fit, y_mean, y_scale = standardised_split(train, targets, fit, out)
        for a, values in enumerate(ridge_grid_predictions(X_fit, y_fit, X_out, alphas)):
            predicted = values * y_scale + y_mean
            rmse[i, a] = np.sqrt(np.mean((targets[out] - predicted) ** 2, axis=0))
    return rmse.mean(axis=0)


def _subset_predictions(
    train, targets, test, sets, algorithm, parameters
) -> dict[tuple, np.ndarray]:
    """Held-out predictions (rows, outputs) of each set of column indices, one core call per set size."""
    by_size: dict[int, list[tuple]] = {}
    for chosen in dict.fromkeys(tuple(int(i) for i in c) for c in sets):
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


def _columns(index: dict, points, signals) -> tuple[int, ...]:
    """A point set's columns of :func:`_features`: its sensors, then every signal."""
    return (*(index[s] for s in points), *range(len(index), len(index) + len(signals)))


def _decoupled_fits(X, Y, fold, algorithm, model, degree, point_sets):
    """The held-out rows of ``fold`` and, per (k points, b points), the predicted slope and
    shape coefficients, intercept and error curves: what :func:`decoupled_metrics` scores."""
    X_train, Y_train, X_test, Y_test = _split_fold(X, Y, fold)
    sensors = _used(X, [s for pair in point_sets for points in pair for s in points])
    index = {s: i for i, s in enumerate(sensors)}
    positions = _positions_of(X_train, Y_train)
    kb_train = decouple_rows(X_train, Y_train, degree)
    shape = [_KB_COLUMNS["k"], *(_KB_COLUMNS[f"c{p}"] for p in range(2, degree + 1))]
    fitter = _Fitter(algorithm, model, X_train["run"].to_numpy())
    signals = model.signals
    k_sets = [_columns(index, k, signals) for k, _ in point_sets]
    b_sets = [_columns(index, b, signals) for _, b in point_sets]
    shape_predicted = fitter.predict_sets(
        _features(X_train, sensors, "absolute", signals),
        kb_train[shape].to_numpy(dtype=float),
        _features(X_test, sensors, "absolute", signals),
        k_sets,
    )
    b_predicted = fitter.predict_sets(
        _features(X_train, sensors, "relative", signals),
        kb_train[[_KB_COLUMNS["b"]]].to_numpy(dtype=float),
        _features(X_test, sensors, "relative", signals),
        b_sets,
    )
    fits = []
    for k_set, b_set in zip(k_sets, b_sets, strict=True):
        k_and_shape, b = shape_predicted[k_set], b_predicted[b_set][:, 0]
        # Eq. 7's ascending powers: b, k, c2, c3.
        curve = compose_curve(np.column_stack([b, k_and_shape]), positions, float(positions[0]))
        fits.append((k_and_shape, b, curve))
    return X_test, Y_test, fits


def decoupled_metrics(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: str,
    algorithm: str,
    model: ModelSettings,
    degree: int,
    point_sets: Sequence[tuple[tuple[str, ...], tuple[str, ...]]],
    per_run: bool = False,
) -> list[pd.DataFrame]:
    """``evaluate_configuration(..., "decoupled", ...).metrics`` for each (k points, b points).

    ``per_run``: a fold of several runs (:func:`thermaxis.method.folds.held_out_runs`) is
    scored run by run, each row's ``fold`` its run, from one fit.

    As :class:`thermaxis.method.estimators.DecoupledAxisModel`: k (and c2, c3) on the absolute
    temperatures of the k points, b on the rise of the b points since each run's first
    measurement, each coefficient its own standardised regression (Eq. 9).
    """
    X_test, Y_test, fits = _decoupled_fits(X, Y, fold, algorithm, model, degree, point_sets)
    kb_test = decouple_rows(X_test, Y_test, degree)
    label = {"fold": fold_name(fold), "approach": "decoupled", "algorithm": algorithm}
    measured = Y_test.to_numpy(dtype=float)
    return [
        metric_frame(
            label,
            [
                ("k", kb_test[_KB_COLUMNS["k"]].to_numpy(), k_and_shape[:, 0]),
                ("b", kb_test[_KB_COLUMNS["b"]].to_numpy(), b),
                ("error", measured, curve),
            ],
            X_test["run"].to_numpy() if per_run else None,
        )
        for k_and_shape, b, curve in fits
    ]


def decoupled_curves(X, Y, fold, algorithm, model, degree, k_points, b_points) -> np.ndarray:
    """The held-out error curves (rows of ``fold`` in X's order, positions) of one
    decoupled fit, as :func:`decoupled_metrics` scores them."""
    _, _, fits = _decoupled_fits(X, Y, fold, algorithm, model, degree, [(k_points, b_points)])
    return fits[0][2]


def _pointwise_fits(X, Y, fold, algorithm, model, point_sets):
    """The held-out rows of ``fold`` and each point set's predicted error curves."""
    X_train, Y_train, X_test, Y_test = _split_fold(X, Y, fold)
    sensors = _used(X, [s for points in point_sets for s in points])
    index = {s: i for i, s in enumerate(sensors)}
    signals = model.signals
    sets = [_columns(index, points, signals) for points in point_sets]
    predicted = _Fitter(algorithm, model, X_train["run"].to_numpy()).predict_sets(
        _features(X_train, sensors, "relative", signals),
        Y_train.to_numpy(dtype=float),
        _features(X_test, sensors, "relative", signals),
        sets,
    )
    return X_test, Y_test, [predicted[s] for s in sets]


def pointwise_metrics(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: str,
    algorithm: str,
    model: ModelSettings,
    point_sets: Sequence[tuple[str, ...]],
    per_run: bool = False,
) -> list[pd.DataFrame]:
    """``evaluate_configuration(..., "pointwise", ...).metrics`` for each set of points
    (``per_run`` as for :func:`decoupled_metrics`).

    As :class:`thermaxis.method.estimators.PointwiseAxisModel` (Eq. 8): each position's error
    its own standardised regression on the points' rise since each run's first measurement.
    """
    X_test, Y_test, curves = _pointwise_fits(X, Y, fold, algorithm, model, point_sets)
    label = {"fold": fold_name(fold), "approach": "pointwise", "algorithm": algorithm}
    measured = Y_test.to_numpy(dtype=float)
    runs = X_test["run"].to_numpy() if per_run else None
    return [metric_frame(label, [("error", measured, curve)], runs) for curve in curves]


def pointwise_curves(X, Y, fold, algorithm, model, points) -> np.ndarray:
    """The held-out error curves (rows of ``fold`` in X's order, positions) of one
    point-by-point fit, as :func:`pointwise_metrics` scores them."""
    return _pointwise_fits(X, Y, fold, algorithm, model, [points])[2][0]
