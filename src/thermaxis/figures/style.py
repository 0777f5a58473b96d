"""The figures' shared style, axes helpers, provenance stamp and saving."""

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
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.cm import ScalarMappable  # noqa: E402
from matplotlib.colors import ListedColormap, Normalize  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from thermaxis.figures.captions import SIMULATED_NOTE
from thermaxis.figures.font_subsets import shared_font_subsets
from thermaxis.labels import natural_sorted

__all__ = [
    "STYLE",
    "SINGLE_COLUMN_IN",
    "DOUBLE_COLUMN_IN",
    "stamp_provenance",
    "save_figure",
]

SINGLE_COLUMN_IN = 3.5
DOUBLE_COLUMN_IN = 7.0

# Matplotlib's tab10, written out so that the palette does not depend on the version.
CATEGORICAL_COLORS = (
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
)  # fmt: skip
# Seven markers against ten colours: the (colour, marker) pair repeats only after 70 lines.
MARKERS = ("o", "s", "^", "v", "D", "<", ">")
# The light yellow end of viridis vanishes on white paper, hence the truncation.
ORDERED_CMAP = ListedColormap(
    plt.get_cmap("viridis")(np.linspace(0.0, 0.85, 256)), name="thermaxis_ordered"
)
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
    # Every figure asks for its layout by name (:func:`figure`); a user's matplotlibrc
    # must not give one to the figures save_figure strips of theirs.
    "figure.autolayout": False,
    "figure.constrained_layout.use": False,
    "savefig.dpi": 300,
    "savefig.bbox": None,
    "svg.hashsalt": "thermaxis",
    "svg.fonttype": "path",
    "pdf.fonttype": 42,
    # matplotlib 3.11's PDF writer sizes its font subsets by ps.fonttype: at its default
    # (Type 3, 256 glyphs) a minus sign (U+2212) lands in a second embedded subset of
    # the same font, and subsetting a font costs more than drawing the figure.
    "ps.fonttype": 42,
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
            raise ValueError(
                f"{name} table has no rows with {column}={value!r}; available: {choices}"
            )
        out = hit
    return out


# --------------------------------------------------------------------------- helpers


# Characters of a run, sensor or dataset name in a tick label, a legend or a panel title:
# a longer name squeezes the axes until constrained layout gives up. Captions and tables
# keep every name whole.
NAME_WIDTH = 20


def short_names(names: Iterable) -> dict[str, str]:
    """Each name as a figure shows it: one longer than :data:`NAME_WIDTH` keeps its start
    and its end around an ellipsis, the width growing until the shortened names are as
    distinct as the names (runs often differ only in a date or a suffix)."""
    names = list(dict.fromkeys(str(n) for n in names))
    for width in range(NAME_WIDTH, max(map(len, names), default=0)):
        shown = {n: _shortened(n, width) for n in names}
        if len(set(shown.values())) == len(names):
            return shown
    return {n: n for n in names}


def short_name(name) -> str:
    """One name as a figure shows it (:func:`short_names`)."""
    return _shortened(str(name), NAME_WIDTH)


def _shortened(name: str, width: int) -> str:
    if len(name) <= width:
        return name
    head = (width - 1) // 2
    return f"{name[:head]}…{name[len(name) - (width - 1 - head) :]}"


def _new_figure(width: float, height: float, **kwargs) -> Figure:
    return Figure(figsize=(width, height), layout="constrained", **kwargs)


def _categorical_style(index: int) -> dict:
    return {
        "color": CATEGORICAL_COLORS[index % len(CATEGORICAL_COLORS)],
        "marker": MARKERS[index % len(MARKERS)],
    }


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
        ax.legend(
            loc="upper left",
            bbox_to_anchor=(1.02, 1.0),
            borderaxespad=0.0,
            ncol=math.ceil(n_entries / 16),
        )


def _top_legend(fig: Figure, ax) -> None:
    """Legend of ``ax`` above the axes, where it can hide no data whatever the curves do:
    in up to four columns, fewer where long labels side by side would overrun the figure."""
    _fitting_legend(fig, ax, "outside upper center", 4)


def _bottom_legend(fig: Figure, ax, max_columns: int = 5) -> None:
    """Legend of ``ax`` below the axes and their tick labels, as :func:`_top_legend`."""
    _fitting_legend(fig, ax, "outside lower center", max_columns)


def _fitting_legend(fig: Figure, ax, loc: str, max_columns: int) -> None:
    """A figure legend the layout makes room for, in as many columns (up to ``max_columns``)
    as fit the figure's width: one wider than the figure is cut at its edge."""
    handles, labels = ax.get_legend_handles_labels()
    renderer = FigureCanvasAgg(fig).get_renderer()
    for ncol in range(min(len(labels), max_columns), 0, -1):
        legend = fig.legend(handles, labels, loc=loc, ncol=ncol)
        if ncol == 1 or legend.get_window_extent(renderer).width <= fig.bbox.width:
            return
        legend.remove()


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
    curve = run_errors.groupby("measurement").agg(
        time_min=("time_min", "min"), value=(value_column, "mean")
    )
    curve = curve.sort_values("time_min", kind="stable")
    ax.plot(
        curve["time_min"].to_numpy(dtype=float),
        curve["value"].to_numpy(dtype=float),
        markevery=_markevery(len(curve)),
        **_categorical_style(0),
    )
    ax.set_xlabel(TIME_LABEL)


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
    # Upright, in the figure's one font: an oblique note would embed a second font in
    # every PDF, and subsetting a font for a PDF costs more than drawing the figure.
    style = dict(fontsize=5.5, color="0.35", ha="right")
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
            raise ValueError(
                f"cannot save figure as {path.name!r}; expected a .png, .pdf or .svg suffix"
            )
    try:
        with matplotlib.rc_context(STYLE), shared_font_subsets():
            for i, path in enumerate(paths):
                fmt = path.suffix.lower().lstrip(".")
                path.parent.mkdir(parents=True, exist_ok=True)
                fig.savefig(
                    path, format=fmt, metadata=_SAVE_METADATA[fmt], dpi=dpi or STYLE["savefig.dpi"]
                )
                if i == 0:
                    # The layout is in figure fractions: solved once for the first
                    # format, it holds for the others. No engine at all, not "none": with
                    # "none"'s placeholder engine savefig still lays the figure out in a
                    # draw pass of its own before every later format (the same bytes).
                    fig.set_layout_engine(None)
    finally:
        plt.close(fig)
