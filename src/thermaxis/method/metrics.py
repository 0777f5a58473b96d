"""The prediction metrics of Tables 4, 7 and 8 (the folds themselves: :mod:`thermaxis.method.folds`).

Residuals are ``measured - predicted``: what the model misses, so a positive residual
means the axis erred more (in the positive sense) than predicted.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = [
    "METRIC_COLUMNS",
    "METRICS_CSV_COLUMNS",
    "prediction_metrics",
    "metric_frame",
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
        raise ValueError(
            "no pair of measured and predicted values without NaN; cannot compute metrics"
        )
    absolute = np.abs(residual)
    return {
        "rmse": float(np.sqrt(np.mean(residual**2))),
        "max_abs": float(absolute.max()),
        "mae": float(absolute.mean()),
        "residual_min": float(residual.min()),
        "residual_max": float(residual.max()),
    }


def metric_frame(label: dict, compared, runs=None) -> pd.DataFrame:
    """One row of :func:`prediction_metrics` per (target, measured, predicted) of ``compared``,
    after ``label``'s columns; with ``runs`` (each compared row's run), one per run and
    target, ``fold`` the run, in the order the runs first appear."""
    if runs is None:
        return pd.DataFrame(
            [{**label, "target": target, **prediction_metrics(m, p)} for target, m, p in compared]
        )
    return pd.concat(
        [metric_frame({**label, "fold": run}, [(t, m[runs == run], p[runs == run]) for t, m, p in compared])
         for run in pd.unique(runs)],
        ignore_index=True,
    )  # fmt: skip
