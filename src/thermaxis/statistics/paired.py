"""Paired comparisons on the same held-out measurements, and the Holm correction.

Two models (or two quantities) are compared through per-measurement sums ``a`` and ``b``
of the same held-out measurements. The effect is a fold-wise statistic averaged over the
folds, so every held-out condition weighs the same whatever its length:

* its interval: both sides resampled with the SAME block-bootstrap rows within each fold
  (the pairing is kept);
* a sign-flip permutation test (``scipy.stats.permutation_test``, paired samples): under
  "no difference" the two sides of each measurement are exchangeable, so each
  measurement's pair is swapped at random, within its fold;
* a Wilcoxon signed-rank test over the folds' effects (``scipy.stats.wilcoxon``): the fold
  as the unit, which does not assume the measurements of a run independent but cannot
  resolve much with few folds (4 folds: p >= 0.125).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import stats

from thermaxis.config import StatisticsSettings
from thermaxis.statistics.resampling import percentile_interval, stratified_indices

__all__ = [
    "VERDICTS",
    "PairedResult",
    "rmse_difference",
    "share_above_half",
    "paired_comparison",
    "wilcoxon_p",
    "holm",
    "verdict",
]

VERDICTS = ("holds", "reversed", "not resolved")
# fold statistic(a sums, b sums, counts) -> value, each argument (..., folds)
FoldStatistic = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def rmse_difference(a: np.ndarray, b: np.ndarray, n: np.ndarray) -> np.ndarray:
    """RMSE of side a minus RMSE of side b, per fold (a, b: sums of squared residuals)."""
    return np.sqrt(a / n) - np.sqrt(b / n)


def share_above_half(a: np.ndarray, b: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Share of a in a + b, minus one half, per fold: positive when a carries most.

    NaN where both are zero (a replicate that drew only runs' first measurements): there
    is no share to take.
    """
    total = a + b
    share = np.divide(a, total, out=np.full(np.broadcast(a, total).shape, np.nan), where=total != 0)
    return share - 0.5


@dataclass(frozen=True)
class PairedResult:
    effect: float  # mean over folds of the fold statistic
    lo: float
    hi: float
    p_permutation: float
    p_wilcoxon: float
    fold_effects: tuple[float, ...]


def _fold_matrix(folds: np.ndarray) -> np.ndarray:
    labels = list(dict.fromkeys(folds.tolist()))
    return (folds[:, None] == np.array(labels, dtype=object)[None, :]).astype(float)


def _mean_over_folds(statistic: FoldStatistic, F: np.ndarray, n: np.ndarray):
    """The effect of per-measurement sums (..., measurements): the fold statistic's mean."""
    counts = n @ F

    def effect(a, b, axis=-1):
        a, b = np.moveaxis(a, axis, -1), np.moveaxis(b, axis, -1)
        return statistic(a @ F, b @ F, counts).mean(axis=-1)

    return effect


def wilcoxon_p(differences, alternative: str = "two-sided") -> float:
    """Wilcoxon signed-rank p over the folds; NaN when nothing can be ranked.

    ``alternative`` is scipy's: "less" asks whether the differences tend below zero.
    Exact up to 50 folds, so the smallest p of n folds is 2**-n one-sided.
    """
    d = np.asarray(differences, dtype=float)
    d = d[np.isfinite(d)]
    if d.size < 2 or not np.any(d != 0.0):
        return math.nan
    return float(stats.wilcoxon(d, zero_method="wilcox", alternative=alternative).pvalue)


def paired_comparison(
    a,
    b,
    folds,
    statistic: FoldStatistic,
    settings: StatisticsSettings,
    n=None,
) -> PairedResult:
    """Effect, interval and both tests of side a against side b on the same measurements.

    ``a``, ``b`` (measurements,): per-measurement sums; ``folds`` labels each measurement,
    in time order within a fold; ``n`` the residual count per measurement (default 1).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    folds = np.asarray(folds, dtype=object)
    n = np.ones_like(a) if n is None else np.asarray(n, dtype=float)
    F = _fold_matrix(folds)
    effect_of = _mean_over_folds(statistic, F, n)
    fold_effects = statistic(a @ F, b @ F, n @ F)
    effect = float(fold_effects.mean())
    rows = stratified_indices(
        folds, settings.block_length, settings.n_resamples, np.random.default_rng(settings.seed)
    )
    counts = n[rows] @ F  # a replicate's fold sizes stay, its residual counts may not
    replicates = statistic(a[rows] @ F, b[rows] @ F, counts).mean(axis=-1)
    lo, hi = percentile_interval(replicates, settings.level)
    p_perm = math.nan
    if a.size >= 1 and np.any(a != b):
        p_perm = float(
            stats.permutation_test(
                (a, b),
                effect_of,
                permutation_type="samples",
                vectorized=True,
                n_resamples=settings.n_resamples,
                alternative="two-sided",
                rng=np.random.default_rng(settings.seed),
            ).pvalue
        )
    return PairedResult(
        effect=effect,
        lo=lo,
        hi=hi,
        p_permutation=p_perm,
        p_wilcoxon=wilcoxon_p(fold_effects) if len(fold_effects) > 1 else math.nan,
        fold_effects=tuple(float(v) for v in fold_effects),
    )


def holm(p_values) -> np.ndarray:
    """Holm's step-down adjusted p-values (NaN stays NaN and is not counted).

    scipy offers only the false-discovery-rate adjustments (``false_discovery_control``);
    Holm controls the family-wise error, which a list of "is A better than B" answers needs.
    """
    p = np.asarray(p_values, dtype=float)
    out = np.full_like(p, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    if ok.size == 0:
        return out
    order = ok[np.argsort(p[ok], kind="stable")]
    m = order.size
    adjusted = np.maximum.accumulate((m - np.arange(m)) * p[order])
    out[order] = np.minimum(adjusted, 1.0)
    return out


def verdict(effect: float, lo: float, hi: float, p_value: float, alpha: float) -> str:
    """holds (effect > 0 resolved), reversed (< 0 resolved) or not resolved.

    Resolved needs both the interval to exclude 0 and the test to reject at ``alpha``.
    """
    if not all(math.isfinite(v) for v in (effect, lo, hi, p_value)) or p_value >= alpha:
        return "not resolved"
    if lo > 0.0:
        return "holds"
    if hi < 0.0:
        return "reversed"
    return "not resolved"
