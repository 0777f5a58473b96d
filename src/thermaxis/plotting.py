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

import functools
import math
from collections.abc import Iterable, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from cycler import cycler  # noqa: E402
from matplotlib.cm import ScalarMappable  # noqa: E402
from matplotlib.colors import ListedColormap, Normalize  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from .captions import DISPLAY_NAMES, SIMULATED_NOTE, _display, figure_caption  # noqa: E402,F401
from .naming import natural_key, natural_sorted  # noqa: E402

__all__ = [
    "STYLE",
    "SINGLE_COLUMN_IN",
    "DOUBLE_COLUMN_IN",
    "SIMULATED_NOTE",
    "POINTWISE_APPROACH",
    "fig2_positioning_error",
    "fig3_ambient",
    "fig5_unzeroed",
    "fig6_error_vs_time",
    "fig7_error_surface",
    "fig8_rezeroed",
    "fig9_other_runs",
    "fig10_temperature_rise",
    "fig11_pointwise_prediction",
    "fig12_slope_intercept",
    "fig_kb_prediction",
    "fig_error_prediction",
    "fig_fold_comparison",
    "stamp_provenance",
    "save_figure",
    "figure_caption",
]

SINGLE_COLUMN_IN = 3.5
DOUBLE_COLUMN_IN = 7.0
POINTWISE_APPROACH = "pointwise"

# Matplotlib's tab10, written out so that the palette does not depend on the version.
CATEGORICAL_COLORS = (
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
)  # fmt: skip
# Seven markers against ten colours: the (colour, marker) pair repeats only after 70 lines.
MARKERS = ("o", "s", "^", "v", "D", "<", ">")
# The light yellow end of viridis vanishes on white paper, hence the truncation.
ORDERED_CMAP = ListedColormap(plt.get_cmap("viridis")(np.linspace(0.0, 0.85, 256)), name="thermaxis_ordered")
SURFACE_CMAP = "coolwarm"

# More entries than this: the legend moves out of the axes; more than
# MAX_LEGEND_ENTRIES ordered lines: a colour bar replaces the legend.
MAX_INSIDE_LEGEND = 6
MAX_LEGEND_ENTRIES = 10
# Dense time series get about this many markers per line so markers stay readable.
MARKERS_PER_SERIES = 12

STYLE: dict[str, object] = {
    "font.family": "sans-serif",
    # DejaVu Sans ships with matplotlib, so every machine draws the same glyphs.
    "font.sans-serif": ["DejaVu Sans"],
    "font.size": 8.0,
    "axes.titlesize": 8.0,
    "axes.labelsize": 8.0,
    "xtick.labelsize": 7.5,
    "ytick.labelsize": 7.5,
    "legend.fontsize": 7.0,
    "legend.frameon": False,
    "legend.handlelength": 2.2,
    "axes.linewidth": 0.6,
    "axes.grid": True,
    "grid.linewidth": 0.4,
    "grid.alpha": 0.35,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.prop_cycle": cycler(color=list(CATEGORICAL_COLORS)),
    "lines.linewidth": 1.0,
    "lines.markersize": 3.5,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "xtick.direction": "in",
    "ytick.direction": "in",
    "figure.dpi": 100,
    "savefig.dpi": 300,
    "savefig.bbox": None,
    "svg.hashsalt": "thermaxis",
    "svg.fonttype": "path",
    "pdf.fonttype": 42,
    "path.simplify": False,
}

_SAVE_METADATA = {
    "png": {"Software": None},
    "pdf": {"Creator": None, "Producer": None, "CreationDate": None},
    "svg": {"Creator": None, "Date": None},
}

ERROR_LABEL = "Positioning error (µm)"
POSITION_LABEL = "Position (mm)"
TIME_LABEL = "Time since first measurement (min)"


