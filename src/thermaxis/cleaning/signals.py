"""Operating signals (spindle speed, feed, ...) on the temperature grid."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from thermaxis.cleaning._timebase import _NS, _as_ns
from thermaxis.dataset.plausibility import usable_signal_readings

__all__ = ["signals_on_grid"]


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
