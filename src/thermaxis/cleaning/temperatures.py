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
5. **Spikes** (:func:`spike_mask`) on the native series, so the test sees the raw
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

The interferometer readings are cleaned by :mod:`thermaxis.cleaning.passes` (one error
per target from a measurement's one or two passes), the clock offsets of step 6 are
estimated by :mod:`thermaxis.cleaning.clock`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.lib.stride_tricks import sliding_window_view

from thermaxis.cleaning._timebase import _NS, MAD_TO_SIGMA, _as_ns, _iso, _timestamp_ns
from thermaxis.cleaning.clock import OffsetNotFound, _best_offset
from thermaxis.config import TemperatureCleaning
from thermaxis.dataset.plausibility import usable_signal_readings
from thermaxis.labels import sort_naturally

__all__ = [
    "CleanedTemperatures",
    "GAP_FACTOR",
    "QC_COLUMNS",
    "GAP_COLUMNS",
    "EXCURSION_COLUMNS",
    "MERGED_COLUMNS",
    "MAX_SPIKE_SAMPLES",
    "interior_excursions",
    "neighbour_residuals",
    "noise_sigma",
    "sigma_of_residuals",
    "resolution",
    "spike_limit",
    "spike_mask",
    "excursions",
    "clean_temperatures",
    "GapOverlap",
    "gap_overlaps",
    "signals_on_grid",
    "temperatures_in_windows",
]
# A spacing between valid samples longer than this many times the sensor's median
# spacing is a gap (lost packet, removed spike, ...): grid points in it are counted as
# interpolated in the QC table.  1.5 tolerates the jitter of irregular (wireless) sampling.
GAP_FACTOR = 1.5
# Relative tolerance of threshold comparisons: a tie must not flip on float rounding.
_TIE_RTOL = 1e-9

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
GAP_COLUMNS = ["sensor", "start", "end", "duration_s", "kind"]
EXCURSION_COLUMNS = ["sensor", "source", "start", "end", "duration_s", "size_c", "action"]
MERGED_COLUMNS = ["sensor", "source", "n_timestamps", "first", "spread_c"]


@dataclass(frozen=True)
class CleanedTemperatures:
    """Result of :func:`clean_temperatures`.

    frame : ``time`` + one column per sensor on the regular grid (NaN in long gaps).
    qc    : one row per sensor, columns :data:`QC_COLUMNS`.
    gaps  : one row per gap left NaN, columns :data:`GAP_COLUMNS` (``start``/``end``
            are the valid samples bounding it, or the grid's ends for a sensor that
            starts late or stops early).
    excursions : one row per departure that jumped away and back (:func:`excursions`),
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


# ----------------------------------------------------------------------------- spikes

# A spike is at most this many adjacent samples: longer excursions are real events.
MAX_SPIKE_SAMPLES = 2
# Second-difference residuals of white noise have sqrt(1 + 1/4 + 1/4) times its sigma.
_RESIDUAL_TO_SIGMA = 1.0 / np.sqrt(1.5)


def resolution(values) -> float:
    """The logger's resolution as the data shows it: the smallest step between two of its levels.

    0 for fewer than two distinct values. On unquantised data it is tiny and harmless: it
    is a floor under the spike limit, and the noise scale is then larger.
    """
    levels = np.unique(np.asarray(values, dtype=float))
    return float(np.diff(levels).min()) if levels.size > 1 else 0.0


def neighbour_residuals(t_s, values) -> np.ndarray:
    """Each interior sample minus the line through its two neighbours (in time)."""
    t, x = np.asarray(t_s, dtype=float), np.asarray(values, dtype=float)
    if x.size < 3:
        return np.empty(0)
    span = t[2:] - t[:-2]
    w = np.divide(t[1:-1] - t[:-2], span, out=np.full(span.shape, 0.5), where=span > 0)
    return x[1:-1] - (x[:-2] + w * (x[2:] - x[:-2]))


def sigma_of_residuals(residuals) -> float:
    """Robust noise sigma from :func:`neighbour_residuals` (0 without any)."""
    r = np.abs(np.asarray(residuals, dtype=float))
    return float(MAD_TO_SIGMA * np.median(r) * _RESIDUAL_TO_SIGMA) if r.size else 0.0


def noise_sigma(t_s, values) -> float:
    """Robust noise scale of a series: each sample against the line through its two neighbours.

    A linear trend leaves no residual whatever its slope; a spike spoils three residuals
    of the whole record, which the median ignores.
    """
    return sigma_of_residuals(neighbour_residuals(t_s, values))


def spike_limit(t_s, values, threshold: float, min_deviation: float) -> float:
    """The excursion a spike must exceed: ``threshold`` noise sigmas, ``min_deviation``, two resolution steps.

    Two steps, because one step up and back down is what a quantised logger shows when
    the temperature sits between two of its levels.
    """
    return max(threshold * noise_sigma(t_s, values), min_deviation, 2.0 * resolution(values))


def interior_excursions(x: np.ndarray, width: int) -> np.ndarray:
    """How far each block of ``width`` adjacent samples lies beyond both flanking samples, all in one direction.

    Element i is for the block starting at sample i + 1; <= 0 where the block lies
    between or within its flanks, as every sample of a monotone trend does.
    """
    n = x.size - width - 1
    blocks = sliding_window_view(x[1:-1], width) if n > 0 else np.empty((0, width))
    left, right = x[: max(n, 0)], x[width + 1 : width + 1 + max(n, 0)]
    above = blocks.min(axis=1) - np.maximum(left, right)
    below = np.minimum(left, right) - blocks.max(axis=1)
    return np.maximum(above, below)


def _bipolar_excursions(x: np.ndarray) -> np.ndarray:
    """How far each pair of adjacent samples lies beyond both flanking samples, one above
    them and the other below (a glitch that overshoots and undershoots).

    Element i is for the pair starting at sample i + 1, as :func:`interior_excursions`
    with width 2; <= 0 unless the pair straddles both flanks, which no trend's samples do.
    """
    n = max(x.size - 3, 0)
    left, first, second, right = x[:n], x[1 : n + 1], x[2 : n + 2], x[3 : n + 3]
    high, low = np.maximum(left, right), np.minimum(left, right)
    return np.maximum(
        np.minimum(first - high, low - second), np.minimum(low - first, second - high)
    )


def _end_excursion(t_min: np.ndarray, x: np.ndarray, width: int, rate: float) -> float:
    """How far the first ``width`` samples lie beyond what the rate limit allows from the next sample.

    The smallest over the block, and <= 0 unless every sample of it departs in the same
    direction: an end has one neighbour only, so the physical rate is all it can be judged by.
    """
    ref_t, ref = t_min[width], x[width]
    departure = x[:width] - ref
    if not (np.all(departure > 0) or np.all(departure < 0)):
        return 0.0
    return float(np.min(np.abs(departure) - rate * np.abs(ref_t - t_min[:width])))


def _blocks(
    t_min: np.ndarray, x: np.ndarray, rate: float, limit: float
) -> list[tuple[float, int, int]]:
    """Every block (excursion, first sample, width) departing by more than ``limit``, the largest first."""
    found = []
    for width in range(1, MAX_SPIKE_SAMPLES + 1):
        excursions = interior_excursions(x, width)
        if width == 2:
            # Each sample of an up-and-down pair fails the single-sample test: its
            # neighbour is the other half of the glitch, so the flanks seem off trend.
            excursions = np.maximum(excursions, _bipolar_excursions(x))
        found += [
            (float(excursions[i]), int(i) + 1, width) for i in np.flatnonzero(excursions > limit)
        ]
        if x.size >= 2 * width + 1:  # shorter, and which end of a jump is wrong is unknown
            head = _end_excursion(t_min, x, width, rate)
            tail = _end_excursion(-t_min[::-1], x[::-1], width, rate)
            found += [(head, 0, width)] if head > limit else []
            found += [(tail, x.size - width, width)] if tail > limit else []
    # Largest first; among equals the earlier and narrower: deterministic.
    return sorted(found, key=lambda c: (-c[0], c[1], c[2]))


def _returns(
    t: np.ndarray, x: np.ndarray, first: int, width: int, limit: float, excursion: float
) -> bool:
    """Whether the samples on both sides of an interior block lie on one local trend.

    The trend's slope is the median of the slopes just before the block, just after it
    and across it: one outer slope spoiled by a neighbouring spike does not move it. The
    flanks may stray from that trend by the limit, or by half the block's ``excursion``
    (a quantised, noisy ramp's flanks stray by a step or two): a series that stays away
    after the block, as after an excursion's first sample, does not return. Blocks at a
    record's ends have one side only and are judged by the rate.
    """
    left, right = first - 1, first + width
    if left < 0 or right >= x.size:
        return True
    slopes = [(x[right] - x[left]) / (t[right] - t[left])]
    if left >= 1:
        slopes.append((x[left] - x[left - 1]) / (t[left] - t[left - 1]))
    if right + 1 < x.size:
        slopes.append((x[right + 1] - x[right]) / (t[right + 1] - t[right]))
    drift = x[right] - x[left] - float(np.median(slopes)) * (t[right] - t[left])
    return abs(drift) <= max(limit, excursion / 2.0)


def _short(removed: np.ndarray, block: np.ndarray, t: np.ndarray, window_s: float) -> bool:
    """Whether ``block`` (original sample indices), joined to the removed samples next to it, stays a spike."""
    lo, hi = int(block.min()), int(block.max())
    while lo > 0 and removed[lo - 1]:
        lo -= 1
    while hi + 1 < removed.size and removed[hi + 1]:
        hi += 1
    return hi - lo + 1 <= MAX_SPIKE_SAMPLES and t[hi] - t[lo] <= window_s * (1.0 + _TIE_RTOL)


def spike_mask(
    t_s,
    values,
    *,
    threshold: float,
    min_deviation: float,
    max_rate_c_per_min: float,
    window_s: float,
) -> np.ndarray:
    """Boolean mask of the samples that are spikes: short, isolated departures that return.

    A block of one or two adjacent samples (:data:`MAX_SPIKE_SAMPLES`) is a spike when
    every sample of it lies beyond both samples flanking the block, on the same side (or,
    for two, one above both and the other below both), by more than :func:`spike_limit`,
    its samples span at most ``window_s`` (config
    ``temperatures.spike_window_s``), and the flanking samples lie on one local trend
    (:func:`_returns`): the series comes back to where it was heading. A sample between
    its neighbours is never a spike, so a trend is kept however steep, steepening or
    quantised it is. The first and last one or two samples have one neighbour only:
    they are spikes only when they depart from it faster than ``max_rate_c_per_min``
    (config ``temperatures.spike_max_rate_c_per_min``) allows, by more than the same limit.

    The block that departs the most is removed first and the rest judged again without
    it: on a steep ramp the sample after an upward spike lies below both of its
    neighbours, and must not be flagged for the spike's sake. A block that would join
    removed samples into a departure longer than a spike is not removed, so a longer
    departure (an excursion, :func:`excursions`) is never eaten a sample at a time.

    Parameters
    ----------
    t_s : sample times in seconds, increasing.
    values : 1-D array of valid (finite) samples in time order.
    threshold : in noise sigmas (:func:`noise_sigma`; ``spike_threshold``).
    min_deviation : excursions up to this are never spikes (``spike_min_deviation_c``).
    max_rate_c_per_min : the fastest a real temperature changes at the record's ends.
    window_s : the longest a spike's samples span (``spike_window_s``).

    Notes
    -----
    Excursions within a relative 1e-9 of the limit count as equal to it, so a reading
    exactly one limit away is never flagged by a rounding error (0.1 C steps give
    0.20000000000000284 for 0.2).
    """
    t, x = np.asarray(t_s, dtype=float), np.asarray(values, dtype=float)
    limit = spike_limit(t, x, threshold, min_deviation) * (1.0 + _TIE_RTOL)
    removed = np.zeros(x.shape, dtype=bool)
    kept = np.arange(x.size)
    while kept.size:
        tk, xk = t[kept], x[kept]
        for excursion, first, width in _blocks(tk / 60.0, xk, max_rate_c_per_min, limit):
            block = kept[first : first + width]
            if _short(removed, block, t, window_s) and _returns(
                tk, xk, first, width, limit, excursion
            ):
                removed[block] = True
                kept = np.delete(kept, np.arange(first, first + width))
                break
        else:
            break
    return removed


def _jumps(t: np.ndarray, x: np.ndarray, limit: float) -> np.ndarray:
    """Each step x[i] - x[i-1] beyond the local trend (element i; 0 where within ``limit``).

    The trend's slope is the median of the (up to four) neighbouring intervals' slopes,
    so a jump does not set the trend it is judged against, and a ramp however steep
    makes no jump.
    """
    jumps = np.zeros(x.size)
    if x.size < 3:
        return jumps
    dt = np.diff(t)
    slopes = np.diff(x) / dt
    padded = np.pad(slopes, 2, constant_values=np.nan)
    # Intervals i-2, i-1, i+1, i+2 around interval i (padded: NaN beyond the record).
    around = np.stack([padded[k : k + slopes.size] for k in (0, 1, 3, 4)])
    trend = np.nanmedian(around, axis=0)
    step = np.diff(x) - trend * dt
    jumps[1:] = np.where(np.abs(step) > limit, step, 0.0)
    return jumps


_MAX_JUMPS_BACK = 64


def _jump_back(jumps: np.ndarray, at: np.ndarray, k: int, limit: float) -> int | None:
    """Index into ``at`` of the jump that undoes jump ``at[k]``: the first the other way
    after which the jumps since ``at[k]`` sum to within ``limit`` (or half the first) of 0."""
    first = jumps[at[k]]
    total = first
    # The next _MAX_JUMPS_BACK jumps only: bounds the cost on a noisy sensor.
    for m in range(k + 1, min(at.size, k + 1 + _MAX_JUMPS_BACK)):
        total += jumps[at[m]]
        if np.sign(jumps[at[m]]) != np.sign(first) and abs(total) <= max(limit, abs(first) / 2):
            return m
    return None


# Readings on each side of a departure that stand for the trend across it.
_FLANK_READINGS = 5


def _trend_across(t: np.ndarray, x: np.ndarray, i: int, j: int) -> np.ndarray:
    """The trend at readings ``i .. j - 1``: the line joining the medians (time and value)
    of up to :data:`_FLANK_READINGS` readings just before ``i`` and from ``j`` on.

    Medians, not the two readings next to the departure: on a noisy sensor one reading
    tilts the line by its noise, and every reading between then seems to depart.
    """
    before, after = slice(max(i - _FLANK_READINGS, 0), i), slice(j, j + _FLANK_READINGS)
    t0, x0 = np.median(t[before]), np.median(x[before])
    t1, x1 = np.median(t[after]), np.median(x[after])
    return x0 + (x1 - x0) * (t[i:j] - t0) / (t1 - t0)


def excursions(t_s, values, limit: float) -> list[tuple[int, int, float]]:
    """Departures that jump away from a sensor's trend and jump back: (first, last, size).

    ``first`` and ``last`` index the departing samples; ``size`` is the signed median
    distance from the trend across it (:func:`_trend_across`: the line joining the
    readings just before and just after it, each side's median). A jump is a step beyond
    the local trend by more than twice ``limit`` (:func:`_jumps`: a noisy, quantised
    ramp's steps reach one limit now and then, and over a long span its curvature alone
    lifts it off the line joining its ends); a departure starts with a jump and ends with
    the jump that undoes it (:func:`_jump_back`), its samples beyond that line, on the
    first jump's side, by more than ``limit`` at their median. A jump never undone is a
    change of level, not a departure.
    """
    t, x = np.asarray(t_s, dtype=float), np.asarray(values, dtype=float)
    jumps = _jumps(t, x, 2.0 * limit)
    at = np.flatnonzero(jumps)
    found, k = [], 0
    while k < at.size:
        back = _jump_back(jumps, at, k, limit)
        if back is None:
            k += 1
            continue
        i, j = at[k], at[back]
        line = _trend_across(t, x, i, j)
        departure = (x[i:j] - line) * np.sign(jumps[i])
        if np.median(departure) > limit:
            found.append((int(i), int(j - 1), float(np.sign(jumps[i]) * np.median(departure))))
            k = back + 1
        else:
            k += 1
    return found


# ----------------------------------------------------------------------------- native series


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

    natives = []
    for j, sensor in enumerate(sensors):
        ok = np.isfinite(values[:, j])
        ts, vs = t[ok], values[ok, j]
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
        natives.append(
            _Native(
                sensor=str(sensor),
                source=name,
                t=ts,
                v=vs,
                n_raw=int(n_raw[j]),
                n_duplicates=int(duplicates[j]),
                n_out_of_range=int(out_of_range[:, j].sum()),
                n_spikes=int(spikes.sum()),
                clock_offset_s=float(offset_s),
                excursions=events,
                merged=merged[j],
            )
        )
    return natives


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


# ----------------------------------------------------------------------------- grid


def _grid(start_ns: int, end_ns: int, interval_ns: int) -> np.ndarray:
    first = -(-start_ns // interval_ns)  # ceil: the grid stays inside [start, end]
    last = end_ns // interval_ns
    if last < first:
        raise ValueError(
            f"empty time grid: no whole multiple of the interval between {_iso(start_ns)} and {_iso(end_ns)}"
        )
    return np.arange(first, last + 1, dtype=np.int64) * interval_ns


def _onto_grid(native: _Native, grid: np.ndarray, max_gap_s: float):
    """Interpolate one sensor onto the grid; returns values, QC counts and long gaps."""
    t, v = native.t, native.v
    max_gap = max_gap_s * _NS
    n = t.size
    if n == 0:
        counts = dict(
            n_interpolated=0, n_edge_held=0, n_long_gap=int(grid.size), longest_gap_s=np.nan
        )
        return np.full(grid.size, np.nan), counts, [(int(grid[0]), int(grid[-1]), "no readings")]
    origin = t[0]
    y = np.interp((grid - origin) / _NS, (t - origin) / _NS, v)  # holds the end values outside
    left = np.searchsorted(t, grid, side="right") - 1  # last sample <= grid point
    right = np.searchsorted(t, grid, side="left")  # first sample >= grid point
    before, after = left < 0, right >= n
    inside = ~before & ~after
    li, ri = np.clip(left, 0, n - 1), np.clip(right, 0, n - 1)
    spacing = np.where(inside, t[ri] - t[li], 0)
    long_gap = inside & (spacing > max_gap)
    edge_far = (before & (t[0] - grid > max_gap / 2)) | (after & (grid - t[-1] > max_gap / 2))
    y[long_gap | edge_far] = np.nan

    steps = np.diff(t)
    typical = np.median(steps) if steps.size else np.inf
    interpolated = inside & ~long_gap & (spacing > GAP_FACTOR * typical)

    gaps = [
        (int(t[i]), int(t[i + 1]), "interior")
        for i in np.flatnonzero(steps > max_gap)
        if t[i] < grid[-1] and t[i + 1] > grid[0]
    ]
    if t[0] - grid[0] > max_gap / 2:
        gaps.insert(0, (int(grid[0]), int(t[0]), "record start"))
    if grid[-1] - t[-1] > max_gap / 2:
        gaps.append((int(t[-1]), int(grid[-1]), "record end"))
    counts = dict(
        n_interpolated=int(interpolated.sum()),
        n_edge_held=int(((before | after) & ~edge_far).sum()),
        n_long_gap=int((long_gap | edge_far).sum()),
        longest_gap_s=float(steps.max() / _NS) if steps.size else np.nan,
    )
    return y, counts, gaps


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
        values, counts, gaps = _onto_grid(native, grid, settings.max_gap_s)
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


def _gap_table(gap_rows: list[tuple]) -> pd.DataFrame:
    """The long gaps as a table (:data:`GAP_COLUMNS`), in time order."""
    gaps = pd.DataFrame(gap_rows, columns=GAP_COLUMNS)
    gaps["start"] = gaps["start"].to_numpy(dtype=np.int64).astype("datetime64[ns]")
    gaps["end"] = gaps["end"].to_numpy(dtype=np.int64).astype("datetime64[ns]")
    gaps["duration_s"] = gaps["duration_s"].astype(float)
    return sort_naturally(gaps, ["start", "sensor"])


def signals_on_grid(
    signals: Mapping[str, pd.DataFrame], clock_offsets_s: Mapping[str, float], grid_times
) -> pd.DataFrame:
    """Operating signals on the temperature grid, each held at its last logged value.

    Signals are set points or programme states (a spindle speed, a feed), not physical
    quantities with noise: no spike filter applies, and a step stays a step instead of
    being smeared into a ramp. A reading no signal reaches (a logger's overflow value,
    :func:`~thermaxis.dataset.plausibility.usable_signal_readings`) counts as missing.
    Before a signal's first sample it takes that sample's value: the grid starts a margin
    before the first measurement, which may be the record's first sample.
    """
    grid = _as_ns(grid_times)
    columns = {"time": grid.astype("datetime64[ns]")}
    for name, frame in signals.items():
        t = _as_ns(frame["time"]) + int(round(float(clock_offsets_s.get(name, 0.0)) * _NS))
        for signal in (c for c in frame.columns if c != "time"):
            v = frame[signal].to_numpy(dtype=float)
            ok = usable_signal_readings(v)
            ts, vs = t[ok], v[ok]
            last = np.clip(np.searchsorted(ts, grid, side="right") - 1, 0, None)
            columns[signal] = vs[last] if vs.size else np.full(grid.size, np.nan)
    return pd.DataFrame(columns)


# ----------------------------------------------------------------------------- windows


def _window_label(row) -> str:
    if "name" in row and pd.notna(row["name"]):
        return f"{row['measurement']} ({row['name']})" if "measurement" in row else str(row["name"])
    return str(row["measurement"])


def _check_windows(windows: pd.DataFrame) -> None:
    for column in ("start", "end"):
        if column not in windows.columns:
            raise ValueError(
                f"measurement windows: missing column {column!r} (expected measurement, start, end)"
            )
    if "measurement" not in windows.columns:
        raise ValueError(
            "measurement windows: missing column 'measurement' (expected measurement, start, end)"
        )
    if (_as_ns(windows["end"]) < _as_ns(windows["start"])).any():
        raise ValueError(
            "measurement windows: a window ends before it starts; expected start <= end"
        )


def _gap_text(gap, start_ns: int, end_ns: int, max_gap_s: float) -> str:
    """What a gap is, in the words a user can act on."""
    limit = f" (max_gap_s {max_gap_s:g})"
    if gap.get("kind", "interior") == "no readings":
        return (
            "has no valid reading at all (no column, empty, or every value out of range or a spike)"
        )
    if gap.get("kind", "interior") == "record start":
        return (
            f"has no reading before {_iso(end_ns)}: its record starts too late{limit}; a value is held at most "
            "max_gap_s / 2 before a sensor's first sample"
        )
    if gap.get("kind", "interior") == "record end":
        return (
            f"has no reading after {_iso(start_ns)}: its record ends too early{limit}; a value is held at most "
            "max_gap_s / 2 after a sensor's last sample"
        )
    return f"has a {gap['duration_s']:.0f} s gap ({_iso(start_ns)} to {_iso(end_ns)}) longer than max_gap_s{limit}"


@dataclass(frozen=True)
class GapOverlap:
    """A sensor's long gaps that overlap measurement windows: the first, and how many.

    ``text`` names the file (when known), the sensor, the first gap (interior, or the
    record's start or end) and the first measurement it hides, then how many more.
    """

    sensor: str
    start: pd.Timestamp
    end: pd.Timestamp
    text: str


def gap_overlaps(
    gaps: pd.DataFrame,
    windows: pd.DataFrame,
    *,
    max_gap_s: float,
    files: Mapping[str, object] | None = None,
) -> list[GapOverlap]:
    """Long temperature gaps that overlap a measurement window, one summary per sensor.

    Parameters
    ----------
    gaps : ``CleanedTemperatures.gaps``.
    windows : one row per measurement: ``measurement``, ``start``, ``end`` (optionally
        ``name``).
    max_gap_s : the limit in force, named in the messages (``temperatures.max_gap_s``).
    files : sensor -> the file its readings came from, named in the messages.

    Returns
    -------
    list of GapOverlap
        In the order of the sensors' first overlap. Gaps outside every window are
        harmless and already listed in ``gaps``; a gap ending exactly when a window
        starts has a real sample there.
    """
    _check_windows(windows)
    files = files or {}
    g_start, g_end = _as_ns(gaps["start"]), _as_ns(gaps["end"])
    w_start, w_end = _as_ns(windows["start"]), _as_ns(windows["end"])
    hits = (g_start[:, None] < w_end[None, :]) & (g_end[:, None] > w_start[None, :])
    by_sensor: dict[str, list[tuple[int, int]]] = {}
    for i, j in zip(*np.nonzero(hits), strict=False):
        by_sensor.setdefault(gaps.iloc[i]["sensor"], []).append((i, j))
    out = []
    for sensor, pairs in by_sensor.items():
        i, j = pairs[0]
        gap, window = gaps.iloc[i], windows.iloc[j]
        where = f"{files[sensor]}: " if sensor in files else ""
        more = f" (and {len(pairs) - 1} more)" if len(pairs) > 1 else ""
        text = (
            f"{where}sensor {sensor} {_gap_text(gap, g_start[i], g_end[i], max_gap_s)}, during measurement "
            f"{_window_label(window)} ({_iso(w_start[j])} to {_iso(w_end[j])}){more}"
        )
        out.append(GapOverlap(str(sensor), gap["start"], gap["end"], text))
    return out


def _interp_at(grid_ns: np.ndarray, values: np.ndarray, t_ns: np.ndarray) -> np.ndarray:
    """Linear interpolation of grid rows at times t (NaN if a neighbour is NaN)."""
    j = np.clip(np.searchsorted(grid_ns, t_ns, side="right") - 1, 0, grid_ns.size - 1)
    k = np.minimum(j + 1, grid_ns.size - 1)
    span = (grid_ns[k] - grid_ns[j]).astype(float)
    w = np.divide((t_ns - grid_ns[j]).astype(float), span, out=np.zeros(t_ns.shape), where=span > 0)
    exact = (w == 0)[:, None]
    # An exact hit must not be spoilt by a NaN next door.
    return np.where(exact, values[j], values[j] * (1 - w[:, None]) + values[k] * w[:, None])


def _window_mean(grid_ns: np.ndarray, values: np.ndarray, start: int, end: int) -> np.ndarray:
    """Time average of the piecewise-linear grid signal over [start, end], NaN segments skipped."""
    if end == start:
        return _interp_at(grid_ns, values, np.array([start]))[0]
    inner = (grid_ns > start) & (grid_ns < end)
    t = np.concatenate([[start], grid_ns[inner], [end]])
    v = np.vstack(
        [
            _interp_at(grid_ns, values, np.array([start])),
            values[inner],
            _interp_at(grid_ns, values, np.array([end])),
        ]
    )
    width = np.diff(t).astype(float)[:, None]
    segment = 0.5 * (v[:-1] + v[1:])
    ok = np.isfinite(segment)
    covered = (width * ok).sum(axis=0)
    total = np.where(ok, segment * width, 0.0).sum(axis=0)
    return np.divide(total, covered, out=np.full(values.shape[1], np.nan), where=covered > 0)


def temperatures_in_windows(frame: pd.DataFrame, windows: pd.DataFrame, how: str) -> pd.DataFrame:
    """Each sensor's temperature during each measurement.

    Parameters
    ----------
    frame : ``CleanedTemperatures.frame`` (``time`` + sensor columns on a regular grid).
    windows : ``measurement``, ``start``, ``end`` per measurement.
    how : (config ``temperatures.window``) "mean" - time average of the linearly interpolated series over [start, end]
        (exact for a linear ramp: its value at the window's middle); NaN stretches are
        left out of the average.  "start" - the value at the window's start.

    Returns
    -------
    pd.DataFrame
        ``measurement``, ``start``, ``end`` and one column per sensor, one row per window
        in the windows' order.

    Raises
    ------
    ValueError
        Unknown ``how``, or a window outside the frame's time span.
    """
    if how not in ("mean", "start"):
        raise ValueError(f"how must be 'mean' or 'start', got {how!r}")
    _check_windows(windows)
    sensors = [c for c in frame.columns if c != "time"]
    grid = _as_ns(frame["time"])
    values = frame[sensors].to_numpy(dtype=float)
    w_start, w_end = _as_ns(windows["start"]), _as_ns(windows["end"])
    if grid.size == 0:
        raise ValueError(
            "temperature frame is empty: expected a time grid covering the measurements"
        )
    outside = (w_start < grid[0]) | (w_end > grid[-1])
    if outside.any():
        i = int(np.flatnonzero(outside)[0])
        raise ValueError(
            f"measurement {_window_label(windows.iloc[i])} ({_iso(w_start[i])} to {_iso(w_end[i])}) lies outside "
            f"the temperature record ({_iso(grid[0])} to {_iso(grid[-1])})"
        )
    if how == "start":
        rows = _interp_at(grid, values, w_start)
    else:
        rows = np.vstack(
            [_window_mean(grid, values, a, b) for a, b in zip(w_start, w_end, strict=False)]
        )
    out = windows[["measurement", "start", "end"]].reset_index(drop=True)
    return pd.concat(
        [out, pd.DataFrame(rows.reshape(len(out), len(sensors)), columns=sensors)], axis=1
    )
