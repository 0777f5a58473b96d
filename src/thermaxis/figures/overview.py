"""Small multiples of many runs: one small panel per run, on shared axes, for the combined conditions report."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from thermaxis.figures.style import (  # noqa: E402
    CATEGORICAL_COLORS,
    DOUBLE_COLUMN_IN,
    _new_figure,
    _require_columns,
    _styled,
    short_name,
)
from thermaxis.labels import natural_key  # noqa: E402

__all__ = ["COLUMNS", "largest_error_by_measurement", "fig_runs_overview"]

COLUMNS = 4


def largest_error_by_measurement(errors: pd.DataFrame) -> pd.DataFrame:
    """Per run and measurement: its time and the largest |unzeroed error| over the stroke."""
    _require_columns(errors, ("run", "measurement", "time_min", "error_um"), "errors")
    grouped = errors.assign(abs_um=errors["error_um"].abs()).groupby(
        ["run", "measurement"], sort=True
    )
    return pd.DataFrame(
        {"time_min": grouped["time_min"].first(), "largest_abs_um": grouped["abs_um"].max()}
    ).reset_index()


@_styled
def fig_runs_overview(errors: pd.DataFrame) -> Figure:
    """The largest |unzeroed error| of each measurement against time, one panel per run.

    Every panel shares both axes, so runs compare at a glance; runs in natural order
    (E2 before E10), four panels a row.
    """
    table = largest_error_by_measurement(errors)
    runs = sorted(table["run"].unique(), key=natural_key)
    if not runs:
        raise ValueError("the overview needs at least one run; the errors table is empty")
    rows = math.ceil(len(runs) / COLUMNS)
    fig = _new_figure(DOUBLE_COLUMN_IN, 1.3 * rows + 0.5)
    axes = np.atleast_1d(
        fig.subplots(rows, COLUMNS, sharex=True, sharey=True, squeeze=False)
    ).ravel()
    for i, (ax, run) in enumerate(zip(axes, runs, strict=False)):
        mine = table[table["run"] == run]
        ax.plot(
            mine["time_min"],
            mine["largest_abs_um"],
            marker="o",
            markersize=2,
            color=CATEGORICAL_COLORS[0],
        )
        ax.set_title(short_name(run), fontsize=7, loc="left")
        ax.tick_params(labelsize=6)
        if i % COLUMNS == 0:
            ax.set_ylabel("max |error| (µm)", fontsize=6)
        if i >= len(runs) - COLUMNS:  # the lowest panel of its column
            ax.set_xlabel("time (min)", fontsize=6)
    for ax in axes[len(runs) :]:
        ax.remove()
    return fig
