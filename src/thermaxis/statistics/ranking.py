"""The sweep's ranking with its uncertainty: intervals, mean ranks, Friedman and a post-hoc test.

Many configurations over a few folds is the setting of Demšar (2006) for many methods over
many data sets: rank the configurations within each fold (1 = lowest held-out max
|residual|), test with Friedman whether the mean ranks differ at all, and only then compare
every configuration with the best one (ranking.csv's rank 1, the control) by the z
statistic of their mean ranks, Holm-corrected over the k - 1 comparisons (Demšar §3.2.2).
The critical difference drawn in the figure is the Bonferroni-Dunn one of the same test:
z at alpha / (2 (k - 1)) times the standard error of a mean-rank difference. Only
configurations evaluated on every fold take part; the others get empty cells.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
from scipy import stats

from thermaxis.config import StatisticsSettings
from thermaxis.statistics.paired import holm

__all__ = [
    "UNCERTAINTY_COLUMNS",
    "mean_ranks",
    "rank_standard_error",
    "versus_control",
    "with_uncertainty",
]

UNCERTAINTY_COLUMNS = (
    "mean_max_abs_lo",
    "mean_max_abs_hi",
    "mean_rank",
    "p_vs_best",
    "distinguishable",
    "friedman_p",
    "critical_difference",
)


def mean_ranks(scores: np.ndarray) -> np.ndarray:
    """(k,) mean rank of each row of ``scores`` (k configurations x N folds), 1 = lowest, ties averaged."""
    return stats.rankdata(scores, axis=0).mean(axis=1)


def rank_standard_error(k: int, n: int) -> float:
    """Standard error of the difference of two mean ranks: sqrt(k (k + 1) / (6 N))."""
    return math.sqrt(k * (k + 1) / (6.0 * n))


def versus_control(ranks: np.ndarray, control: int, n: int) -> np.ndarray:
    """Two-sided p of each configuration's mean rank against the control's, Holm-corrected."""
    z = (ranks - ranks[control]) / rank_standard_error(ranks.size, n)
    p = 2.0 * stats.norm.sf(np.abs(z))
    p[control] = np.nan
    return holm(p)


def _friedman_p(scores: np.ndarray) -> float:
    k, n = scores.shape
    if k < 3 or n < 2:
        return math.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all ranks tied: NaN, not resolved
        return float(stats.friedmanchisquare(*scores).pvalue)


def _fold_mean_intervals(scores: np.ndarray, settings: StatisticsSettings):
    """Percentile intervals of every configuration's mean over folds, the folds resampled.

    One scipy.stats.bootstrap call over the (configurations x folds) array: every
    configuration sees the same resampled folds, as the ranking compares them.
    """
    if scores.shape[1] < 2:
        return np.full(scores.shape[0], np.nan), np.full(scores.shape[0], np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", stats.DegenerateDataWarning)
        ci = stats.bootstrap(
            (scores,),
            np.mean,
            axis=-1,
            vectorized=True,
            n_resamples=settings.n_resamples,
            confidence_level=settings.level,
            method="percentile",
            rng=np.random.default_rng(settings.seed),
        ).confidence_interval
    return ci.low, ci.high


def with_uncertainty(
    summary: pd.DataFrame, ranking: pd.DataFrame, settings: StatisticsSettings
) -> pd.DataFrame:
    """ranking.csv with :data:`UNCERTAINTY_COLUMNS` after its columns, its rows in their order."""
    errors = summary.loc[summary["target"] == "error"]
    wide = errors.pivot_table(index="config_id", columns="fold", values="max_abs", aggfunc="first")
    wide = wide.dropna(axis=0, how="any")
    order = [c for c in ranking["config_id"] if c in wide.index]
    scores = wide.loc[order].to_numpy(dtype=float)
    k, n = scores.shape
    table = pd.DataFrame(index=pd.Index(order, name="config_id"))
    table["mean_max_abs_lo"], table["mean_max_abs_hi"] = _fold_mean_intervals(scores, settings)
    friedman = _friedman_p(scores)
    table["friedman_p"] = friedman
    if k >= 2 and n >= 2:
        ranks = mean_ranks(scores)
        p = versus_control(ranks, 0, n)
        table["mean_rank"] = ranks
        table["p_vs_best"] = p
        # Only after Friedman rejects equal ranks (Demšar): otherwise nothing is distinguished.
        resolved = np.isfinite(friedman) and friedman < settings.alpha
        table["distinguishable"] = np.where(np.isnan(p), False, resolved & (p < settings.alpha))
        z = stats.norm.ppf(1.0 - settings.alpha / (2.0 * (k - 1)))
        table["critical_difference"] = z * rank_standard_error(k, n)
    out = ranking.join(table, on="config_id")
    for column in UNCERTAINTY_COLUMNS:
        if column not in out:
            out[column] = np.nan
    return out[[*ranking.columns, *UNCERTAINTY_COLUMNS]]