def _styled(func):
    """Build the figure inside the module style so global rcParams stay untouched."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


# --------------------------------------------------------------------------- checks


def _require_columns(table: pd.DataFrame, columns: Iterable[str], name: str) -> None:
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ValueError(
            f"{name} table lacks column(s) {', '.join(missing)}; it has {', '.join(map(str, table.columns))}"
        )


def _select(table: pd.DataFrame, name: str, **equals) -> pd.DataFrame:
    """Rows where every column equals the given value; a ValueError names the choices when none match."""
    out = table
    for column, value in equals.items():
        # Also match by text: ids that come from Snakemake wildcards are strings even
        # when the CSV reader turned the column into integers.
        hit = out[(out[column] == value) | (out[column].astype(str) == str(value))]
        if hit.empty:
            choices = ", ".join(map(str, natural_sorted(out[column]))) or "none"
            raise ValueError(f"{name} table has no rows with {column}={value!r}; available: {choices}")
        out = hit
    return out


# --------------------------------------------------------------------------- helpers


def _new_figure(width: float, height: float, **kwargs) -> Figure:
    return Figure(figsize=(width, height), layout="constrained", **kwargs)


def _categorical_style(index: int) -> dict:
    return {"color": CATEGORICAL_COLORS[index % len(CATEGORICAL_COLORS)], "marker": MARKERS[index % len(MARKERS)]}


def _markevery(n_points: int) -> int:
    return max(1, n_points // MARKERS_PER_SERIES)


def _panel_label(index: int) -> str:
    """(a), (b), ..., (z), (aa), (ab), ... for any number of panels."""
    letters = ""
    index += 1
    while index:
        index, rest = divmod(index - 1, 26)
        letters = chr(ord("a") + rest) + letters
    return f"({letters})"


def _add_legend(ax, n_entries: int) -> None:
    """Inside the axes for a few entries, outside on the right for many."""
    if n_entries <= MAX_INSIDE_LEGEND:
        ax.legend(loc="best")
    else:
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, ncol=math.ceil(n_entries / 16))


def _top_legend(fig: Figure, ax) -> None:
    """Legend of ``ax`` above the axes, where it can hide no data whatever the curves do."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncol=min(len(labels), 4))


def _ordered_norm(values: Sequence[float]) -> Normalize:
    values = np.asarray(values, dtype=float)
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return Normalize(0.0, 1.0)
    return Normalize(float(finite.min()), float(finite.max()))


def _ordered_key(fig: Figure, ax, norm: Normalize, n_lines: int, quantity_label: str) -> None:
    """Legend for a few ordered lines, a colour bar for many."""
    if n_lines <= MAX_LEGEND_ENTRIES:
        _add_legend(ax, n_lines)
    else:
        mappable = ScalarMappable(norm=norm, cmap=ORDERED_CMAP)
        bar = fig.colorbar(mappable, ax=ax, pad=0.02, aspect=30)
        bar.set_label(quantity_label)


def _measurement_times(errors: pd.DataFrame) -> pd.Series:
    """Each measurement's time: its first reading (readings of one measurement may carry their own times)."""
    return errors.groupby("measurement")["time_min"].min().sort_index()


def _time_label(minutes: float) -> str:
    return f"{minutes:.0f} min" if np.isfinite(minutes) else "time unknown"


def single_position(table: pd.DataFrame) -> bool:
    """A table of one target position: its curves are drawn against time, not position."""
    return table["position_mm"].nunique() == 1


