"""Spikes and excursions in one sensor's native series (step 5 of :mod:`thermaxis.cleaning.temperatures`).

A spike is one or two samples beyond both neighbours that returns (:func:`spike_mask`),
judged against a limit that cannot fall below two steps of the logger's resolution, so a
heating ramp, however quantised or steep, is kept to its last sample; the record's first
and last samples, which have one neighbour only, are judged by a physical rate limit.
An excursion (:func:`excursions`) is a longer departure that jumps away from the trend
and jumps back. Pure functions of (times, values); the displacement cleaning
(:mod:`thermaxis.cleaning.displacement`) judges its readings with the same residuals.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from thermaxis.cleaning._timebase import MAD_TO_SIGMA

__all__ = [
    "MAX_SPIKE_SAMPLES",
    "interior_excursions",
    "neighbour_residuals",
    "noise_sigma",
    "sigma_of_residuals",
    "resolution",
    "spike_limit",
    "spike_mask",
    "excursions",
]

# Relative tolerance of threshold comparisons: a tie must not flip on float rounding.
_TIE_RTOL = 1e-9

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
