"""tables/claims.csv: the paper's conclusions put to the test on a dataset.

Each claim is an effect that is positive when the paper is right, so one rule gives the
verdict: ``holds`` when its interval lies above 0 and its test rejects "no effect",
``reversed`` when the interval lies below 0 and the test rejects, ``not resolved``
otherwise (and when the dataset cannot express the claim: its ``effect`` is then empty).
Every effect is a mean over folds (or runs) of a statistic of the same measurements
seen two ways, so all of them use :func:`thermaxis.statistics.paired.paired_comparison`:
the block-bootstrap interval and the sign-flip permutation test, whose p-values are
Holm-corrected across the claims of the dataset. :data:`CLAIMS` defines each one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from thermaxis.config import SelectionSettings, StatisticsSettings
from thermaxis.method.features import decouple_rows, relative_temperatures
from thermaxis.method.linear import subset_fit
from thermaxis.method.selection import informative_sensors, select_sensitive_points
from thermaxis.statistics.comparisons import aligned
from thermaxis.statistics.paired import (
    PairedResult,
    holm,
    paired_comparison,
    rmse_difference,
    share_above_half,
    verdict,
)

__all__ = ["CLAIM_COLUMNS", "Claim", "CLAIMS", "claim_results", "claims_table", "claims_markdown"]

CLAIM_COLUMNS = ("claim", "dataset", "effect", "lo", "hi", "p_value", "verdict")


@dataclass(frozen=True)
class Claim:
    id: str
    text: str  # the claim column: what the paper concludes
    effect: str  # what the effect measures, positive when the paper is right
    unit: str


CLAIMS: tuple[Claim, ...] = (
    Claim(
        "decoupled_mlr",
        "decoupled modelling predicts the error better than point-by-point (MLR)",
        "held-out RMSE of the error curves, point-by-point MLR minus decoupled MLR, mean over folds",
        "µm",
    ),
    Claim(
        "decoupled_svr",
        "decoupled modelling predicts the error better than point-by-point (SVR)",
        "held-out RMSE of the error curves, point-by-point SVR minus decoupled SVR, mean over folds",
        "µm",
    ),
    Claim(
        "svr_over_mlr",
        "SVR predicts the error better than MLR (decoupled)",
        "held-out RMSE of the error curves, MLR minus SVR, decoupled (point-by-point when the "
        "dataset has one position, where both are the same model of the error), mean over folds",
        "µm",
    ),
    Claim(
        "intercept_drift",
        "the intercept b carries most of the thermal drift",
        "share of the drift's mean square (change since the run's first measurement, over the "
        "stroke) carried by the intercept change, against the slope change times the position, "
        "minus 1/2; k and b of the line through each measurement (Eq. 6), mean over runs",
        "share",
    ),
    Claim(
        "slope_absolute",
        "the slope k follows absolute temperatures",
        "held-out RMSE of k, MLR on relative minus MLR on absolute temperatures, each with the "
        "sensitive points the paper's method (fuzzy clustering, grey relational grade, config "
        "selection) picks on the training runs from its own temperatures, mean over folds",
        "µm/m",
    ),
    Claim(
        "intercept_relative",
        "the intercept b follows relative temperatures",
        "held-out RMSE of b (the error itself when the dataset has one position), MLR on "
        "absolute minus MLR on relative temperatures, sensitive points as for k, mean over folds",
        "µm",
    ),
    Claim(
        "rezeroing_hides_drift",
        "re-zeroing each measurement hides the drift",
        "share of the unzeroed errors' mean square carried by the offset that re-zeroing at the "
        "first position removes, against what re-zeroing leaves, minus 1/2, mean over runs",
        "share",
    ),
)
_BY_ID = {c.id: c for c in CLAIMS}


def _paired_rmse(models, a, b, settings) -> PairedResult | None:
    if a not in models or b not in models:
        return None
    sq_a, sq_b, n, folds = aligned(models[a], models[b], (" ".join(a), " ".join(b)))
    return paired_comparison(sq_a, sq_b, folds, rmse_difference, settings, n=n)


def _drift_shares(X: pd.DataFrame, Y: pd.DataFrame, settings) -> PairedResult | None:
    """b's change against k's change times the stroke, per measurement, from each run's first."""
    if Y.shape[1] < 2:
        return None
    kb = decouple_rows(X, Y, degree=1)
    first = kb.groupby("run", sort=False)[["k_um_per_m", "b_um"]].transform("first")
    dk = (kb["k_um_per_m"] - first["k_um_per_m"]).to_numpy()
    db = (kb["b_um"] - first["b_um"]).to_numpy()
    positions = np.asarray(Y.columns, dtype=float)
    stroke_m = (positions - positions[0]) / 1000.0
    slope_part = (dk[:, None] * stroke_m[None, :]) ** 2
    return paired_comparison(
        len(positions) * db**2,
        slope_part.sum(axis=1),
        X["run"].to_numpy(dtype=object),
        share_above_half,
        settings,
    )


def _rezeroing_shares(errors: pd.DataFrame, settings) -> PairedResult | None:
    """The offset re-zeroing removes against what it leaves, per measurement."""
    if errors["position_mm"].nunique() < 2:
        return None
    e = errors.assign(
        removed=(errors["error_um"] - errors["rezeroed_um"]) ** 2, left=errors["rezeroed_um"] ** 2
    )
    per = e.groupby(["run", "measurement"], sort=True)[["removed", "left"]].sum().reset_index()
    return paired_comparison(
        per["removed"].to_numpy(),
        per["left"].to_numpy(),
        per["run"].to_numpy(dtype=object),
        share_above_half,
        settings,
    )


