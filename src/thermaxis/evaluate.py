"""Leave-one-condition-out evaluation and the prediction metrics of Tables 4, 7 and 8.

Every condition (run) is held out in turn; the model is fitted on the others and predicts
the held-out run from that run's temperatures alone.  The fold id is the held-out run's id.

Residuals are ``measured - predicted``: what the model misses, so a positive residual
means the axis erred more (in the positive sense) than predicted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from sklearn.base import clone

__all__ = [
    "METRIC_COLUMNS",
    "METRICS_CSV_COLUMNS",
    "LocoPrediction",
    "prediction_metrics",
    "loco_folds",
    "loco_predict",
]

METRIC_COLUMNS = ("rmse", "max_abs", "mae", "residual_min", "residual_max")
METRICS_CSV_COLUMNS = ("fold", "approach", "algorithm", "target", *METRIC_COLUMNS)


def prediction_metrics(measured, predicted) -> dict[str, float]:
    """Error statistics of a prediction, ignoring pairs where either value is NaN.

    Parameters
    ----------
    measured, predicted : array-like of equal shape
        Any shape (e.g. rows x positions for error curves); compared element by element.

    Returns
    -------
    dict
        ``rmse``, ``max_abs`` (largest absolute residual), ``mae``, ``residual_min``,
        ``residual_max``, with residual = measured - predicted.

    Raises
    ------
    ValueError
        If the shapes differ or no pair has both values.
    """
    measured = np.asarray(measured, dtype=float)
    predicted = np.asarray(predicted, dtype=float)
    if measured.shape != predicted.shape:
        raise ValueError(
            f"measured has shape {measured.shape} but predicted {predicted.shape}; expected equal shapes"
        )
    residual = (measured - predicted).ravel()
    residual = residual[np.isfinite(residual)]
    if residual.size == 0:
        raise ValueError("no pair of measured and predicted values without NaN; cannot compute metrics")
    absolute = np.abs(residual)
    return {
        "rmse": float(np.sqrt(np.mean(residual**2))),
        "max_abs": float(absolute.max()),
        "mae": float(absolute.mean()),
        "residual_min": float(residual.min()),
        "residual_max": float(residual.max()),
    }


def loco_folds(X: pd.DataFrame) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Leave-one-condition-out folds over the runs of X.

    Parameters
    ----------
    X : DataFrame
        Must have a ``run`` column.

    Returns
    -------
    list of (fold, train, test)
        One fold per run, sorted by run id; ``fold`` is the held-out run id, ``train`` and
        ``test`` are positional row indices (for ``.iloc``) of the other runs and of the
        held-out run.
    """
    if "run" not in X.columns:
        raise ValueError("X lacks the 'run' column needed to form leave-one-condition-out folds")
    runs = X["run"].astype(str).to_numpy()
    unique = sorted(set(runs))
    if len(unique) < 2:
        raise ValueError(f"leave-one-condition-out needs at least 2 runs, got {len(unique)}")
    return [(run, np.flatnonzero(runs != run), np.flatnonzero(runs == run)) for run in unique]


@dataclass(frozen=True)
class LocoPrediction:
    """One fold: the held-out run, the model fitted without it, and its prediction."""

    fold: str
    test: np.ndarray
    model: object
    predicted: np.ndarray


def loco_predict(estimator, X: pd.DataFrame, Y: pd.DataFrame) -> list[LocoPrediction]:
    """Fit a fresh clone of ``estimator`` per fold and predict the held-out run.

    The clone sees only the training runs' rows of X and Y; the held-out run's rows of X
    (its temperatures) are all that reaches ``predict``.
    """
    results = []
    for fold, train, test in loco_folds(X):
        model = clone(estimator).fit(X.iloc[train], Y.iloc[train])
        results.append(LocoPrediction(fold, test, model, np.asarray(model.predict(X.iloc[test]))))
    return results