def _series_in_time(ax, run_errors: pd.DataFrame, value_column: str) -> None:
    """A single-position run: its value at each measurement against time."""
    curve = run_errors.groupby("measurement").agg(time_min=("time_min", "min"), value=(value_column, "mean"))
    curve = curve.sort_values("time_min", kind="stable")
    ax.plot(
        curve["time_min"].to_numpy(dtype=float),
        curve["value"].to_numpy(dtype=float),
        markevery=_markevery(len(curve)),
        **_categorical_style(0),
    )
    ax.set_xlabel(TIME_LABEL)


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
        label=f"Run {run}, first measurement",
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
    for i, run in enumerate(runs):
        series = ambient[ambient["run"] == run].sort_values("elapsed_min", kind="stable")
        series = series[np.isfinite(series["temperature_c"].to_numpy(dtype=float))]
        ax.plot(
            series["elapsed_min"].to_numpy(dtype=float),
            series["temperature_c"].to_numpy(dtype=float),
            markevery=_markevery(len(series)),
            label=f"Run {run}",
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
        curve = at.groupby("measurement").agg(time_min=("time_min", "min"), error_um=("error_um", "mean")).sort_index()
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
    run_errors = _run_errors(errors, run)
    grid = run_errors.pivot_table(
        index="measurement", columns="position_mm", values="error_um", aggfunc="mean", dropna=False
    )
    grid = grid.sort_index().sort_index(axis=1)
    times = _measurement_times(run_errors).reindex(grid.index).to_numpy(dtype=float)
    positions = grid.columns.to_numpy(dtype=float)
    z = grid.to_numpy(dtype=float)
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
            Poly3DCollection(quads, facecolors=cmap(_ordered_norm(heights)(heights)), edgecolors="none", alpha=0.9)
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
    for i, (run, run_errors) in enumerate(zip(runs, selected)):
        ax = axes[i]
        _curves_by_measurement(fig, ax, run_errors, "error_um")
        ax.set_ylabel(ERROR_LABEL)
        ax.set_title(f"{_panel_label(i)} Run {run}", loc="left")
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
    signal_names = [] if signals is None else [c for c in signals.columns if c not in ("time", "elapsed_min")]
    available = [
        c for c in series.columns if c not in ("time", "elapsed_min") and pd.api.types.is_numeric_dtype(series[c])
    ]
    if sensors is None:
        sensors = available
    else:
        sensors = [sensors] if isinstance(sensors, str) else list(sensors)
        unknown = [s for s in sensors if s not in available]
        if unknown:
            raise ValueError(
                f"series table has no sensor column(s) {', '.join(unknown)}; available: {', '.join(available)}"
            )
    elapsed = series["elapsed_min"].to_numpy(dtype=float)
    order = np.argsort(elapsed, kind="stable")
    elapsed = elapsed[order]
    if signal_names:
        fig = _new_figure(SINGLE_COLUMN_IN, 3.8)
        ax, ax_signal = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1.3))
        _signal_panel(ax_signal, signals, signal_names, units or {})
    else:
        fig = _new_figure(SINGLE_COLUMN_IN, 2.6)
        ax = fig.subplots()
    drawn = 0
    for i, sensor in enumerate(sensors):
        values = series[sensor].to_numpy(dtype=float)[order]
        ok = np.isfinite(values) & np.isfinite(elapsed)
        if not ok.any():
            continue
        reference = np.interp(0.0, elapsed[ok], values[ok])
        ax.plot(
            elapsed[ok],
            values[ok] - reference,
            markevery=_markevery(int(ok.sum())),
            label=str(sensor),
            **_categorical_style(i),
        )
        drawn += 1
    if drawn == 0:
        raise ValueError("series table has no finite sample in any requested sensor; expected at least one")
    ax.axhline(0.0, color="0.3", linewidth=0.5, zorder=0)
    if not signal_names:
        ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("Temperature rise (°C)")
    _top_legend(fig, ax)
    return fig


def _signal_panel(ax, signals: pd.DataFrame, names: Sequence[str], units: dict) -> None:
    """Operating signals (held values, so drawn as steps) against elapsed time."""
    elapsed = signals["elapsed_min"].to_numpy(dtype=float)
    for i, name in enumerate(names):
        unit = f" ({units[name]})" if units.get(name) else ""
        ax.step(elapsed, signals[name].to_numpy(dtype=float), where="post", color=CATEGORICAL_COLORS[i % len(CATEGORICAL_COLORS)], label=f"{name}{unit}")
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
    for i, run in enumerate(runs):
        rows = kb[kb["run"] == run].sort_values("measurement", kind="stable")
        m = rows["measurement"].to_numpy(dtype=float)
        ax_k.plot(m, rows["k_um_per_m"].to_numpy(dtype=float), label=f"Run {run}", **_categorical_style(i))
        ax_b.plot(m, rows["b_um"].to_numpy(dtype=float), label=f"Run {run}", **_categorical_style(i))
    ax_k.set_ylabel("Slope k (µm/m)")
    ax_b.set_ylabel("Intercept b (µm)")
    ax_b.set_xlabel("Measurement")
    ax_b.xaxis.set_major_locator(MaxNLocator(integer=True))
    _top_legend(fig, ax_k)
    return fig


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


