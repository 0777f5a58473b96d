"""Confidence intervals of the held-out metrics (RMSE, max |residual|, MAE).

The unit resampled is the held-out measurement: its whole error curve (or its k, b) stays
together, and measurements are resampled in blocks of consecutive ones within their fold
(:mod:`thermaxis.statistics.resampling`). Each metric is a function of four sums per
measurement (squared and absolute residuals, their count, the largest |residual|), so
every replicate is a fancy-indexed sum in numpy: no Python loop over replicates.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from thermaxis.config import StatisticsSettings
from thermaxis.statistics.resampling import percentile_interval, stratified_indices

__all__ = [
    "INTERVAL_METRICS",
    "MODEL_KEYS",
    "measurement_sums",
    "interval_columns",
    "metric_intervals",
    "with_intervals",
]

INTERVAL_METRICS = ("rmse", "max_abs", "mae")
MODEL_KEYS = ["fold", "approach", "algorithm", "target"]


def interval_columns(metrics=INTERVAL_METRICS) -> list[str]:
    """``rmse, rmse_lo, rmse_hi, max_abs, ...``: each metric with its interval beside it."""
    return [c for m in metrics for c in (m, f"{m}_lo", f"{m}_hi")]


def _residuals(kb_predictions: pd.DataFrame, error_predictions: pd.DataFrame) -> pd.DataFrame:
    """One row per residual: the model keys, run, measurement, residual (measured - predicted)."""
    kb = kb_predictions.assign(residual=kb_predictions["measured"] - kb_predictions["predicted"])
    errors = error_predictions.assign(
        target="error", residual=error_predictions["measured"] - error_predictions["predicted"]
    )
    columns = [*MODEL_KEYS, "run", "measurement", "residual"]
    # A single-position dataset has no k/b rows: its empty table must not make the column object.
    frames = [f[columns] for f in (kb, errors) if len(f)]
    residuals = pd.concat(frames, ignore_index=True) if frames else errors[columns]
    return residuals.astype({"residual": float})


def measurement_sums(kb_predictions: pd.DataFrame, error_predictions: pd.DataFrame) -> pd.DataFrame:
    """Per model and held-out measurement: ``sq`` (sum of r^2), ``ab`` (sum of |r|), ``peak``, ``n``.

    NaN residuals (a position a measurement lacks) count in none of them. Rows are in
    time order within each fold (measurement number), as the block bootstrap needs.
    """
    r = _residuals(kb_predictions, error_predictions)
    r = r.loc[np.isfinite(r["residual"].to_numpy(dtype=float))]
    absolute = r["residual"].abs()
    r = r.assign(sq=r["residual"] ** 2, ab=absolute, peak=absolute)
    sums = r.groupby([*MODEL_KEYS, "run", "measurement"], sort=True).agg(
        sq=("sq", "sum"), ab=("ab", "sum"), peak=("peak", "max"), n=("residual", "size")
    )
    return sums.reset_index()


def _replicate_metrics(sums: pd.DataFrame, rows: np.ndarray) -> dict[str, np.ndarray]:
    """RMSE, max |residual| and MAE of every replicate (``rows``: replicates x measurements)."""
    n = sums["n"].to_numpy(dtype=float)[rows].sum(axis=1)
    return {
        "rmse": np.sqrt(sums["sq"].to_numpy(dtype=float)[rows].sum(axis=1) / n),
        "max_abs": sums["peak"].to_numpy(dtype=float)[rows].max(axis=1),
        "mae": sums["ab"].to_numpy(dtype=float)[rows].sum(axis=1) / n,
    }


def metric_intervals(sums: pd.DataFrame, settings: StatisticsSettings) -> pd.DataFrame:
    """``*_lo`` and ``*_hi`` of RMSE, max |residual| and MAE per fold x approach x algorithm x target.

    Every model is resampled with the same generator state, so models scored on the same
    measurements see the same replicates (their intervals are comparable row by row).
    The bootstrap of a maximum can never exceed the observed one: its upper end is the
    observed maximum whenever the largest residual's measurement is drawn often enough.
    """
    out = []
    for keys, group in sums.groupby(MODEL_KEYS, sort=True):
        group = group.sort_values("measurement")
        rng = np.random.default_rng(settings.seed)
        rows = stratified_indices(
            np.zeros(len(group)), settings.block_length, settings.n_resamples, rng
        )
        replicates = _replicate_metrics(group.reset_index(drop=True), rows)
        row = dict(zip(MODEL_KEYS, keys, strict=True))
        for metric, values in replicates.items():
            row[f"{metric}_lo"], row[f"{metric}_hi"] = percentile_interval(values, settings.level)
        out.append(row)
    columns = [*MODEL_KEYS, *(f"{m}_{e}" for m in INTERVAL_METRICS for e in ("lo", "hi"))]
    return pd.DataFrame(out, columns=columns)


def with_intervals(metrics: pd.DataFrame, intervals: pd.DataFrame) -> pd.DataFrame:
    """The metrics table with each metric's interval beside it, rows in their order."""
    merged = metrics.merge(intervals, on=MODEL_KEYS, how="left", validate="one_to_one")
    rest = [c for c in metrics.columns if c not in (*MODEL_KEYS, *INTERVAL_METRICS)]
    return merged[[*MODEL_KEYS, *interval_columns(), *rest]]
