"""Figures of a sweep: the heat map of configurations and the factor effects."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from thermaxis.figures.captions import _display
from thermaxis.figures.style import CATEGORICAL_COLORS, DOUBLE_COLUMN_IN, ORDERED_CMAP, STYLE


def fig_sweep_heatmap(tables: dict[str, pd.DataFrame], titles: dict[str, str] | None = None):
    """Heat maps of mean held-out max |residual| (um), one panel per approach.

    Parameters
    ----------
    tables : mapping of approach to DataFrame
        :func:`thermaxis.sweep.run.heatmap_table` results (rows n_clusters, columns algorithms).
    titles : mapping of approach to str, optional
        Panel titles; default the approach and what :func:`thermaxis.sweep.run.heatmap_table` held fixed.

    Returns
    -------
    matplotlib.figure.Figure
    """
    tables = {k: v for k, v in tables.items() if v.size}
    if not tables:
        # A grid of 'all' and 'fixed' only, or a dataset with fewer sensors than every
        # n_clusters: the rest of the sweep stands, and the figure says why it is empty.
        return _no_cluster_counts()
    values = np.concatenate([t.to_numpy(dtype=float).ravel() for t in tables.values()])
    values = values[np.isfinite(values)]
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(DOUBLE_COLUMN_IN, 2.8), layout="constrained")
        axes = np.atleast_1d(fig.subplots(1, len(tables), sharey=True))
        norm = (
            matplotlib.colors.Normalize(vmin=values.min(), vmax=values.max())
            if values.size
            else None
        )
        image = None
        for ax, (approach, table) in zip(axes, tables.items(), strict=False):
            data = table.to_numpy(dtype=float)
            image = ax.imshow(data, cmap=ORDERED_CMAP, norm=norm, aspect="auto", origin="lower")
            ax.set_xticks(range(table.shape[1]), [_display(a) for a in table.columns])
            ax.set_yticks(range(table.shape[0]), [str(n) for n in table.index])
            ax.grid(False)
            threshold = norm.vmin + 0.6 * (norm.vmax - norm.vmin) if norm is not None else 0.0
            for (i, j), v in np.ndenumerate(data):
                if np.isfinite(v):
                    ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=6.5,
                            color="black" if v > threshold else "white")  # fmt: skip
            title = (titles or {}).get(
                approach
            ) or f"{_display(approach)} ({table.attrs.get('held', '')})".replace(" ()", "")
            ax.set_title(title)
            ax.set_xlabel("Algorithm")
        axes[0].set_ylabel("Number of clusters")
        if image is not None:
            fig.colorbar(
                image, ax=list(axes), label="Mean held-out max |residual| (µm)", shrink=0.9
            )
    return fig


def _no_cluster_counts() -> Figure:
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(DOUBLE_COLUMN_IN, 1.2), layout="constrained")
        ax = fig.subplots()
        ax.set_axis_off()
        ax.text(
            0.5,
            0.5,
            "No configuration of this sweep varies the number of clusters: no fuzzy_grey or\n"
            "correlation setting of sweep.methods and sweep.n_clusters fits the dataset.",
            ha="center",
            va="center",
            transform=ax.transAxes,
        )
    return fig


def fig_factor_effects(ranking: pd.DataFrame):
    """One panel per factor: the configurations' mean held-out max |residual| by level.

    Box plots (median, quartiles, whiskers to 1.5 IQR) over every complete
    configuration where the factor applies; the dots are the configurations.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from thermaxis.sweep.run import FACTORS, factor_levels

    complete = ranking[ranking["n_folds"] == ranking["n_folds"].max()]
    factors = [f for f in FACTORS if complete[f].notna().any()]
    if not factors:
        raise ValueError("factor effects: the ranking has no complete configuration")
    ncols = min(4, len(factors))
    nrows = math.ceil(len(factors) / ncols)
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(DOUBLE_COLUMN_IN, 2.1 * nrows + 0.4), layout="constrained")
        axes = np.atleast_1d(fig.subplots(nrows, ncols, sharey=True)).ravel()
        for ax, factor in zip(axes, factors, strict=False):
            values = complete[[factor, "mean_max_abs"]].dropna()
            levels = factor_levels(values[factor], factor)
            groups = [
                values.loc[values[factor] == level, "mean_max_abs"].to_numpy(dtype=float)
                for level in levels
            ]
            ax.boxplot(
                groups, widths=0.55, showfliers=False, medianprops={"color": CATEGORICAL_COLORS[3]}
            )
            jitter = np.random.default_rng(0)  # fixed seed: the same figure every run
            for i, g in enumerate(groups, start=1):
                offsets = jitter.uniform(-0.18, 0.18, len(g))
                ax.plot(
                    i + offsets, g, ".", color=CATEGORICAL_COLORS[0], alpha=0.35, markersize=2.0
                )
            ax.set_xticks(range(1, len(levels) + 1), [_display(v) for v in levels],
                          rotation=30 if len(levels) > 3 else 0, ha="right" if len(levels) > 3 else "center")  # fmt: skip
            ax.set_title(factor.replace("_", " "))
            ax.grid(axis="x", visible=False)
        for ax in axes[len(factors) :]:
            ax.set_visible(False)
        for row in range(nrows):
            axes[row * ncols].set_ylabel("Mean max |residual| (µm)")
    return fig