def _measured_and_predicted(ax, x: np.ndarray, rows: pd.DataFrame, algorithm: str, markevery=None) -> None:
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
    ax.plot(x, rows["measured"].to_numpy(dtype=float), label="Measured", markevery=markevery, **_categorical_style(0))
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
            part = rows[(rows["run"] == run) & (rows["target"] == target)].sort_values("measurement", kind="stable")
            _measured_and_predicted(ax, part["measurement"].to_numpy(dtype=float), part, algorithm)
            ax.set_ylabel(label if col == 0 else "")
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            if row == 0:
                ax.set_title(f"Held-out run {run}", loc="left")
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
            _prediction_in_time(axes[0, col], axes[1, col], rows[rows["run"] == run], algorithm, first=col == 0)
            axes[0, col].set_title(f"Held-out run {run}", loc="left")
        return fig
    for col, run in enumerate(runs):
        ax_curve, ax_res = axes[0, col], axes[1, col]
        run_rows = rows[rows["run"] == run]
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
            ax_res.plot(x, group["residual"].to_numpy(dtype=float), color=color, marker=marker, label=_time_label(t))
        ax_res.axhline(0.0, color="0.3", linewidth=0.5, zorder=0)
        ax_curve.set_title(f"Held-out run {run}", loc="left")
        ax_curve.set_ylabel(ERROR_LABEL if col == 0 else "")
        ax_res.set_ylabel("Residual (µm)" if col == 0 else "")
        ax_res.set_xlabel(POSITION_LABEL)
        handles = [
            Line2D([], [], color="0.2", marker="o", label="Measured"),
            Line2D([], [], color="0.2", linestyle="--", label=f"Predicted ({_display(algorithm)})"),
        ]
        if _has_band(run_rows):
            handles.append(Patch(facecolor="0.2", alpha=0.15, label="Prediction interval"))
        ax_curve.legend(handles=handles, loc="best")
        _ordered_key(fig, ax_res, norm, len(times), TIME_LABEL)
    return fig


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


