"""The audit: every number the paper publishes beside its reproduction.

Each published item (``thermaxis.paper.published.published_values``) is looked up in the
pipeline's own tables for the paper's fold (train on every other condition,
predict the paper's held-out run). Nothing here computes a model: a reproduced
value is read from the tables the workflow wrote, so the audit cannot disagree
with them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from thermaxis.dataset.summary import data_statement
from thermaxis.tables import markdown_table

__all__ = ["ReproducedTables", "paper_comparison", "comparison_markdown"]


@dataclass(frozen=True, kw_only=True)
class ReproducedTables:
    """The workflow tables the audit reads (all tidy DataFrames)."""

    runs: pd.DataFrame
    ambient: pd.DataFrame  # run, ambient_min_c, ambient_max_c
    kb: pd.DataFrame
    metrics: pd.DataFrame
    coefficients: pd.DataFrame
    sensitive_points: pd.DataFrame
    error_predictions: pd.DataFrame
    errors: pd.DataFrame
    paper_fold: str


def _one(frame: pd.DataFrame, column: str) -> float:
    if len(frame) == 0:
        return np.nan
    return float(frame[column].iloc[0])


def _metric(t: ReproducedTables, approach, algorithm, target, quantity) -> float:
    m = t.metrics
    sel = m[
        (m["fold"] == t.paper_fold)
        & (m["approach"] == approach)
        & (m["algorithm"] == algorithm)
        & (m["target"] == target)
    ]
    return _one(sel, quantity)


def _positions(t: ReproducedTables) -> np.ndarray:
    return np.sort(t.errors["position_mm"].unique())


def _reproduce(row, t: ReproducedTables) -> tuple[float, str]:
    # One helper per table of the paper: each reads its own reproduced table.
    table, q = row["table"], row["quantity"]
    if table == "table1":
        return _table1(row, t)
    if table == "table5":
        kb = t.kb
        sel = kb[(kb["run"] == row["run"]) & (kb["measurement"] == int(row["measurement"]))]
        return _one(sel, "k_um_per_m" if q == "k" else "b_um"), ""
    if table in ("table4", "table7", "table8") or (
        table == "text" and q in ("residual_min", "residual_max")
    ):
        value = _metric(t, row["approach"], row["algorithm"], row["target"], q)
        return value, f"fold {t.paper_fold}"
    if table == "table3":
        return _table3(row, t)
    if table == "table6":
        return _table6(row, t)
    if table in ("eq8", "eq9"):
        return _equation(row, t)
    if table == "text":
        return _text(row, t)
    return np.nan, "not reproduced"


def _table1(row, t: ReproducedTables) -> tuple[float, str]:
    """Table 1: a run's feed, measurement count and ambient range."""
    q = row["quantity"]
    runs = t.runs.set_index("run")
    if row["run"] not in runs.index:
        return np.nan, "run not in dataset"
    if q == "feed":
        return float(runs.loc[row["run"], "feed_mm_min"]), ""
    if q == "measurements":
        return float(t.errors.loc[t.errors["run"] == row["run"], "measurement"].nunique()), ""
    amb = t.ambient.set_index("run")
    column = "ambient_min_c" if q == "ambient_min" else "ambient_max_c"
    return float(amb.loc[row["run"], column]), "ambient sensor, first to last measurement"


def _table3(row, t: ReproducedTables) -> tuple[float, str]:
    """Table 3: whether the paper's sensitive point at a position is also selected."""
    fold = t.paper_fold
    sp = t.sensitive_points
    sel = sp[
        (sp["fold"] == fold)
        & (sp["target"] == "error")
        & np.isclose(sp["position_mm"], float(row["position_mm"]))
    ]
    if len(sel) == 0:
        return (
            np.nan,
            "position not selected by the workflow (fixed selection or missing position)",
        )
    return float(
        ((sel["sensor"] == row["term"]) & sel["selected"]).any()
    ), f"fold {fold}; 1 = also selected"


