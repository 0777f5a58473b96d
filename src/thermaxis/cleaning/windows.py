"""Each sensor's temperature during each measurement window, and the gaps that hide one."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from thermaxis.cleaning._timebase import _as_ns, _iso

__all__ = ["GapOverlap", "gap_overlaps", "temperatures_in_windows"]


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
