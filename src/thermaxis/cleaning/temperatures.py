"""Cleaning of one run's raw temperature logs.

Temperatures
------------
Each source (acquisition box, wireless nut sensor, CNC HMI, ...) logs on its own
clock and at its own, possibly irregular, rate.  :func:`clean_temperatures` repairs
each sensor's *native* series and then puts every sensor on one regular time grid.
The order of the steps matters:

1. **Exact duplicate rows** are dropped first: they are logging artefacts and would
   otherwise count twice in the spike filter's window.
2. **Clock offset** (from ``dataset.yaml``) is added to the source's timestamps.  A
   constant shift does not change steps 3-5 (they work per sample or per sample
   index), but every later step that compares *times* must see corrected times.
3. **Out-of-range** readings (open or short circuit, e.g. 850 C or -200 C) are removed
   before anything statistical: one such value would dominate any mean.
4. **Repeated timestamps** with different values are merged into their mean (after
   step 3, so an open-circuit value never enters the mean), and each sensor that had
   them is named in a warning (``merged``).
5. **Spikes** (:func:`~thermaxis.cleaning.spikes.spike_mask`) on the native series, so the test sees the raw
   sampling and not interpolated points: a spike is one or two samples beyond both
   neighbours that returns, judged against a limit that cannot fall below two steps of
   the logger's resolution, so a heating ramp, however quantised or steep, is kept to
   its last sample. The record's first and last samples, which have one neighbour
   only, are judged by a physical rate limit.
6. **Estimated clock offsets** (optional): after steps 3-5, because a spike or an
   open-circuit value would dominate the cross-correlation.
7. **Grid**: the remaining valid samples are interpolated *linearly in time* onto a
   grid aligned to whole multiples of ``interval_s``.  Interpolation, not bin
   averaging, so a fast transient is not smeared by the bin width and a linear
   temperature ramp is reproduced exactly.
8. **Gaps**: a grid point whose nearest valid samples on either side are more than
   ``max_gap_s`` apart stays NaN and the gap is reported.  Before a sensor's first
   (after its last) valid sample, its value is held for up to ``max_gap_s / 2``: that
   is the farthest an interior point of an allowed gap can be from a real sample.

Removed spikes and out-of-range values leave short gaps that step 7 fills; the QC
table says how many grid points each repair touched.

This module does steps 1-4 and 6 and puts the pieces together; the spike and excursion
tests of step 5 are :mod:`thermaxis.cleaning.spikes`, the grid of steps 7-8
:mod:`thermaxis.cleaning.grid`, the clock offsets of step 6 are estimated by
:mod:`thermaxis.cleaning.clock`. Operating signals go on the same grid by
:mod:`thermaxis.cleaning.signals`, and the temperatures during each measurement are
read by :mod:`thermaxis.cleaning.windows`. The interferometer readings are cleaned by
:mod:`thermaxis.cleaning.passes` (one error per target from a measurement's one or two
passes).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from thermaxis.cleaning._timebase import _NS, _as_ns, _timestamp_ns
from thermaxis.cleaning.clock import OffsetNotFound, _best_offset
from thermaxis.cleaning.grid import _gap_table, _grid, _onto_grid
from thermaxis.cleaning.spikes import _TIE_RTOL, excursions, spike_limit, spike_mask
from thermaxis.config import TemperatureCleaning
from thermaxis.labels import sort_naturally

__all__ = [
    "CleanedTemperatures",
    "QC_COLUMNS",
    "EXCURSION_COLUMNS",
    "MERGED_COLUMNS",
    "clean_temperatures",
]

QC_COLUMNS = [
    "sensor",
    "source",
    "n_raw",
    "n_duplicates",
    "n_out_of_range",
    "n_spikes",
    "n_interpolated",
    "n_edge_held",
    "n_long_gap",
    "longest_gap_s",
    "clock_offset_s",
    "offset_estimated",
]
EXCURSION_COLUMNS = ["sensor", "source", "start", "end", "duration_s", "size_c", "action"]
MERGED_COLUMNS = ["sensor", "source", "n_timestamps", "first", "spread_c"]


@dataclass(frozen=True)
class CleanedTemperatures:
    """Result of :func:`clean_temperatures`.

    frame : ``time`` + one column per sensor on the regular grid (NaN in long gaps).
    qc    : one row per sensor, columns :data:`QC_COLUMNS`.
    gaps  : one row per gap left NaN, columns :data:`~thermaxis.cleaning.grid.GAP_COLUMNS` (``start``/``end``
            are the valid samples bounding it, or the grid's ends for a sensor that
            starts late or stops early).
    excursions : one row per departure that jumped away and back (:func:`~thermaxis.cleaning.spikes.excursions`),
            columns :data:`EXCURSION_COLUMNS` (``start``/``end``: its first and last
            departing samples; ``size_c`` signed).
    merged : one row per sensor whose log repeats a timestamp with different readings
            (step 4), columns :data:`MERGED_COLUMNS`: how many such timestamps, the
            first (on the corrected clock, as excursions), and the largest spread of
            readings merged into one mean.
    """

    frame: pd.DataFrame
    qc: pd.DataFrame
    gaps: pd.DataFrame
    excursions: pd.DataFrame
    merged: pd.DataFrame
    # (source, why) per source whose clock offset could not be estimated (why: the
    # OffsetNotFound's reason): it keeps the declared offset (qc's offset_estimated is
    # False for its sensors).
    unestimated: tuple[tuple[str, str], ...] = ()


@dataclass
class _Native:
    """One sensor's valid samples after the native-series repairs, and their counts."""

    sensor: str
    source: str
    t: np.ndarray
    v: np.ndarray
    n_raw: int
    n_duplicates: int
    n_out_of_range: int
    n_spikes: int
    clock_offset_s: float
    excursions: tuple[tuple[int, int, float], ...] = ()  # (start ns, end ns, size C)
    merged: tuple[int, int, float] | None = None  # (timestamps, first ns, largest spread C)
    offset_estimated: bool = False


