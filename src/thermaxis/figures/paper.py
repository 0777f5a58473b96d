"""Figures of the paper (Figs. 2-17) and the fold comparison, for any dataset shape.

Every ``fig*`` function takes tidy tables, returns a :class:`matplotlib.figure.Figure`
and touches no file; :func:`save_figure` is the only writer.  The figures are built
as bare ``Figure`` objects (not through ``pyplot``) so that rendering many of them in
a workflow leaves no global figure registry behind.

Style and determinism
---------------------
All drawing happens inside ``matplotlib.rc_context(STYLE)``: global rcParams are
never changed, except that importing this module selects the non-interactive Agg
backend (figures are only ever written to files).  ``save_figure`` renders inside the
same context because several parameters (``svg.hashsalt``, ``pdf.fonttype``, the
minus sign, ...) are read when the file is written, not when the artists are made;
together with the fixed metadata below the bytes of PNG, PDF and SVG output are the
same for two renders of the same data.

Lines that have a natural order (measurements in time, target positions) are coloured
by their value on a sequential map and get a legend while there are few of them and a
colour bar when there are many; unordered lines (runs, sensors, algorithms) take a
fixed qualitative cycle of colours and markers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from thermaxis.figures.style import (
    CATEGORICAL_COLORS,
    DOUBLE_COLUMN_IN,
    ERROR_LABEL,
    MARKERS,
    ORDERED_CMAP,
    POSITION_LABEL,
    SINGLE_COLUMN_IN,
    SURFACE_CMAP,
    TIME_LABEL,
    _add_legend,
    _categorical_style,
    _markevery,
    _measurement_times,
    _new_figure,
    _ordered_key,
    _ordered_norm,
    _panel_label,
    _require_columns,
    _select,
    _series_in_time,
    _styled,
    _time_label,
    _top_legend,
    short_name,
    short_names,
    single_position,
)
from thermaxis.labels import natural_sorted

__all__ = [
    "fig2_positioning_error",
    "fig3_ambient",
    "fig5_unzeroed",
    "fig6_error_vs_time",
    "fig7_error_surface",
    "fig8_rezeroed",
    "fig9_other_runs",
    "fig10_temperature_rise",
    "fig12_slope_intercept",
]


def _curves_by_measurement(fig: Figure, ax, run_errors: pd.DataFrame, value_column: str) -> None:
    """One error curve per measurement, coloured by its time, with a legend or colour bar.

    With a single target position there is no curve along the stroke: the values are
    drawn against time instead.
    """
    if single_position(run_errors):
        _series_in_time(ax, run_errors, value_column)
        return
    times = _measurement_times(run_errors)
    norm = _ordered_norm(times.to_numpy())
    for i, (measurement, group) in enumerate(run_errors.groupby("measurement", sort=True)):
        curve = group.groupby("position_mm")[value_column].mean().sort_index()
        t = float(times.loc[measurement])
        ax.plot(
            curve.index.to_numpy(dtype=float),
            curve.to_numpy(dtype=float),
            color=ORDERED_CMAP(norm(t)),
            marker=MARKERS[i % len(MARKERS)],
            label=_time_label(t),
        )
    ax.set_xlabel(POSITION_LABEL)
    _ordered_key(fig, ax, norm, len(times), TIME_LABEL)


_ERRORS_COLUMNS = ("run", "measurement", "time_min", "position_mm", "error_um")


def _run_errors(errors: pd.DataFrame, run, extra: Sequence[str] = ()) -> pd.DataFrame:
    _require_columns(errors, (*_ERRORS_COLUMNS, *extra), "errors")
    return _select(errors, "errors", run=run)


# --------------------------------------------------------------------------- figures


@_styled
def fig2_positioning_error(errors: pd.DataFrame, run) -> Figure:
    """Positioning error of the first measurement of a run against position (the paper's Fig. 2).

    Parameters
    ----------
    errors : pandas.DataFrame
        Tidy errors table (run, measurement, time_min, position_mm, error_um, ...); passes
        are expected combined already, remaining duplicates of a position are averaged.
    run : str
        The run to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    run_errors = _run_errors(errors, run)
    first = run_errors[run_errors["measurement"] == run_errors["measurement"].min()]
    curve = first.groupby("position_mm")["error_um"].mean().sort_index()
    fig = _new_figure(SINGLE_COLUMN_IN, 2.4)
    ax = fig.subplots()
    ax.plot(
        curve.index.to_numpy(dtype=float),
        curve.to_numpy(dtype=float),
        label=f"Run {short_name(run)}, first measurement",
        **_categorical_style(0),
    )
    ax.set_xlabel(POSITION_LABEL)
    ax.set_ylabel(ERROR_LABEL)
    _add_legend(ax, 1)
    return fig


@_styled
def fig3_ambient(ambient: pd.DataFrame) -> Figure:
    """Ambient temperature of every run against elapsed time (the paper's Fig. 3).

    Parameters
    ----------
    ambient : pandas.DataFrame
        Long table with columns run, elapsed_min, temperature_c.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require_columns(ambient, ("run", "elapsed_min", "temperature_c"), "ambient")
    if ambient.empty:
        raise ValueError("ambient table is empty; expected at least one sample of one run")
    runs = natural_sorted(ambient["run"])
    fig = _new_figure(SINGLE_COLUMN_IN, 2.4)
    ax = fig.subplots()
    shown = short_names(runs)
    for i, run in enumerate(runs):
        series = ambient[ambient["run"] == run].sort_values("elapsed_min", kind="stable")
        series = series[np.isfinite(series["temperature_c"].to_numpy(dtype=float))]
        ax.plot(
            series["elapsed_min"].to_numpy(dtype=float),
            series["temperature_c"].to_numpy(dtype=float),
            markevery=_markevery(len(series)),
            label=f"Run {shown[str(run)]}",
            **_categorical_style(i),
        )
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("Ambient temperature (°C)")
    _top_legend(fig, ax)
    return fig


@_styled
def fig5_unzeroed(errors: pd.DataFrame, run) -> Figure:
    """Unzeroed errors of every measurement of a run against position (the paper's Fig. 5).

    One curve per measurement, labelled by the measurement's time since the run's first
    measurement.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tidy errors table.
    run : str
        The run to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    run_errors = _run_errors(errors, run)
    fig = _new_figure(SINGLE_COLUMN_IN, 2.6)
    ax = fig.subplots()
    _curves_by_measurement(fig, ax, run_errors, "error_um")
    ax.set_ylabel(ERROR_LABEL)
    return fig


@_styled
def fig6_error_vs_time(errors: pd.DataFrame, run) -> Figure:
    """Unzeroed error of a run against time, one curve per target position (the paper's Fig. 6).

    Parameters
    ----------
    errors : pandas.DataFrame
        Tidy errors table.
    run : str
        The run to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    run_errors = _run_errors(errors, run)
    positions = np.sort(run_errors["position_mm"].unique().astype(float))
    norm = _ordered_norm(positions)
    fig = _new_figure(SINGLE_COLUMN_IN, 2.6)
    ax = fig.subplots()
    for i, position in enumerate(positions):
        at = run_errors[run_errors["position_mm"] == position]
        curve = (
            at.groupby("measurement")
            .agg(time_min=("time_min", "min"), error_um=("error_um", "mean"))
            .sort_index()
        )
        ax.plot(
            curve["time_min"].to_numpy(dtype=float),
            curve["error_um"].to_numpy(dtype=float),
            color=ORDERED_CMAP(norm(position)),
            marker=MARKERS[i % len(MARKERS)],
            label=f"{position:g} mm",
        )
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel(ERROR_LABEL)
    _ordered_key(fig, ax, norm, len(positions), POSITION_LABEL)
    return fig


def _surface_quads(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[list, np.ndarray]:
    """Grid cells whose four corners are all measured, with their mean height.

    Matplotlib's ``plot_surface`` draws a cell with a missing corner as a stray
    triangle in the 'bad' colour; dropping the cell shows the gap honestly.
    """
    quads, heights = [], []
    for i in range(z.shape[0] - 1):
        for j in range(z.shape[1] - 1):
            corners = ((i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j))
            zs = np.array([z[c] for c in corners])
            if np.isfinite(zs).all():
                quads.append([(x[c], y[c], z[c]) for c in corners])
                heights.append(zs.mean())
    return quads, np.asarray(heights, dtype=float)


@_styled
def fig7_error_surface(errors: pd.DataFrame, run) -> Figure:
    """Unzeroed error of a run over position and time as a 3-D surface (the paper's Fig. 7).

    Every measurement's curve is drawn as a black line with markers; the grid cells
    between two neighbouring measurements and positions are filled and coloured by
    their height.  A cell with a missing reading stays open, and a run with one
    measurement or one position shows its curves only.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tidy errors table.
    run : str
        The run to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    positions, times, z = _error_grid(errors, run)
    x, y = np.meshgrid(positions, times)

    # Fixed axes instead of constrained layout, which does not see the labels of 3-D axes.
    # The cells are coloured by height for readability only; the z axis is their scale,
    # so no colour bar is needed.
    fig = Figure(figsize=(SINGLE_COLUMN_IN, 3.0))
    ax = fig.add_axes((0.02, 0.02, 0.9, 0.96), projection="3d")
    quads, heights = _surface_quads(x, y, z)
    if quads:
        cmap = plt.get_cmap(SURFACE_CMAP)
        ax.add_collection3d(
            Poly3DCollection(
                quads,
                facecolors=cmap(_ordered_norm(heights)(heights)),
                edgecolors="none",
                alpha=0.9,
            )
        )
    for row in range(z.shape[0]):
        ax.plot(x[row], y[row], z[row], color="k", linewidth=0.6, marker="o", markersize=1.8)
    finite = np.isfinite(z)
    if finite.any():
        ax.set_zlim(*_padded_limits(z[finite]))
    ax.set_xlim(*_padded_limits(positions))
    ax.set_ylim(*_padded_limits(times))
    ax.set_xlabel(POSITION_LABEL, labelpad=2)
    ax.set_ylabel("Time (min)", labelpad=2)
    ax.set_zlabel("Error (µm)", labelpad=2)
    ax.tick_params(pad=0)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(5))
    ax.view_init(elev=25.0, azim=-60.0)
    ax.set_box_aspect(None, zoom=0.88)
    return fig


def _error_grid(errors: pd.DataFrame, run):
    """A run's positions (mm), measurement times (min) and errors, measurement x position."""
    run_errors = _run_errors(errors, run)
    grid = run_errors.pivot_table(
        index="measurement", columns="position_mm", values="error_um", aggfunc="mean", dropna=False
    )
    grid = grid.sort_index().sort_index(axis=1)
    times = _measurement_times(run_errors).reindex(grid.index).to_numpy(dtype=float)
    positions = grid.columns.to_numpy(dtype=float)
    z = grid.to_numpy(dtype=float)
    return positions, times, z


def _padded_limits(values: np.ndarray) -> tuple[float, float]:
    """Data range with a little room; a single value gets a unit-wide window."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    if lo == hi:
        return lo - 0.5, hi + 0.5
    pad = 0.02 * (hi - lo)
    return lo - pad, hi + pad


@_styled
def fig8_rezeroed(errors: pd.DataFrame, run) -> Figure:
    """Re-zeroed errors of a run against position (the paper's Fig. 8).

    Every curve is that measurement minus its own reading at the first position, so
    all curves start at zero: the drift between measurements is hidden and only the
    expansion along the stroke is left, as the paper argues.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tidy errors table with the column ``rezeroed_um``.
    run : str
        The run to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    run_errors = _run_errors(errors, run, extra=("rezeroed_um",))
    fig = _new_figure(SINGLE_COLUMN_IN, 2.6)
    ax = fig.subplots()
    _curves_by_measurement(fig, ax, run_errors, "rezeroed_um")
    ax.set_ylabel("Re-zeroed positioning error (µm)")
    return fig


@_styled
def fig9_other_runs(errors: pd.DataFrame, runs: Sequence) -> Figure:
    """Unzeroed errors of several runs, one panel (a), (b), ... per run (the paper's Fig. 9).

    Panels are laid out two per row; each panel has its own error scale because the
    runs' error ranges differ.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tidy errors table.
    runs : sequence of str
        The runs, one panel each, in the given order.

    Returns
    -------
    matplotlib.figure.Figure
    """
    runs = list(runs) if not isinstance(runs, str) else [runs]
    if not runs:
        raise ValueError("fig9 needs at least one run; got an empty list")
    selected = [_run_errors(errors, run) for run in runs]
    ncols = min(len(runs), 2)
    nrows = math.ceil(len(runs) / ncols)
    fig = _new_figure(DOUBLE_COLUMN_IN, 2.4 * nrows)
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False)).ravel()
    shown = short_names(runs)
    for i, (run, run_errors) in enumerate(zip(runs, selected, strict=False)):
        ax = axes[i]
        _curves_by_measurement(fig, ax, run_errors, "error_um")
        ax.set_ylabel(ERROR_LABEL)
        ax.set_title(f"{_panel_label(i)} Run {shown[str(run)]}", loc="left")
    for ax in axes[len(runs) :]:
        ax.remove()
    return fig


@_styled
def fig10_temperature_rise(
    series: pd.DataFrame,
    sensors: Sequence[str] | None = None,
    signals: pd.DataFrame | None = None,
    units: dict | None = None,
) -> Figure:
    """Temperature rise of a run's sensors relative to the start of its first measurement (Fig. 10).

    The reference of each sensor is its value at ``elapsed_min == 0``, linearly
    interpolated between the neighbouring samples because sources sample at their own
    moments; a sensor without samples on one side of 0 takes its nearest sample.
    Sensors with no sample at all are left out.

    Parameters
    ----------
    series : pandas.DataFrame
        One run's cleaned series: ``time``, ``elapsed_min`` and one float column per sensor.
    sensors : sequence of str, optional
        Sensors to draw, in this order; default every sensor column in table order.
    signals : pandas.DataFrame, optional
        The run's operating signals on the same time base (``elapsed_min`` and one
        column per signal); when it has any, they are drawn in a panel below.
    units : dict, optional
        Unit of each signal, for the panel's axis label.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require_columns(series, ("elapsed_min",), "series")
    signal_names = (
        [] if signals is None else [c for c in signals.columns if c not in ("time", "elapsed_min")]
    )
    sensors = _requested_sensors(series, sensors)
    if signal_names:
        fig = _new_figure(SINGLE_COLUMN_IN, 3.8)
        ax, ax_signal = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1.3))
        _signal_panel(ax_signal, signals, signal_names, units or {})
    else:
        fig = _new_figure(SINGLE_COLUMN_IN, 2.6)
        ax = fig.subplots()
    if _draw_rises(ax, series, sensors) == 0:
        raise ValueError(
            "series table has no finite sample in any requested sensor; expected at least one"
        )
    ax.axhline(0.0, color="0.3", linewidth=0.5, zorder=0)
    if not signal_names:
        ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("Temperature rise (°C)")
    _top_legend(fig, ax)
    return fig


def _requested_sensors(series: pd.DataFrame, sensors) -> list:
    """The sensor columns to draw: ``sensors`` (one name or several), checked, or every numeric column."""
    available = [
        c
        for c in series.columns
        if c not in ("time", "elapsed_min") and pd.api.types.is_numeric_dtype(series[c])
    ]
    if sensors is None:
        return available
    sensors = [sensors] if isinstance(sensors, str) else list(sensors)
    unknown = [s for s in sensors if s not in available]
    if unknown:
        raise ValueError(
            f"series table has no sensor column(s) {', '.join(unknown)}; available: {', '.join(available)}"
        )
    return sensors


#: Fig. 10 names at most this many sensors: four rows of its four-column legend above the
#: axes.  With more (a machine logged at 60 points), a legend naming every one buries
#: the axes; the sensors that rise most keep a colour and a name, the others are drawn
#: thin and grey as one entry.
MAX_NAMED_RISES = 16


def _draw_rises(ax, series: pd.DataFrame, sensors: Sequence[str]) -> int:
    """Each sensor's rise since ``elapsed_min == 0`` (interpolated there); returns how many were drawn."""
    elapsed = series["elapsed_min"].to_numpy(dtype=float)
    order = np.argsort(elapsed, kind="stable")
    elapsed = elapsed[order]
    rises = {}
    for sensor in sensors:
        values = series[sensor].to_numpy(dtype=float)[order]
        ok = np.isfinite(values) & np.isfinite(elapsed)
        if ok.any():
            rises[sensor] = (elapsed[ok], values[ok] - np.interp(0.0, elapsed[ok], values[ok]))
    named, shown = set(rises), short_names(rises)
    if len(rises) > MAX_NAMED_RISES:
        # The largest |rise| first, ties in the given order; drawn in the given order.
        ranked = sorted(rises, key=lambda s: -float(np.abs(rises[s][1]).max()))
        named = set(ranked[: MAX_NAMED_RISES - 1])
    others = [s for s in rises if s not in named]
    for j, sensor in enumerate(others):
        x, rise = rises[sensor]
        label = f"other {len(others)} sensors" if j == 0 else "_nolegend_"
        ax.plot(x, rise, color="0.65", linewidth=0.5, zorder=1, label=label)
    for i, sensor in enumerate(s for s in rises if s in named):
        x, rise = rises[sensor]
        ax.plot(
            x,
            rise,
            markevery=_markevery(x.size),
            label=shown[str(sensor)],
            zorder=2,
            **_categorical_style(i),
        )
    return len(rises)


def _signal_panel(ax, signals: pd.DataFrame, names: Sequence[str], units: dict) -> None:
    """Operating signals (held values, so drawn as steps) against elapsed time."""
    elapsed = signals["elapsed_min"].to_numpy(dtype=float)
    for i, name in enumerate(names):
        unit = f" ({units[name]})" if units.get(name) else ""
        ax.step(
            elapsed,
            signals[name].to_numpy(dtype=float),
            where="post",
            color=CATEGORICAL_COLORS[i % len(CATEGORICAL_COLORS)],
            label=f"{name}{unit}",
        )
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("Operating signal")
    ax.legend(loc="best")


@_styled
def fig12_slope_intercept(kb: pd.DataFrame) -> Figure:
    """Slope k (top) and intercept b (bottom) of every measurement, one line per run (Fig. 12).

    Parameters
    ----------
    kb : pandas.DataFrame
        Columns run, measurement, k_um_per_m, b_um.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require_columns(kb, ("run", "measurement", "k_um_per_m", "b_um"), "kb")
    if kb.empty:
        raise ValueError("kb table is empty; expected one row per run and measurement")
    runs = natural_sorted(kb["run"])
    fig = _new_figure(SINGLE_COLUMN_IN, 3.6)
    ax_k, ax_b = fig.subplots(2, 1, sharex=True)
    shown = short_names(runs)
    for i, run in enumerate(runs):
        rows = kb[kb["run"] == run].sort_values("measurement", kind="stable")
        m = rows["measurement"].to_numpy(dtype=float)
        ax_k.plot(
            m,
            rows["k_um_per_m"].to_numpy(dtype=float),
            label=f"Run {shown[str(run)]}",
            **_categorical_style(i),
        )
        ax_b.plot(
            m,
            rows["b_um"].to_numpy(dtype=float),
            label=f"Run {shown[str(run)]}",
            **_categorical_style(i),
        )
    ax_k.set_ylabel("Slope k (µm/m)")
    ax_b.set_ylabel("Intercept b (µm)")
    ax_b.set_xlabel("Measurement")
    ax_b.xaxis.set_major_locator(MaxNLocator(integer=True))
    _top_legend(fig, ax_k)
    return fig