@_styled
def fig11_pointwise_prediction(
    err_pred: pd.DataFrame, fold, algorithm: str, approach: str = POINTWISE_APPROACH
) -> Figure:
    """Point-by-point prediction of the held-out run(s): curves and residuals (the paper's Fig. 11).

    The same drawing as :func:`fig_error_prediction` for the point-by-point approach,
    whose label in ``err_pred`` is ``approach`` (default :data:`POINTWISE_APPROACH`).

    Parameters
    ----------
    err_pred : pandas.DataFrame
        Tidy error predictions.
    fold, algorithm
        Which predictions to draw.
    approach : str, optional
        Label of the point-by-point approach in ``err_pred``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return fig_error_prediction(err_pred, fold, approach, algorithm)


_METRIC_UNITS = {"k": "µm/m", "b": "µm", "error": "µm"}


@_styled
def fig_fold_comparison(metrics: pd.DataFrame, target: str = "error") -> Figure:
    """RMSE (top) and maximum absolute residual (bottom) of every fold, approach and algorithm.

    Grouped bars: one group per fold, one bar per (approach, algorithm) pair; a pair
    missing from a fold leaves a gap.

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
    _require_columns(metrics, ("fold", "approach", "algorithm", "target", "rmse", "max_abs"), "metrics")
    rows = _select(metrics, "metrics", target=target)
    folds = natural_sorted(rows["fold"])
    pairs = sorted(
        {(str(a), str(g)) for a, g in zip(rows["approach"], rows["algorithm"])},
        key=lambda p: (natural_key(p[0]), natural_key(p[1])),
    )
    unit = _METRIC_UNITS.get(str(target))
    suffix = f" ({unit})" if unit else ""
    width = SINGLE_COLUMN_IN if len(folds) * len(pairs) <= 12 else DOUBLE_COLUMN_IN
    fig = _new_figure(width, 3.6)
    ax_rmse, ax_max = fig.subplots(2, 1, sharex=True)
    bar_width = 0.8 / len(pairs)
    centres = np.arange(len(folds), dtype=float)
    keyed = rows.assign(approach=rows["approach"].astype(str), algorithm=rows["algorithm"].astype(str))
    for j, (approach, algorithm) in enumerate(pairs):
        pair_rows = keyed[(keyed["approach"] == approach) & (keyed["algorithm"] == algorithm)]
        offsets = centres + (j - (len(pairs) - 1) / 2) * bar_width
        for ax, column in ((ax_rmse, "rmse"), (ax_max, "max_abs")):
            by_fold = pair_rows.groupby("fold")[column].mean()
            heights = np.array([by_fold.get(f, np.nan) for f in folds], dtype=float)
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
    ax_rmse.set_ylabel(f"RMSE{suffix}")
    ax_max.set_ylabel(f"Max |residual|{suffix}")
    labels = [str(f) for f in folds]
    # Long run names or many folds would overlap side by side: slant them.
    slanted = sum(len(label) for label in labels) > 40 or max(map(len, labels)) > 6
    ax_max.set_xticks(centres, labels, rotation=30 if slanted else 0, ha="right" if slanted else "center")
    ax_max.set_xlabel("Fold (held-out run)")
    for ax in (ax_rmse, ax_max):
        ax.grid(axis="x", visible=False)
        ax.set_axisbelow(True)
    _top_legend(fig, ax_rmse)
    return fig


# --------------------------------------------------------------------------- output


@_styled
def stamp_provenance(fig: Figure, note: str = SIMULATED_NOTE) -> Figure:
    """Print a small provenance note (default :data:`SIMULATED_NOTE`) in the figure's bottom-right corner.

    On figures with constrained layout the note is the figure's ``supxlabel``, so the
    layout makes room for it instead of letting it cover the x labels.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure from one of the ``fig*`` functions (changed in place).
    note : str, optional
        The text.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``, for chaining.
    """
    if not note:
        raise ValueError("provenance note is empty; expected a sentence such as SIMULATED_NOTE")
    style = dict(fontsize=5.5, color="0.35", fontstyle="italic", ha="right")
    if fig.get_layout_engine() is not None:
        fig.supxlabel(note, x=0.995, **style)
    else:
        fig.text(0.995, 0.005, note, va="bottom", **style)
    return fig


def save_figure(fig: Figure, paths, dpi: float | None = None) -> None:
    """Write ``fig`` to every path (format from the suffix: png, pdf or svg), then close it.

    The output bytes depend only on the figure: timestamps and software versions are
    left out of the metadata and SVG ids are salted with a fixed string.  Parent
    folders are created.  All suffixes are checked before anything is written.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure, as returned by one of the ``fig*`` functions.
    paths : str or os.PathLike or iterable of them
        Output files.
    dpi : float, optional
        Resolution of raster output; default ``STYLE["savefig.dpi"]`` (300).
    """
    if isinstance(paths, (str, Path)) or not isinstance(paths, Iterable):
        paths = [paths]
    paths = [Path(p) for p in paths]
    if not paths:
        raise ValueError("save_figure needs at least one output path; got none")
    for path in paths:
        fmt = path.suffix.lower().lstrip(".")
        if fmt not in _SAVE_METADATA:
            raise ValueError(f"cannot save figure as {path.name!r}; expected a .png, .pdf or .svg suffix")
    try:
        with matplotlib.rc_context(STYLE):
            for path in paths:
                fmt = path.suffix.lower().lstrip(".")
                path.parent.mkdir(parents=True, exist_ok=True)
                fig.savefig(path, format=fmt, metadata=_SAVE_METADATA[fmt], dpi=dpi or STYLE["savefig.dpi"])
    finally:
        plt.close(fig)