def _clean_source(
    name: str, frame: pd.DataFrame, offset_s: float, settings: TemperatureCleaning
) -> list[_Native]:
    if "time" not in frame.columns:
        raise ValueError(f"temperature source {name!r}: missing column 'time'")
    sensors = [c for c in frame.columns if c != "time"]
    values = frame[sensors].to_numpy(dtype=float)
    n_raw = np.isfinite(values).sum(axis=0)

    repeated = frame.duplicated(keep="first").to_numpy()
    duplicates = np.isfinite(values[repeated]).sum(axis=0)
    values = values[~repeated]
    t = _as_ns(frame["time"])[~repeated] + int(round(offset_s * _NS))
    if np.any(np.diff(t) < 0):
        raise ValueError(
            f"temperature source {name!r}: column 'time' goes backwards; expected non-decreasing times"
        )

    low, high = settings.limits_c
    out_of_range = ~np.isnan(values) & ((values < low) | (values > high))
    values = np.where(out_of_range, np.nan, values)

    values, t, duplicates, merged = _merge_repeated_times(values, t, sensors, duplicates)

    natives = []
    for j, sensor in enumerate(sensors):
        ok = np.isfinite(values[:, j])
        ts, vs = t[ok], values[ok, j]
        ts, vs, n_spikes, events = _despiked(ts, vs, settings)
        natives.append(
            _Native(
                sensor=str(sensor),
                source=name,
                t=ts,
                v=vs,
                n_raw=int(n_raw[j]),
                n_duplicates=int(duplicates[j]),
                n_out_of_range=int(out_of_range[:, j].sum()),
                n_spikes=n_spikes,
                clock_offset_s=float(offset_s),
                excursions=events,
                merged=merged[j],
            )
        )
    return natives


def _merge_repeated_times(values: np.ndarray, t: np.ndarray, sensors: list, duplicates):
    """One row per timestamp, readings logged at the same time averaged (step 4).

    Returns the values, times and duplicate counts after merging, and per sensor
    ``(rows merged with differing readings, first such time, largest spread)`` or None.
    """
    merged: list = [None] * len(sensors)
    if t.size and np.any(np.diff(t) == 0):
        grouped = pd.DataFrame(values, columns=sensors).groupby(t, sort=True)
        counts = grouped.count().to_numpy()
        duplicates = duplicates + np.clip(counts - 1, 0, None).sum(axis=0)
        means = grouped.mean()
        # A timestamp logged twice with different readings: merged, and said (step 4).
        spread = (grouped.max() - grouped.min()).to_numpy()
        conflicting = (counts >= 2) & (spread > 0)
        values = means.to_numpy(dtype=float)
        t = means.index.to_numpy(dtype=np.int64)
        for j in np.flatnonzero(conflicting.any(axis=0)):
            rows = np.flatnonzero(conflicting[:, j])
            merged[j] = (int(rows.size), int(t[rows[0]]), float(spread[rows, j].max()))
    return values, t, duplicates, merged


