"""The cross-dataset figure: held-out error of each approach and algorithm on every dataset."""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = [
    "fig_heldout_error",
]


def fig_heldout_error(summary: pd.DataFrame):
    """Grouped bars: mean held-out max |residual| per dataset, one bar per approach x algorithm.

    The whisker reaches the worst fold.  Simulated datasets are marked in the tick label.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib
    from matplotlib.figure import Figure

    from thermaxis.figures import captions, style

    datasets = list(dict.fromkeys(summary["dataset"]))
    series = list(dict.fromkeys(zip(summary["approach"], summary["algorithm"], strict=False)))
    width = 0.8 / len(series)
    with matplotlib.rc_context(style.STYLE):
        fig = Figure(figsize=(style.DOUBLE_COLUMN_IN, 2.8), layout="constrained")
        ax = fig.subplots()
        for i, (approach, algorithm) in enumerate(series):
            rows = summary[
                (summary["approach"] == approach) & (summary["algorithm"] == algorithm)
            ].set_index("dataset")
            rows = rows.reindex(datasets)
            x = np.arange(len(datasets)) + (i - (len(series) - 1) / 2) * width
            mean = rows["mean_max_abs_um"].to_numpy(dtype=float)
            worst = rows["worst_max_abs_um"].to_numpy(dtype=float)
            color = style.CATEGORICAL_COLORS[i % len(style.CATEGORICAL_COLORS)]
            hatch = "" if approach == "decoupled" else "///"
            ax.bar(x, mean, width, color=color, hatch=hatch, edgecolor="white", linewidth=0.3,
                   label=f"{captions._display(approach)}, {captions._display(algorithm)}")  # fmt: skip
            ax.errorbar(
                x,
                mean,
                # worst >= mean; the clip only absorbs the tables' rounding.
                yerr=[np.zeros_like(mean), np.maximum(worst - mean, 0.0)],
                fmt="none",
                ecolor="0.3",
                elinewidth=0.6,
                capsize=1.5,
            )
        kinds = summary.drop_duplicates("dataset").set_index("dataset")["data"]
        labels = [
            f"{d}\n(SIMULATED)" if kinds[d] == "simulated" else f"{d}\n(measured)" for d in datasets
        ]
        ax.set_xticks(range(len(datasets)), labels)
        ax.set_ylabel("Held-out max |residual| (µm)\nmean over folds, whisker: worst")
        ax.grid(axis="x", visible=False)
        # Below the tick labels, in the columns that fit: an axes legend anchored outside
        # the axes was cut at the figure's edge with five long labels in a row.
        style._bottom_legend(fig, ax)
    return fig
