"""Prediction figures (the paper's Figs. 11, 14-17) and the fold comparison."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from thermaxis.figures.captions import _display
from thermaxis.figures.style import (
    CATEGORICAL_COLORS,
    DOUBLE_COLUMN_IN,
    ERROR_LABEL,
    MARKERS,
    ORDERED_CMAP,
    POSITION_LABEL,
    SINGLE_COLUMN_IN,
    TIME_LABEL,
    _categorical_style,
    _markevery,
    _measurement_times,
    _new_figure,
    _ordered_key,
    _ordered_norm,
    _require_columns,
    _select,
    _styled,
    _time_label,
    _top_legend,
    short_name,
    short_names,
    single_position,
)
from thermaxis.labels import natural_key, natural_sorted

__all__ = [
    "fig_kb_prediction",
    "fig_error_prediction",
    "fig_fold_comparison",
    "fig_recommendation",
]


def _prediction_columns(n_runs: int) -> float:
    return SINGLE_COLUMN_IN if n_runs == 1 else DOUBLE_COLUMN_IN


def _has_band(rows: pd.DataFrame) -> bool:
    return bool(
        np.isfinite(rows["lower"].to_numpy(dtype=float)).any()
        and np.isfinite(rows["upper"].to_numpy(dtype=float)).any()
    )


_KB_PRED_COLUMNS = (
    "fold",
    "approach",
    "algorithm",
    "run",
    "measurement",
    "target",
    "measured",
    "predicted",
    "lower",
    "upper",
)
_KB_TARGETS = (("k", "Slope k (µm/m)"), ("b", "Intercept b (µm)"))


def _measured_and_predicted(
    ax, x: np.ndarray, rows: pd.DataFrame, algorithm: str, markevery=None
) -> None:
    """Measured (solid) and predicted (dashed) against x, the prediction interval shaded where given."""
    if _has_band(rows):
        ax.fill_between(
            x,
            rows["lower"].to_numpy(dtype=float),
            rows["upper"].to_numpy(dtype=float),
            color=CATEGORICAL_COLORS[1],
            alpha=0.25,
            linewidth=0,
            label="Prediction interval",
        )
    ax.plot(
        x,
        rows["measured"].to_numpy(dtype=float),
        label="Measured",
        markevery=markevery,
        **_categorical_style(0),
    )
    ax.plot(
        x,
        rows["predicted"].to_numpy(dtype=float),
        linestyle="--",
        label=f"Predicted ({_display(algorithm)})",
        markevery=markevery,
        **_categorical_style(1),
    )


@_styled
def fig_kb_prediction(kb_pred: pd.DataFrame, fold, approach: str, algorithm: str) -> Figure:
    """Predicted against measured slope k and intercept b of the held-out run(s) (Figs. 14 and 16).

    One column per held-out run of the fold; k on top, b below, against the
    measurement number.  A prediction interval is shaded where ``lower``/``upper``
    are given (GPR).

    Parameters
    ----------
    kb_pred : pandas.DataFrame
        Tidy predictions of k and b (columns fold, approach, algorithm, run, measurement,
        target, measured, predicted, lower, upper).
    fold, approach, algorithm
        Which predictions to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require_columns(kb_pred, _KB_PRED_COLUMNS, "kb_pred")
    rows = _select(kb_pred, "kb_pred", fold=fold, approach=approach, algorithm=algorithm)
    runs = natural_sorted(rows["run"])
    fig = _new_figure(_prediction_columns(len(runs)), 3.6)
    axes = fig.subplots(2, len(runs), sharex="col", squeeze=False)
    for col, run in enumerate(runs):
        for row, (target, label) in enumerate(_KB_TARGETS):
            ax = axes[row, col]
            part = rows[(rows["run"] == run) & (rows["target"] == target)].sort_values(
                "measurement", kind="stable"
            )
            _measured_and_predicted(ax, part["measurement"].to_numpy(dtype=float), part, algorithm)
            ax.set_ylabel(label if col == 0 else "")
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            if row == 0:
                ax.set_title(f"Held-out run {short_name(run)}", loc="left")
                ax.legend(loc="best")
        axes[-1, col].set_xlabel("Measurement")
    return fig


_ERR_PRED_COLUMNS = (
    "fold",
    "approach",
    "algorithm",
    "run",
    "measurement",
    "time_min",
    "position_mm",
    "measured",
    "predicted",
    "residual",
    "lower",
    "upper",
)


