"""A chronological protocol: fit on the start of a record, score a later block.

This is how the FL_THERMAL authors evaluate their models: train on the first part of
one long record, test on a later block. Every choice (the inputs, their time
constants, the ridge strength) is made inside the training part by scikit-learn's
``TimeSeriesSplit``, whose expanding windows never validate on data older than what
they fit; the test block reaches nothing but the final score.

Inputs are the logged temperatures, optionally the operating signals (and their
squares), first-order lags of all of them (:func:`thermaxis.method.inputs.lag_filter`)
and their rates of change over a window (:func:`thermaxis.method.inputs.rate_of_change`),
all causal: a value at a sample depends only on the samples up to it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from sklearn.model_selection import TimeSeriesSplit

from thermaxis.method.inputs import lag_filter, rate_of_change
from thermaxis.method.metrics import prediction_metrics
from thermaxis.method.regressors import make_regressor

__all__ = ["INPUT_KINDS", "InputSet", "block", "input_sets", "choose", "evaluate_channel"]

# Nested: each kind adds to the previous one.
INPUT_KINDS = ("temperatures", "signals", "signal_squares")


@dataclass(frozen=True)
class InputSet:
    """One candidate set of input columns: its kind, lag time constants, rate windows and the matrix."""

    kind: str
    lags_min: tuple[float, ...]
    rates_min: tuple[float, ...]
    names: tuple[str, ...]
    values: np.ndarray

    @property
    def label(self) -> str:
        lags = ", ".join(f"{m:g}" for m in self.lags_min) or "none"
        rates = ", ".join(f"{m:g}" for m in self.rates_min) or "none"
        return f"{self.kind}; lags (min): {lags}; rates (min): {rates}"


def block(n: int, fractions: Sequence[float]) -> slice:
    """The rows of fractions ``[lo, hi)`` of an ``n``-sample record (floor of each bound)."""
    lo, hi = (int(np.floor(f * n)) for f in fractions)
    if not 0 <= lo < hi <= n:
        raise ValueError(f"block {list(fractions)} of a {n}-sample record is empty or outside it")
    return slice(lo, hi)


def _base(kind: str, temperatures: Mapping[str, np.ndarray], signals: Mapping[str, np.ndarray]):
    columns = dict(temperatures)
    if kind in ("signals", "signal_squares"):
        columns.update(signals)
    if kind == "signal_squares":
        columns.update({f"{name}^2": values**2 for name, values in signals.items()})
    return columns


def input_sets(
    t_s: np.ndarray,
    temperatures: Mapping[str, np.ndarray],
    signals: Mapping[str, np.ndarray],
    kinds: Sequence[str],
    lag_sets_min: Sequence[Sequence[float]],
    rate_sets_min: Sequence[Sequence[float]] = ((),),
) -> list[InputSet]:
    """Every candidate input set (kind x lag set x rate set), simplest first (fewer columns first)."""
    unknown = [k for k in kinds if k not in INPUT_KINDS]
    if unknown:
        raise ValueError(
            f"unknown input kind {unknown[0]!r}; expected one of {', '.join(INPUT_KINDS)}"
        )
    if not signals and any(k != "temperatures" for k in kinds):
        kinds = ["temperatures"]
    derived: dict[tuple[str, str, float], np.ndarray] = {}

    def column(name: str, values: np.ndarray, how: str, minutes: float) -> np.ndarray:
        key = (name, how, float(minutes))
        if key not in derived:
            make = lag_filter if how == "lag" else rate_of_change
            derived[key] = make(t_s, values, 60.0 * float(minutes))
        return derived[key]

    sets = []
    for kind in dict.fromkeys(kinds):
        base = _base(kind, temperatures, signals)
        for lags in lag_sets_min:
            for rates in rate_sets_min:
                names, columns = list(base), list(base.values())
                for how, durations in (("lag", lags), ("rate", rates)):
                    for minutes in durations:
                        for name, values in base.items():
                            names.append(f"{name}@{how}{minutes:g}min")
                            columns.append(column(name, values, how, minutes))
                sets.append(
                    InputSet(
                        kind,
                        tuple(float(m) for m in lags),
                        tuple(float(m) for m in rates),
                        tuple(names),
                        np.column_stack(columns),
                    )
                )
    return sorted(sets, key=lambda s: len(s.names))


def _ridge_path_mae(
    inputs: np.ndarray, y: np.ndarray, fit: np.ndarray, score: np.ndarray, alphas: np.ndarray
):
    """Validation MAE of the ridge pipeline at every alpha, from one eigendecomposition.

    The pipeline standardises the inputs on the fitted rows (population deviation, a
    constant column left unscaled, as StandardScaler does) and centres the target
    (its scaling does not change a ridge prediction). On standardised inputs with
    X'X = V diag(l) V', the ridge weights are V diag(1 / (l + alpha)) V' X'y, so all
    strengths cost one decomposition. The final model is refitted by scikit-learn.
    """
    X = inputs[fit]
    mean, scale = X.mean(axis=0), X.std(axis=0)
    scale[scale == 0] = 1.0
    Xs = (X - mean) / scale
    y_mean = y[fit].mean()
    eigenvalues, V = np.linalg.eigh(Xs.T @ Xs)
    projected = V.T @ (Xs.T @ (y[fit] - y_mean))
    rotated = ((inputs[score] - mean) / scale) @ V
    predictions = rotated @ (projected[:, None] / (eigenvalues[:, None] + alphas[None, :])) + y_mean
    return np.mean(np.abs(predictions - y[score][:, None]), axis=0)


def choose(
    sets: Sequence[InputSet], y: np.ndarray, train: slice, alphas: Sequence[float], n_splits: int
):
    """The (input set, alpha) of least mean validation MAE over the training part's time-series splits.

    Ties (to 1e-12 relative) go to the simpler candidate: fewer columns, then the
    stronger ridge. Returns (input set, alpha, validation MAE).
    """
    rows = np.arange(train.start, train.stop)
    splits = [(rows[a], rows[b]) for a, b in TimeSeriesSplit(n_splits=n_splits).split(rows)]
    strengths = np.array(sorted(alphas, reverse=True), dtype=float)  # strongest first
    best = None
    for inputs in sets:  # simplest first
        scores = np.mean(
            [_ridge_path_mae(inputs.values, y, fit, val, strengths) for fit, val in splits], axis=0
        )
        for alpha, score in zip(strengths, scores, strict=False):
            if best is None or score < best[2] * (1 - 1e-12):
                best = (inputs, float(alpha), float(score))
    return best


def evaluate_channel(sets, y: np.ndarray, train: slice, test: slice, alphas, n_splits: int) -> dict:
    """Choose on the training part, refit on all of it, score the test block."""
    inputs, alpha, validation = choose(sets, y, train, alphas, n_splits)
    # Ridge is deterministic: the seed is only make_regressor's uniform signature.
    model = make_regressor("ridge", {"alpha": alpha}, random_state=0).fit(
        inputs.values[train], y[train]
    )
    metrics = prediction_metrics(y[test], model.predict(inputs.values[test]))
    return {
        "inputs": inputs.label,
        "n_inputs": len(inputs.names),
        "ridge_alpha": alpha,
        "validation_mae_um": validation,
        "mae_um": metrics["mae"],
        "rmse_um": metrics["rmse"],
        "max_abs_um": metrics["max_abs"],
    }