def _table6(row, t: ReproducedTables) -> tuple[float, str]:
    """Table 6: a sensor's cluster and whether it is a sensitive point for k or b."""
    q, fold = row["quantity"], t.paper_fold
    sp = t.sensitive_points
    sel = sp[(sp["fold"] == fold) & (sp["target"] == row["target"]) & (sp["sensor"] == row["term"])]
    if len(sel) == 0:
        return np.nan, "sensor not in the workflow's selection table"
    if q == "sensitive_point":
        return float(bool(sel["selected"].iloc[0])), f"fold {fold}; 1 = also selected"
    return float(sel["cluster"].iloc[0]), f"fold {fold}; clusters numbered by their first sensor"


def _equation(row, t: ReproducedTables) -> tuple[float, str]:
    """Equations 8 (point by point) and 9 (decoupled): a coefficient of the MLR model."""
    table, fold = row["table"], t.paper_fold
    c = t.coefficients
    approach = "pointwise" if table == "eq8" else "decoupled"
    sel = c[
        (c["fold"] == fold)
        & (c["approach"] == approach)
        & (c["algorithm"] == "mlr")
        & (c["target"] == row["target"])
        & (c["term"] == row["term"])
    ]
    if table == "eq8":
        sel = sel[np.isclose(sel["position_mm"], float(row["position_mm"]))]
    if len(sel) == 0:
        return np.nan, "term not in the reproduced model (other sensitive points)"
    return _one(sel, "value"), f"fold {fold}"


def _text(row, t: ReproducedTables) -> tuple[float, str]:
    """The figures quoted in the paper's text: maximum residuals and errors."""
    q, fold = row["quantity"], t.paper_fold
    if q == "max_abs_residual":
        e = t.error_predictions
        sel = e[
            (e["fold"] == fold)
            & (e["approach"] == row["approach"])
            & (e["algorithm"] == row["algorithm"])
            & np.isclose(e["position_mm"], float(row["position_mm"]))
        ]
        return (float(sel["residual"].abs().max()) if len(sel) else np.nan), f"fold {fold}"
    if q == "max_abs_error":
        e = t.errors[t.errors["run"] == row["run"]]
        return (float(e["error_um"].abs().max()) if len(e) else np.nan), ""
    if q == "max_error_from_k_residual":
        positions = _positions(t)
        stroke_m = (positions[-1] - positions[0]) / 1000.0
        return _metric(
            t, "decoupled", "mlr", "k", "max_abs"
        ) * stroke_m, f"fold {fold}; max |k residual| x stroke"
    return np.nan, "not reproduced"


def paper_comparison(
    published: pd.DataFrame, tables: ReproducedTables, dataset_name: str, simulated: bool
) -> pd.DataFrame:
    """One row per published number: published, reproduced, difference."""
    rows = []
    for _, row in published.iterrows():
        reproduced, note = _reproduce(row, tables)
        rows.append(
            {
                "dataset": dataset_name,
                "data": "simulated" if simulated else "measured",
                "item": row["item"],
                "table": row["table"],
                "quantity": row["quantity"],
                "unit": row["unit"],
                "published": float(row["value"]),
                "reproduced": reproduced,
                "difference": reproduced - float(row["value"]),
                "note": note,
            }
        )
    return pd.DataFrame(rows)


def comparison_markdown(
    comparison: pd.DataFrame, dataset_name: str, simulated: bool, paper_fold: str
) -> str:
    stated = data_statement(dataset_name, simulated)
    head = [
        "# Audit: the paper's published numbers beside their reproduction",
        "",
        f"**{stated}**",
        "",
        f"Models: fold `{paper_fold}` (trained on every other run, predicting `{paper_fold}`, the paper's split).",
        "Differences are reproduced minus published. Sensitive-point rows are 1 when the reproduction selects the same sensor.",
        "",
    ]
    shown = comparison.drop(columns=["dataset", "data"])
    summary = (
        comparison.assign(abs_diff=comparison["difference"].abs())
        .groupby("table", sort=True)
        .agg(
            items=("item", "size"),
            reproduced=("reproduced", lambda s: int(s.notna().sum())),
            mean_abs_difference=("abs_diff", "mean"),
        )
        .reset_index()
    )
    return (
        "\n".join(head)
        + "## Summary per table\n\n"
        + markdown_table(summary, "%.3f")
        + "\n## Every item\n\n"
        + markdown_table(shown, "%.3f")
    )