@_styled
def fig_error_prediction(err_pred: pd.DataFrame, fold, approach: str, algorithm: str) -> Figure:
    """Predicted against measured error curves and their residuals (Figs. 15 and 17).

    One column per held-out run: on top the measured curves (solid) and predicted
    curves (dashed) of every measurement, coloured by the measurement's time, with the
    prediction interval shaded where given; below the residuals (measured - predicted).

    Parameters
    ----------
    err_pred : pandas.DataFrame
        Tidy error predictions (columns fold, approach, algorithm, run, measurement,
        time_min, position_mm, measured, predicted, residual, lower, upper).
    fold, approach, algorithm
        Which predictions to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require_columns(err_pred, _ERR_PRED_COLUMNS, "err_pred")
    rows = _select(err_pred, "err_pred", fold=fold, approach=approach, algorithm=algorithm)
    runs = natural_sorted(rows["run"])
    fig = _new_figure(_prediction_columns(len(runs)), 4.0)
    axes = fig.subplots(2, len(runs), sharex="col", squeeze=False, height_ratios=(3, 2))
    if single_position(rows):
        for col, run in enumerate(runs):
            _prediction_in_time(
                axes[0, col], axes[1, col], rows[rows["run"] == run], algorithm, first=col == 0
            )
            axes[0, col].set_title(f"Held-out run {short_name(run)}", loc="left")
        return fig
    for col, run in enumerate(runs):
        _prediction_along_stroke(
            fig,
            axes[0, col],
            axes[1, col],
            run,
            rows[rows["run"] == run],
            algorithm,
            first=col == 0,
        )
    return fig


def _prediction_along_stroke(
    fig, ax_curve, ax_res, run, run_rows: pd.DataFrame, algorithm: str, first: bool
) -> None:
    """One held-out run: measured and predicted curves over the stroke, coloured by time, and residuals."""
    times = _measurement_times(run_rows)
    norm = _ordered_norm(times.to_numpy())
    for i, (measurement, group) in enumerate(run_rows.groupby("measurement", sort=True)):
        group = group.sort_values("position_mm", kind="stable")
        x = group["position_mm"].to_numpy(dtype=float)
        t = float(times.loc[measurement])
        color = ORDERED_CMAP(norm(t))
        marker = MARKERS[i % len(MARKERS)]
        if _has_band(group):
            ax_curve.fill_between(
                x,
                group["lower"].to_numpy(dtype=float),
                group["upper"].to_numpy(dtype=float),
                color=color,
                alpha=0.15,
                linewidth=0,
            )
        ax_curve.plot(x, group["measured"].to_numpy(dtype=float), color=color, marker=marker)
        ax_curve.plot(x, group["predicted"].to_numpy(dtype=float), color=color, linestyle="--")
        ax_res.plot(
            x,
            group["residual"].to_numpy(dtype=float),
            color=color,
            marker=marker,
            label=_time_label(t),
        )
    ax_res.axhline(0.0, color="0.3", linewidth=0.5, zorder=0)
    ax_curve.set_title(f"Held-out run {short_name(run)}", loc="left")
    ax_curve.set_ylabel(ERROR_LABEL if first else "")
    ax_res.set_ylabel("Residual (µm)" if first else "")
    ax_res.set_xlabel(POSITION_LABEL)
    handles = [
        Line2D([], [], color="0.2", marker="o", label="Measured"),
        Line2D([], [], color="0.2", linestyle="--", label=f"Predicted ({_display(algorithm)})"),
    ]
    if _has_band(run_rows):
        handles.append(Patch(facecolor="0.2", alpha=0.15, label="Prediction interval"))
    ax_curve.legend(handles=handles, loc="best")
    _ordered_key(fig, ax_res, norm, len(times), TIME_LABEL)


def _prediction_in_time(ax_value, ax_res, rows: pd.DataFrame, algorithm: str, first: bool) -> None:
    """Single-position prediction: measured and predicted error, and the residual, against time."""
    rows = rows.sort_values("time_min", kind="stable")
    t = rows["time_min"].to_numpy(dtype=float)
    every = _markevery(len(rows))
    _measured_and_predicted(ax_value, t, rows, algorithm, markevery=every)
    ax_res.plot(t, rows["residual"].to_numpy(dtype=float), markevery=every, **_categorical_style(2))
    ax_res.axhline(0.0, color="0.3", linewidth=0.5, zorder=0)
    ax_value.set_ylabel(ERROR_LABEL if first else "")
    ax_res.set_ylabel("Residual (µm)" if first else "")
    ax_res.set_xlabel(TIME_LABEL)
    ax_value.legend(loc="best")


_METRIC_UNITS = {"k": "µm/m", "b": "µm", "error": "µm"}


@_styled
def fig_fold_comparison(metrics: pd.DataFrame, target: str = "error") -> Figure:
    """RMSE (top) and maximum absolute residual (bottom) of every fold, approach and algorithm.

    Grouped bars: one group per fold, one bar per (approach, algorithm) pair; a pair
    missing from a fold leaves a gap. Where the table has ``<metric>_lo`` and
    ``<metric>_hi`` (the metrics table's bootstrap intervals), each bar gets its error bar.

    Parameters
    ----------
    metrics : pandas.DataFrame
        Columns fold, approach, algorithm, target, rmse, max_abs.
    target : str, optional
        Which target's metrics to compare (``"error"``, ``"k"`` or ``"b"``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require_columns(
        metrics, ("fold", "approach", "algorithm", "target", "rmse", "max_abs"), "metrics"
    )
    rows = _select(metrics, "metrics", target=target)
    folds = natural_sorted(rows["fold"])
    pairs = sorted(
        {(str(a), str(g)) for a, g in zip(rows["approach"], rows["algorithm"], strict=False)},
        key=lambda p: (natural_key(p[0]), natural_key(p[1])),
    )
    unit = _METRIC_UNITS.get(str(target))
    suffix = f" ({unit})" if unit else ""
    width = SINGLE_COLUMN_IN if len(folds) * len(pairs) <= 12 else DOUBLE_COLUMN_IN
    fig = _new_figure(width, 3.6)
    ax_rmse, ax_max = fig.subplots(2, 1, sharex=True)
    bar_width = 0.8 / len(pairs)
    centres = np.arange(len(folds), dtype=float)
    keyed = rows.assign(
        approach=rows["approach"].astype(str), algorithm=rows["algorithm"].astype(str)
    )
    for j, (approach, algorithm) in enumerate(pairs):
        pair_rows = keyed[(keyed["approach"] == approach) & (keyed["algorithm"] == algorithm)]
        offsets = centres + (j - (len(pairs) - 1) / 2) * bar_width
        for ax, column in ((ax_rmse, "rmse"), (ax_max, "max_abs")):
            _fold_bars(ax, pair_rows, column, folds, offsets, bar_width, j, (approach, algorithm))
    ax_rmse.set_ylabel(f"RMSE{suffix}")
    ax_max.set_ylabel(f"Max |residual|{suffix}")
    labels = list(short_names(folds).values())
    # Long run names or many folds would overlap side by side: slant them.
    slanted = sum(len(label) for label in labels) > 40 or max(map(len, labels)) > 6
    ax_max.set_xticks(
        centres, labels, rotation=30 if slanted else 0, ha="right" if slanted else "center"
    )
    ax_max.set_xlabel("Fold (held-out run)")
    for ax in (ax_rmse, ax_max):
        ax.grid(axis="x", visible=False)
        ax.set_axisbelow(True)
    _top_legend(fig, ax_rmse)
    return fig


