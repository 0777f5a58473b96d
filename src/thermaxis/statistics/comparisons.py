"""tables/comparisons.csv: every two (approach, algorithm) pairs on the same held-out measurements.

Each row compares model a with model b on the error curves of every fold: the mean over
folds of RMSE(a) - RMSE(b) (negative: a predicts better), its block-bootstrap interval,
the sign-flip permutation test over measurements within folds and the Wilcoxon test
over folds, each Holm-corrected across the rows of the table. The recommendation's last
row compares the pipeline's choice with the paper's configuration fold by fold: the
recommendation keeps each fold's metrics, not its residuals, so that row resamples and
permutes folds (``unit``).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
from scipy import stats

from thermaxis.config import StatisticsSettings
from thermaxis.statistics.paired import holm, paired_comparison, rmse_difference, wilcoxon_p
from thermaxis.statistics.resampling import fold_mean_interval

__all__ = [
    "COMPARISON_COLUMNS",
    "model_sums",
    "aligned",
    "compare_models",
    "compare_recommendation",
    "comparison_table",
    "fold_means",
]

COMPARISON_COLUMNS = (
    "a",
    "b",
    "unit",
    "n_folds",
    "n_measurements",
    "rmse_a",
    "rmse_b",
    "difference",
    "difference_lo",
    "difference_hi",
    "p_permutation",
    "p_permutation_holm",
    "p_wilcoxon",
    "p_wilcoxon_holm",
)
_MEASUREMENT = ["fold", "run", "measurement"]


def model_sums(sums: pd.DataFrame, target: str = "error") -> dict[tuple[str, str], pd.DataFrame]:
    """Per (approach, algorithm): its measurement sums of ``target``, indexed by fold, run, measurement."""
    rows = sums.loc[sums["target"] == target]
    return {
        (str(approach), str(algorithm)): group.set_index(_MEASUREMENT).sort_index()
        for (approach, algorithm), group in rows.groupby(["approach", "algorithm"], sort=True)
    }


def _label(model: tuple[str, str]) -> str:
    return f"{model[0]} {model[1]}"


def aligned(a: pd.DataFrame, b: pd.DataFrame, names: tuple[str, str]):
    """The measurements both models predicted: (a's sq, b's sq, counts, fold labels)."""
    common = a.index.intersection(b.index)
    a, b = a.loc[common], b.loc[common]
    if not np.array_equal(a["n"].to_numpy(), b["n"].to_numpy()):
        raise ValueError(
            f"models {names[0]} and {names[1]}: residual counts differ on the same measurements"
        )
    folds = common.get_level_values("fold").to_numpy(dtype=object)
    return a["sq"].to_numpy(), b["sq"].to_numpy(), a["n"].to_numpy(dtype=float), folds


def _fold_rmse(sq, n, folds) -> float:
    """The mean over folds of each fold's RMSE."""
    _, fold = np.unique(np.asarray(folds, dtype=str), return_inverse=True)
    return float(np.sqrt(np.bincount(fold, weights=sq) / np.bincount(fold, weights=n)).mean())


def compare_models(
    models: dict[tuple[str, str], pd.DataFrame], settings: StatisticsSettings
) -> pd.DataFrame:
    """One row per unordered pair of models, in the models' order."""
    rows = []
    for first, second in itertools.combinations(sorted(models), 2):
        sq_a, sq_b, n, folds = aligned(models[first], models[second], (first, second))
        result = paired_comparison(sq_a, sq_b, folds, rmse_difference, settings, n=n)
        rows.append(
            {
                "a": _label(first),
                "b": _label(second),
                "unit": "measurements",
                "n_folds": len(result.fold_effects),
                "n_measurements": len(folds),
                "rmse_a": _fold_rmse(sq_a, n, folds),
                "rmse_b": _fold_rmse(sq_b, n, folds),
                "difference": result.effect,
                "difference_lo": result.lo,
                "difference_hi": result.hi,
                "p_permutation": result.p_permutation,
                "p_wilcoxon": result.p_wilcoxon,
            }
        )
    return pd.DataFrame(rows, columns=[c for c in COMPARISON_COLUMNS if "holm" not in c])


def compare_recommendation(folds: pd.DataFrame, settings: StatisticsSettings) -> dict:
    """The choice's held-out RMSE against the paper's configuration's, fold by fold."""
    chosen = folds["rmse_um"].to_numpy(dtype=float)
    paper = folds["paper_rmse_um"].to_numpy(dtype=float)
    d = chosen - paper
    lo, hi = fold_mean_interval(d, settings.level, settings.n_resamples, settings.seed)
    p_perm = math.nan
    if d.size >= 2 and np.any(d != 0.0):
        p_perm = float(
            stats.permutation_test(
                (chosen, paper),
                lambda x, y, axis: np.mean(x - y, axis=axis),
                permutation_type="samples",
                vectorized=True,
                n_resamples=settings.n_resamples,
                rng=np.random.default_rng(settings.seed),
            ).pvalue
        )
    return {
        "a": "recommended (per fold)",
        "b": "paper",
        "unit": "folds",
        "n_folds": int(d.size),
        "n_measurements": math.nan,
        "rmse_a": float(chosen.mean()),
        "rmse_b": float(paper.mean()),
        "difference": float(d.mean()),
        "difference_lo": lo,
        "difference_hi": hi,
        "p_permutation": p_perm,
        "p_wilcoxon": wilcoxon_p(d),
    }


def comparison_table(pairs: pd.DataFrame, recommendation: dict | None) -> pd.DataFrame:
    """Every comparison of one table with its Holm-corrected p-values."""
    extra = [recommendation] if recommendation is not None else []
    table = pd.concat([pairs, pd.DataFrame(extra)], ignore_index=True) if extra else pairs.copy()
    for column in ("p_permutation", "p_wilcoxon"):
        table[f"{column}_holm"] = holm(table[column].to_numpy(dtype=float))
    table["n_measurements"] = table["n_measurements"].astype("Int64")
    return table[list(COMPARISON_COLUMNS)]


def fold_means(loco: pd.DataFrame, settings: StatisticsSettings) -> pd.DataFrame:
    """Each candidate's mean held-out RMSE and max |residual| over folds, with intervals.

    ``loco`` holds one row per candidate and held-out run (the recommendation's scores);
    the columns are ``loco_rmse_um``, ``loco_rmse_um_lo``, ``loco_rmse_um_hi``, then the
    same for ``max_abs``, indexed by candidate in first-seen order; intervals resample folds.
    """
    rows = {}
    for candidate, group in loco.groupby("candidate", sort=False):
        row = {}
        for metric in ("rmse", "max_abs"):
            values = group[metric].to_numpy(dtype=float)
            lo, hi = fold_mean_interval(values, settings.level, settings.n_resamples, settings.seed)
            row.update(
                {f"loco_{metric}_um": values.mean(), f"loco_{metric}_um_lo": lo,
                 f"loco_{metric}_um_hi": hi}
            )  # fmt: skip
        rows[candidate] = row
    return pd.DataFrame.from_dict(rows, orient="index").rename_axis("candidate")
