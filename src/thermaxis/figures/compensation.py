"""The thermal-drift figure of a compensated held-out run (after ISO 230-3's drift plots)."""

from __future__ import annotations

import matplotlib
import pandas as pd
from matplotlib.figure import Figure

from thermaxis.figures.style import CATEGORICAL_COLORS, MARKERS, STYLE, TIME_LABEL, short_name

__all__ = ["fig_compensation_drift"]


def fig_compensation_drift(summary: pd.DataFrame, fold) -> Figure:
    """Largest |deviation| over the stroke against time, uncompensated and compensated.

    ``summary`` is a fold's ``summary.csv``; measurements where the fallback policy held
    or ramped the values are ringed, so a flat compensated curve is not mistaken for a
    good model.
    """
    rows = summary[summary["fold"].astype(str) == str(fold)].sort_values(
        "measurement", kind="stable"
    )
    if rows.empty:
        raise ValueError(f"compensation summary has no rows for fold {fold!r}")
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(4.2, 2.8), layout="constrained")
        ax = fig.subplots()
        t = rows["time_min"].to_numpy(dtype=float)
        series = (
            ("largest_abs_uncompensated_um", "Pitch table only"),
            ("largest_abs_compensated_um", "With temperature compensation"),
        )
        for i, (column, label) in enumerate(series):
            ax.plot(
                t,
                rows[column].to_numpy(dtype=float),
                color=CATEGORICAL_COLORS[i],
                marker=MARKERS[i],
                label=label,
            )
        fallback = (rows["status"] != "ok").to_numpy()
        if fallback.any():
            ax.plot(
                t[fallback],
                rows["largest_abs_compensated_um"].to_numpy(dtype=float)[fallback],
                linestyle="none",
                marker="o",
                markersize=8,
                markerfacecolor="none",
                color="0.3",
                label="Fallback (hold / ramp)",
            )
        ax.set_xlabel(TIME_LABEL)
        ax.set_ylabel("Largest |deviation| over the stroke (µm)")
        ax.set_title(f"Held-out run {short_name(fold)}: thermal drift", loc="left")
        ax.set_ylim(bottom=0)
        ax.legend(loc="best")
    return fig