# =========================================================================== sweep figures
# The sweep's figures (thermaxis.sweep's tables: heat map of the cluster count x algorithm,
# factor effects), kept apart from the paper's figures above.

__all__ += ["fig_sweep_heatmap", "fig_factor_effects"]


def fig_sweep_heatmap(tables: dict[str, pd.DataFrame], titles: dict[str, str] | None = None):
    """Heat maps of mean held-out max |residual| (um), one panel per approach.

    Parameters
    ----------
    tables : mapping of approach to DataFrame
        :func:`thermaxis.sweep.heatmap_table` results (rows n_clusters, columns algorithms).
    titles : mapping of approach to str, optional
        Panel titles; default the approach and what :func:`thermaxis.sweep.heatmap_table` held fixed.

    Returns
    -------
    matplotlib.figure.Figure
    """
    tables = {k: v for k, v in tables.items() if v.size}
    if not tables:
        raise ValueError("sweep heat map: no configuration sweeps n_clusters; expected fuzzy_grey or correlation in sweep.methods")
    values = np.concatenate([t.to_numpy(dtype=float).ravel() for t in tables.values()])
    values = values[np.isfinite(values)]
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(DOUBLE_COLUMN_IN, 2.8), layout="constrained")
        axes = np.atleast_1d(fig.subplots(1, len(tables), sharey=True))
        norm = matplotlib.colors.Normalize(vmin=values.min(), vmax=values.max()) if values.size else None
        image = None
        for ax, (approach, table) in zip(axes, tables.items()):
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
            title = (titles or {}).get(approach) or f"{_display(approach)} ({table.attrs.get('held', '')})".replace(" ()", "")
            ax.set_title(title)
            ax.set_xlabel("Algorithm")
        axes[0].set_ylabel("Number of clusters")
        if image is not None:
            fig.colorbar(image, ax=list(axes), label="Mean held-out max |residual| (µm)", shrink=0.9)
    return fig


def fig_factor_effects(ranking: pd.DataFrame):
    """One panel per factor: the configurations' mean held-out max |residual| by level.

    Box plots (median, quartiles, whiskers to 1.5 IQR) over every complete
    configuration where the factor applies; the dots are the configurations.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .sweep import FACTORS, factor_levels

    complete = ranking[ranking["n_folds"] == ranking["n_folds"].max()]
    factors = [f for f in FACTORS if complete[f].notna().any()]
    if not factors:
        raise ValueError("factor effects: the ranking has no complete configuration")
    ncols = min(4, len(factors))
    nrows = math.ceil(len(factors) / ncols)
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(DOUBLE_COLUMN_IN, 2.1 * nrows + 0.4), layout="constrained")
        axes = np.atleast_1d(fig.subplots(nrows, ncols, sharey=True)).ravel()
        for ax, factor in zip(axes, factors):
            values = complete[[factor, "mean_max_abs"]].dropna()
            levels = factor_levels(values[factor], factor)
            groups = [values.loc[values[factor] == level, "mean_max_abs"].to_numpy(dtype=float) for level in levels]
            ax.boxplot(groups, widths=0.55, showfliers=False, medianprops={"color": CATEGORICAL_COLORS[3]})
            jitter = np.random.default_rng(0)  # fixed seed: the same figure every run
            for i, g in enumerate(groups, start=1):
                offsets = jitter.uniform(-0.18, 0.18, len(g))
                ax.plot(i + offsets, g, ".", color=CATEGORICAL_COLORS[0], alpha=0.35, markersize=2.0)
            ax.set_xticks(range(1, len(levels) + 1), [_display(v) for v in levels],
                          rotation=30 if len(levels) > 3 else 0, ha="right" if len(levels) > 3 else "center")  # fmt: skip
            ax.set_title(factor.replace("_", " "))
            ax.grid(axis="x", visible=False)
        for ax in axes[len(factors):]:
            ax.set_visible(False)
        for row in range(nrows):
            axes[row * ncols].set_ylabel("Mean max |residual| (µm)")
    return fig
