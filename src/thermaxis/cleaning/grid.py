"""The regular time grid every sensor is put on (steps 7-8 of :mod:`thermaxis.cleaning.temperatures`).

Valid samples are interpolated linearly in time onto whole multiples of the interval;
a grid point between samples further apart than ``max_gap_s`` stays NaN and the gap is
reported, and a sensor's first (last) value is held for up to ``max_gap_s / 2`` before
(after) its record.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from thermaxis.cleaning._timebase import _NS, _iso
from thermaxis.labels import sort_naturally

__all__ = ["GAP_FACTOR", "GAP_COLUMNS"]

# A spacing between valid samples longer than this many times the sensor's median
# spacing is a gap (lost packet, removed spike, ...): grid points in it are counted as
# interpolated in the QC table.  1.5 tolerates the jitter of irregular (wireless) sampling.
GAP_FACTOR = 1.5
GAP_COLUMNS = ["sensor", "start", "end", "duration_s", "kind"]


def _grid(start_ns: int, end_ns: int, interval_ns: int) -> np.ndarray:
    first = -(-start_ns // interval_ns)  # ceil: the grid stays inside [start, end]
    last = end_ns // interval_ns
    if last < first:
        raise ValueError(
            f"empty time grid: no whole multiple of the interval between {_iso(start_ns)} and {_iso(end_ns)}"
        )
    return np.arange(first, last + 1, dtype=np.int64) * interval_ns


def _onto_grid(t: np.ndarray, v: np.ndarray, grid: np.ndarray, max_gap_s: float):
    """Interpolate one sensor's valid samples (ns, values) onto the grid; returns values,
    QC counts and long gaps."""
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


def _gap_table(gap_rows: list[tuple]) -> pd.DataFrame:
    """The long gaps as a table (:data:`GAP_COLUMNS`), in time order."""
    gaps = pd.DataFrame(gap_rows, columns=GAP_COLUMNS)
    gaps["start"] = gaps["start"].to_numpy(dtype=np.int64).astype("datetime64[ns]")
    gaps["end"] = gaps["end"].to_numpy(dtype=np.int64).astype("datetime64[ns]")
    gaps["duration_s"] = gaps["duration_s"].astype(float)
    return sort_naturally(gaps, ["start", "sensor"])