def _despiked(ts: np.ndarray, vs: np.ndarray, settings: TemperatureCleaning):
    """One sensor's samples without spikes (and faulty excursions), the spike count and
    the excursions found, as (first time, last time, size)."""
    spikes = spike_mask(
        ts / _NS,
        vs,
        threshold=settings.spike_threshold,
        min_deviation=settings.spike_min_deviation_c,
        max_rate_c_per_min=settings.spike_max_rate_c_per_min,
        window_s=settings.spike_window_s,
    )
    ts, vs = ts[~spikes], vs[~spikes]
    limit = spike_limit(ts / _NS, vs, settings.spike_threshold, settings.spike_min_deviation_c)
    found = excursions(ts / _NS, vs, limit * (1.0 + _TIE_RTOL))
    if settings.excursions == "fault" and found:
        faulty = np.zeros(ts.shape, dtype=bool)
        for first, last, _ in found:
            faulty[first : last + 1] = True
        events = tuple((int(ts[a]), int(ts[b]), size) for a, b, size in found)
        ts, vs = ts[~faulty], vs[~faulty]
    else:
        events = tuple((int(ts[a]), int(ts[b]), size) for a, b, size in found)
    return ts, vs, int(spikes.sum()), events


def _estimate_offsets(
    natives: list[_Native], sources: Sequence[str], settings: TemperatureCleaning
) -> list[tuple[str, str]]:
    """Shift every non-reference source by its estimated residual offset (in place).

    A source whose offset cannot be estimated (no shared transient, too little overlap)
    keeps its declared one: one logger's clock must not cost the run. Returns those
    sources, each with why.
    """
    by_source = {s: [n for n in natives if n.source == s] for s in sources}
    reference = settings.reference_source
    if reference is None:
        reference = max(sources, key=lambda s: len(by_source[s]))  # first on ties
    elif reference not in by_source:
        raise ValueError(
            f"reference_source {reference!r} is not one of the run's sources {list(sources)}"
        )
    ref = [(n.t, n.v) for n in by_source[reference]]
    unestimated = []
    for source in sources:
        if source == reference:
            continue
        # Sensors of one source share one clock: the pair of this source's and the
        # reference's sensors that match best decides.
        try:
            best_offset, _ = _best_offset(
                [(n.t, n.v) for n in by_source[source]],
                ref,
                settings.max_offset_s,
                settings.offset_step_s,
            )
        except OffsetNotFound as exc:
            unestimated.append((source, exc.reason))
            continue
        shift = int(round(best_offset * _NS))
        for native in by_source[source]:
            native.t = native.t + shift
            native.excursions = tuple(
                (a + shift, b + shift, size) for a, b, size in native.excursions
            )
            native.clock_offset_s += best_offset
            native.offset_estimated = True
    return unestimated