def _held_out_squares(X, y, folds, representation, selection: SelectionSettings):
    """Squared held-out residuals of an MLR on ``representation`` temperatures, fold by fold.

    The sensitive points are chosen on the training runs from the same representation, so
    neither side inherits points picked for the other.
    """
    sensors = [c for c in X.columns if c not in ("run", "measurement", "time_min")]
    absolute = X[sensors].astype(float)
    relative = relative_temperatures(X, sensors)
    T = absolute if representation == "absolute" else relative
    out = np.full(len(X), np.nan)
    for fold in folds:
        test = (X["run"] == fold).to_numpy()
        train = ~test
        where = f"claims, fold {fold}"
        usable = informative_sensors(absolute.loc[train], (), where)
        informative = set(informative_sensors(relative.loc[train], (), where))
        usable = [s for s in usable if s in informative]
        points = select_sensitive_points(
            T.loc[train, usable],
            y[train],
            n_clusters=min(selection.n_clusters, len(usable)),
            similarity=selection.similarity,
            grade=selection.grade,
            rho=selection.rho,
            normalisation=selection.normalisation,
        )
        columns = [usable.index(s) for s in points.selected]
        fit = subset_fit(
            T.loc[train, usable].to_numpy(),
            y[train],
            [columns],
            "mlr",
            X_new=T.loc[test, usable].to_numpy(),
        )
        out[test] = (y[test] - fit.predictions[:, 0, 0]) ** 2
    return out


def _representation(X, y, folds, worse, better, selection, settings) -> PairedResult:
    """RMSE on ``worse`` minus RMSE on ``better`` temperatures over the held-out measurements."""
    held = X["run"].isin(folds).to_numpy()
    sq = {r: _held_out_squares(X, y, folds, r, selection)[held] for r in (worse, better)}
    return paired_comparison(
        sq[worse],
        sq[better],
        X.loc[held, "run"].to_numpy(dtype=object),
        rmse_difference,
        settings,
    )


def claim_results(
    models: dict,
    X: pd.DataFrame,
    Y: pd.DataFrame,
    errors: pd.DataFrame,
    folds,
    selection: SelectionSettings,
    settings: StatisticsSettings,
) -> dict[str, PairedResult | None]:
    """Each claim's paired result; None where the dataset cannot express it."""
    one_position = Y.shape[1] < 2
    svr_approach = "pointwise" if one_position else "decoupled"
    results = {
        "decoupled_mlr": _paired_rmse(models, ("pointwise", "mlr"), ("decoupled", "mlr"), settings),
        "decoupled_svr": _paired_rmse(models, ("pointwise", "svr"), ("decoupled", "svr"), settings),
        "svr_over_mlr": _paired_rmse(
            models, (svr_approach, "mlr"), (svr_approach, "svr"), settings
        ),
        "intercept_drift": _drift_shares(X, Y, settings),
        "slope_absolute": None,
        "rezeroing_hides_drift": _rezeroing_shares(errors, settings),
    }
    if one_position:
        intercept = Y.iloc[:, 0].to_numpy(dtype=float)
    else:
        kb = decouple_rows(X, Y, degree=1)
        intercept = kb["b_um"].to_numpy()
        results["slope_absolute"] = _representation(
            X, kb["k_um_per_m"].to_numpy(), folds, "relative", "absolute", selection, settings
        )
    results["intercept_relative"] = _representation(
        X, intercept, folds, "absolute", "relative", selection, settings
    )
    return results


def claims_table(dataset: str, results: dict, settings: StatisticsSettings) -> pd.DataFrame:
    """:data:`CLAIM_COLUMNS`, one row per claim; p-values Holm-corrected over the claims."""
    p = [r.p_permutation if r is not None else math.nan for r in (results[c.id] for c in CLAIMS)]
    adjusted = holm(p)
    rows = []
    for claim, p_value in zip(CLAIMS, adjusted, strict=True):
        r = results[claim.id]
        effect, lo, hi = (r.effect, r.lo, r.hi) if r is not None else (math.nan,) * 3
        rows.append(
            {
                "claim": claim.text,
                "dataset": dataset,
                "effect": effect,
                "lo": lo,
                "hi": hi,
                "p_value": p_value,
                "verdict": verdict(effect, lo, hi, p_value, settings.alpha),
            }
        )
    return pd.DataFrame(rows, columns=list(CLAIM_COLUMNS))


def claims_markdown(table: pd.DataFrame, statement: str, settings: StatisticsSettings) -> str:
    """claims.md: the verdicts, then what each effect measures."""
    from thermaxis.tables import markdown_table

    level = f"{settings.level:.0%}"
    lines = [
        "# The paper's claims, tested",
        "",
        statement,
        "",
        f"Effect > 0: the paper is right. [lo, hi]: {level} block-bootstrap interval "
        "(measurements resampled in blocks within their fold or run); p: sign-flip permutation "
        "test over the same measurements, Holm-corrected over the claims. Verdict: holds / "
        f"reversed when the interval excludes 0 and p < {settings.alpha:g}, else not resolved "
        "(an empty effect: the dataset cannot express the claim).",
        "",
        markdown_table(table, "%.3f"),
        "",
        "## What each effect measures",
        "",
    ]
    lines += [f"- **{c.text}** ({c.unit}): {c.effect}." for c in CLAIMS]
    return "\n".join(lines) + "\n"
