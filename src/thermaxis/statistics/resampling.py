"""Resampling held-out measurements: the moving-block bootstrap and its percentile intervals.

A held-out run's measurements are taken one after another while the axis heats up, so
neighbouring measurements share their errors' drift. Resampling them one by one would
treat them as independent and give intervals too narrow; resampling blocks of
consecutive measurements keeps that short-range dependence (Künsch 1989, the moving-block
bootstrap). A measurement's error curve is never split: it is one row. scipy's
``stats.bootstrap`` resamples single observations only, hence this module; intervals of
means over folds (independent conditions) use ``scipy.stats.bootstrap`` itself
(:func:`fold_mean_interval`).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

__all__ = [
    "block_length_for",
    "block_indices",
    "stratified_indices",
    "percentile_interval",
    "fold_mean_interval",
]


def block_length_for(n: int, configured: int) -> int:
    """The block length for ``n`` measurements: ``configured``, or round(n^(1/3)) when it is 0.

    n^(1/3) is the order of the optimal block length of the moving-block bootstrap for a
    variance or a distribution (Hall, Horowitz & Jing 1995): 2 for the paper's 8
    measurements, 4 for 48. Never longer than the run.
    """
    length = configured if configured > 0 else max(1, round(n ** (1.0 / 3.0)))
    return max(1, min(int(length), n))


def block_indices(n: int, block_length: int, n_resamples: int, rng) -> np.ndarray:
    """(n_resamples, n) row indices: blocks of consecutive rows with random starts, cut to n."""
    if n < 1:
        raise ValueError("cannot resample 0 measurements")
    length = max(1, min(block_length, n))
    n_blocks = math.ceil(n / length)
    starts = rng.integers(0, n - length + 1, size=(n_resamples, n_blocks))
    rows = starts[:, :, None] + np.arange(length)[None, None, :]
    return rows.reshape(n_resamples, n_blocks * length)[:, :n]


def stratified_indices(groups, block_length: int, n_resamples: int, rng) -> np.ndarray:
    """Row indices resampled within each group (fold), blocks inside a group only.

    ``groups`` labels each row, rows of a group in time order. Returns (n_resamples, n):
    each replicate keeps every group's size, so a fold stays a fold.
    """
    groups = np.asarray(groups)
    out = np.empty((n_resamples, groups.size), dtype=np.intp)
    for label in dict.fromkeys(groups.tolist()):
        rows = np.flatnonzero(groups == label)
        length = block_length_for(rows.size, block_length)
        out[:, rows] = rows[block_indices(rows.size, length, n_resamples, rng)]
    return out


def percentile_interval(replicates, level: float) -> tuple[float, float]:
    """The percentile interval of bootstrap replicates at confidence ``level`` (NaN if none)."""
    replicates = np.asarray(replicates, dtype=float)
    replicates = replicates[np.isfinite(replicates)]
    if replicates.size == 0:
        return math.nan, math.nan
    alpha = 1.0 - level
    lo, hi = np.quantile(replicates, [alpha / 2.0, 1.0 - alpha / 2.0])
    return float(lo), float(hi)


def fold_mean_interval(values, level: float, n_resamples: int, seed: int) -> tuple[float, float]:
    """Percentile interval of a mean over folds, the folds resampled (scipy.stats.bootstrap).

    One fold has nothing to resample: NaN. Equal values give the value itself.
    """
    # Here, not at module level: scipy.stats costs about 0.6 s to import, and the block
    # bootstrap above and the index page need none of it.
    from scipy import stats

    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if values.size < 2:
        return math.nan, math.nan
    if np.ptp(values) == 0.0:
        return float(values[0]), float(values[0])
    with warnings.catch_warnings():
        # Few folds make few distinct resamples; the percentile interval is still defined.
        warnings.simplefilter("ignore", stats.DegenerateDataWarning)
        result = stats.bootstrap(
            (values,),
            np.mean,
            n_resamples=n_resamples,
            confidence_level=level,
            method="percentile",
            rng=np.random.default_rng(seed),
        )
    return float(result.confidence_interval.low), float(result.confidence_interval.high)