def _fold_bars(ax, pair_rows, column, folds, offsets, bar_width, j, pair) -> None:
    """One (approach, algorithm) pair's bars of one metric, with its bootstrap intervals."""
    approach, algorithm = pair
    heights = _by_fold(pair_rows, column, folds)
    keep = np.isfinite(heights)
    ax.bar(
        offsets[keep],
        heights[keep],
        width=bar_width,
        color=CATEGORICAL_COLORS[j % len(CATEGORICAL_COLORS)],
        edgecolor="0.2",
        linewidth=0.4,
        label=f"{_display(approach)}, {_display(algorithm)}",
    )
    if {f"{column}_lo", f"{column}_hi"} <= set(pair_rows.columns):
        lo = _by_fold(pair_rows, f"{column}_lo", folds)
        hi = _by_fold(pair_rows, f"{column}_hi", folds)
        shown = keep & np.isfinite(lo) & np.isfinite(hi)
        # The interval as computed, about its own centre: a percentile interval need
        # not contain the estimate (a skewed statistic, the tables' rounding).
        ax.errorbar(
            offsets[shown],
            (lo[shown] + hi[shown]) / 2,
            yerr=(hi[shown] - lo[shown]) / 2,
            fmt="none",
            ecolor="0.15",
            elinewidth=0.5,
            capsize=1.2,
        )


def _by_fold(rows: pd.DataFrame, column: str, folds) -> np.ndarray:
    values = rows.groupby("fold")[column].mean()
    return np.array([values.get(f, np.nan) for f in folds], dtype=float)


def fig_recommendation(recommendation: pd.DataFrame) -> Figure:
    """Held-out RMSE (top) and largest |residual| (bottom) per fold: the nested choice and the paper's.

    ``recommendation`` is the recommendation table: per fold the candidate chosen
    without the held-out run, its error there, and the paper's configuration's.
    """
    _require_columns(
        recommendation,
        ("fold", "rmse_um", "max_abs_um", "paper_rmse_um", "paper_max_abs_um"),
        "recommendation",
    )
    rows = [
        {"fold": r["fold"], "approach": label, "algorithm": "held out", "target": "error",
         "rmse": r[f"{prefix}rmse_um"], "max_abs": r[f"{prefix}max_abs_um"]}
        for r in recommendation.to_dict("records")
        for label, prefix in (("paper's configuration", "paper_"), ("recommendation", ""))
    ]  # fmt: skip
    return fig_fold_comparison(pd.DataFrame(rows), target="error")
