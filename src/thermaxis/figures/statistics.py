"""Figures of the statistics: the stability of the sensitive points, the sweep's critical difference."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from thermaxis.figures.style import (  # noqa: E402
    DOUBLE_COLUMN_IN,
    ORDERED_CMAP,
    SINGLE_COLUMN_IN,
    _new_figure,
    _require_columns,
    _styled,
    short_names,
)
from thermaxis.labels import natural_key, natural_sorted  # noqa: E402

__all__ = ["fig_selection_stability", "fig_sweep_critical_difference"]

_TARGETS = {"k": "slope k", "b": "intercept b", "pointwise": "point-by-point common set"}
# Above this many sensors the stability map keeps only the sensors chosen somewhere: a row
# per sensor of a 300-sensor record made the figure 52 in high, nearly all of it zeros.
MAX_STABILITY_ROWS = 40
# How many of the sweep's best configurations the critical-difference figure shows.
TOP_CONFIGURATIONS = 15


@_styled
def fig_selection_stability(stability: pd.DataFrame) -> Figure:
    """Per target a sensors x folds map of how often each sensor is chosen (0 to 1).

    ``stability`` is tables/selection_stability.csv. Ringed cells: the fold's own choice.
    Folds with no subset to resample (one training run) are left blank. Above
    :data:`MAX_STABILITY_ROWS` sensors, a sensor no subset chose has no row, and the axis
    label says how many are shown.
    """
    _require_columns(
        stability, ("fold", "target", "sensor", "chosen", "frequency"), "selection_stability"
    )
    targets = [t for t in _TARGETS if t in set(stability["target"])]
    folds = natural_sorted(stability["fold"].astype(str))
    sensors = sorted(set(stability["sensor"].astype(str)), key=natural_key)
    n_sensors = len(sensors)
    if n_sensors > MAX_STABILITY_ROWS:
        picked = stability["chosen"].astype(bool) | (stability["frequency"].fillna(0) > 0)
        kept = set(stability.loc[picked, "sensor"].astype(str))
        sensors = [s for s in sensors if s in kept] or sensors
    shown_folds = list(short_names(folds).values())
    longest = max(map(len, shown_folds), default=0)
    # Many folds, or long run names, side by side would overlap: slanted, they need height.
    slanted = len(folds) > 4 or longest > 6
    fig = _new_figure(
        SINGLE_COLUMN_IN if len(targets) == 1 else DOUBLE_COLUMN_IN,
        # At least the colour bar's label high, whatever few sensors there are.
        max(2.0, 0.6 + 0.17 * len(sensors)) + (0.03 * longest if slanted else 0.0),
    )
    axes = np.atleast_1d(fig.subplots(1, len(targets), sharey=True))
    image = None
    for ax, target in zip(axes, targets, strict=True):
        image = _stability_panel(ax, stability, target, sensors, folds, slanted)
    axes[0].set_ylabel(
        "Sensor"
        if len(sensors) == n_sensors
        else f"Sensor (the {len(sensors)} of {n_sensors} chosen in some subset)"
    )
    if image is not None:
        fig.colorbar(image, ax=list(axes), label="Share of subsets choosing it", shrink=0.9)
    return fig


def _stability_panel(ax, stability: pd.DataFrame, target: str, sensors, folds, slanted: bool):
    """One target's sensors x folds map, the folds' own choices ringed; returns the image."""
    rows = stability.loc[stability["target"] == target].assign(
        fold=lambda t: t["fold"].astype(str), sensor=lambda t: t["sensor"].astype(str)
    )
    grid = rows.pivot(index="sensor", columns="fold", values="frequency")
    grid = grid.reindex(index=sensors, columns=folds).to_numpy(dtype=float)
    chosen = rows.pivot(index="sensor", columns="fold", values="chosen")
    chosen = chosen.reindex(index=sensors, columns=folds).fillna(False).to_numpy(dtype=bool)
    image = ax.imshow(grid, cmap=ORDERED_CMAP, vmin=0.0, vmax=1.0, aspect="auto")
    ys, xs = np.nonzero(chosen)
    ax.scatter(xs, ys, s=30, facecolors="none", edgecolors="black", linewidths=0.7)
    ax.set_xticks(
        range(len(folds)),
        list(short_names(folds).values()),
        rotation=30 if slanted else 0,
        ha="right" if slanted else "center",
    )
    ax.set_yticks(range(len(sensors)), list(short_names(sensors).values()))
    ax.set_title(_TARGETS[target])
    ax.set_xlabel("Fold (held-out run)")
    ax.grid(False)
    return image


def _name(row) -> str:
    parts = [row["approach"], row["algorithm"], row["method"]]
    for factor in ("n_clusters", "similarity", "grade", "degree"):
        value = row.get(factor)
        if value is not None and not pd.isna(value):
            parts.append(str(value))
    return " ".join(str(p) for p in parts)


@_styled
def fig_sweep_critical_difference(ranking: pd.DataFrame) -> Figure:
    """Mean ranks over folds of the sweep's best configurations and the critical difference.

    ``ranking`` is sweep/ranking.csv with its uncertainty columns; a configuration whose
    mean rank lies within the critical difference of the best one's (the bar) is not
    distinguishable from it (Bonferroni-Dunn against the best, Demšar 2006).
    """
    _require_columns(ranking, ("rank", "config_id", "mean_rank", "critical_difference"), "ranking")
    top = ranking.loc[np.isfinite(ranking["mean_rank"].to_numpy(dtype=float))]
    top = top.sort_values("rank").head(TOP_CONFIGURATIONS)
    fig = _new_figure(DOUBLE_COLUMN_IN, 0.8 + 0.2 * len(top))
    ax = fig.subplots()
    if top.empty:
        ax.text(0.5, 0.5, "no configuration on every fold", ha="center", transform=ax.transAxes)
        return fig
    y = np.arange(len(top))[::-1]
    ranks = top["mean_rank"].to_numpy(dtype=float)
    distinguishable = top["distinguishable"].astype(str).str.lower().eq("true").to_numpy()
    ax.scatter(
        ranks[~distinguishable], y[~distinguishable], color="0.2", s=14, label="not distinguishable"
    )
    ax.scatter(
        ranks[distinguishable],
        y[distinguishable],
        color="tab:red",
        s=14,
        label="worse than the best",
    )
    best = ranks[0]
    cd = float(top["critical_difference"].iloc[0])
    ax.axvspan(best, best + cd, color="0.85", zorder=0, label=f"critical difference {cd:.1f}")
    ax.set_yticks(y, [f"#{int(r['rank'])} {_name(r)}" for _, r in top.iterrows()])
    ax.set_xlabel("Mean rank over folds (1 = lowest held-out max |residual|)")
    ax.legend(loc="lower right", fontsize=6)
    return fig