def clean_temperatures(
    sources: Mapping[str, pd.DataFrame],
    clock_offsets_s: Mapping[str, float],
    settings: TemperatureCleaning,
    start=None,
    end=None,
) -> CleanedTemperatures:
    """Clean one run's temperature logs and put every sensor on one regular grid.

    Parameters
    ----------
    sources : source name -> DataFrame with ``time`` (naive datetimes, non-decreasing)
        and one float column per sensor (NaN = missing).
    clock_offsets_s : source name -> seconds to ADD to its timestamps (missing = 0).
    settings : :class:`TemperatureCleaning`.
    start, end : grid span (anything ``pd.Timestamp`` accepts); default the first and
        last valid sample of any sensor after the clock corrections.  Grid points are
        the whole multiples of ``interval_s`` inside [start, end].

    Returns
    -------
    CleanedTemperatures
        See the module docstring for the order of the repairs and why.

    Raises
    ------
    ValueError
        A sensor in two sources, a source without ``time`` or going back in time, or an
        empty grid. (A clock offset that cannot be estimated is kept as declared and
        listed in ``unestimated``.)
    """
    if not sources:
        raise ValueError("no temperature sources: expected at least one source DataFrame")
    natives = _native_series(sources, clock_offsets_s, settings)
    unestimated = []
    if settings.estimate_clock_offsets and len(sources) > 1:
        unestimated = _estimate_offsets(natives, list(sources), settings)
    grid = _grid(*_grid_span(natives, start, end), int(round(settings.interval_s * _NS)))
    columns = {"time": grid.astype("datetime64[ns]")}
    qc_rows, gap_rows = [], []
    for native in natives:
        values, counts, gaps = _onto_grid(native.t, native.v, grid, settings.max_gap_s)
        columns[native.sensor] = values
        qc_rows.append(_qc_row(native, counts))
        gap_rows.extend((native.sensor, a, b, (b - a) / _NS, kind) for a, b, kind in gaps)
    return CleanedTemperatures(
        frame=pd.DataFrame(columns),
        qc=pd.DataFrame(qc_rows, columns=QC_COLUMNS),
        gaps=_gap_table(gap_rows),
        excursions=_excursion_table(natives, settings.excursions),
        merged=_merged_table(natives),
        unestimated=tuple(unestimated),
    )


def _excursion_table(natives: list[_Native], policy: str) -> pd.DataFrame:
    """Every excursion (:data:`EXCURSION_COLUMNS`), in time order."""
    action = "dropped as a sensor fault" if policy == "fault" else "kept as data"
    rows = [
        (n.sensor, n.source, a, b, (b - a) / _NS, size, action)
        for n in natives
        for a, b, size in n.excursions
    ]
    table = pd.DataFrame(rows, columns=EXCURSION_COLUMNS)
    table["start"] = table["start"].to_numpy(dtype=np.int64).astype("datetime64[ns]")
    table["end"] = table["end"].to_numpy(dtype=np.int64).astype("datetime64[ns]")
    table = table.astype({"duration_s": float, "size_c": float})
    return sort_naturally(table, ["start", "sensor"])


def _merged_table(natives: list[_Native]) -> pd.DataFrame:
    """Every sensor whose log repeats a timestamp with different readings (:data:`MERGED_COLUMNS`)."""
    rows = [(n.sensor, n.source, *n.merged) for n in natives if n.merged is not None]
    table = pd.DataFrame(rows, columns=MERGED_COLUMNS)
    table["first"] = table["first"].to_numpy(dtype=np.int64).astype("datetime64[ns]")
    return table.astype({"n_timestamps": int, "spread_c": float})


def _native_series(
    sources: Mapping[str, pd.DataFrame],
    clock_offsets_s: Mapping[str, float],
    settings: TemperatureCleaning,
) -> list[_Native]:
    """Every sensor's repaired native series (steps 1-5), each sensor in exactly one source."""
    natives: list[_Native] = []
    seen: dict[str, str] = {}
    for name, frame in sources.items():
        for native in _clean_source(name, frame, float(clock_offsets_s.get(name, 0.0)), settings):
            if native.sensor in seen:
                raise ValueError(
                    f"sensor {native.sensor!r} appears in sources {seen[native.sensor]!r} and {name!r}; expected one"
                )
            seen[native.sensor] = name
            natives.append(native)
    return natives


def _grid_span(natives: list[_Native], start, end) -> tuple[int, int]:
    """The grid's span in ns: ``start`` and ``end`` where given, else the first and last valid sample."""
    valid_times = [n.t for n in natives if n.t.size]
    if (start is None or end is None) and not valid_times:
        raise ValueError("no valid temperature sample in any source: cannot place the time grid")
    start_ns = _timestamp_ns(start) if start is not None else int(min(t[0] for t in valid_times))
    end_ns = _timestamp_ns(end) if end is not None else int(max(t[-1] for t in valid_times))
    return start_ns, end_ns


def _qc_row(native: _Native, counts: dict) -> dict:
    """One sensor's row of the QC table: the native repairs' counts, then the grid's."""
    return dict(
        sensor=native.sensor,
        source=native.source,
        n_raw=native.n_raw,
        n_duplicates=native.n_duplicates,
        n_out_of_range=native.n_out_of_range,
        n_spikes=native.n_spikes,
        **counts,
        clock_offset_s=native.clock_offset_s,
        offset_estimated=native.offset_estimated,
    )
