"""``thermaxis compensate``: a logged temperature file replayed through a ``model.json``.

The replay is the controller's: :class:`thermaxis.compensation.runtime.Compensator` runs
cycle by cycle with the model's fallback policy, the first cycle is the reference state
(homing), and each cycle's row holds what the controller would be sent.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.compensation.model import UM_PER_MM
from thermaxis.compensation.runtime import Compensator, Step
from thermaxis.dataset.import_parsing import read_numeric, read_seconds, read_wide_table
from thermaxis.errors import DataError
from thermaxis.method.decouple import MM_PER_M

__all__ = ["LOG_TIME_COLUMNS", "read_log", "replay", "controller_table", "replay_figure"]

# A log gives its clock as ISO 8601 times (`time`) or as seconds since its start (`time_s`).
LOG_TIME_COLUMNS = {
    "time": {"column": "time", "format": "ISO8601"},
    "time_s": {"column": "time_s", "unit": "s"},
}


def read_log(path, sensors) -> tuple[np.ndarray, list[dict]]:
    """Cycle times [s] and one temperature sample per cycle; an empty cell is a missing reading."""
    path = Path(path)
    frame = read_wide_table(path)
    time = next((LOG_TIME_COLUMNS[c] for c in LOG_TIME_COLUMNS if c in frame.columns), None)
    if time is None:
        raise DataError(
            f"{path}: no time column; expected 'time' (ISO 8601 clock times) or 'time_s' "
            f"(seconds), then one column per sensor of the model ({', '.join(sensors)})"
        )
    missing = [s for s in sensors if s not in frame.columns]
    if missing:
        raise DataError(
            f"{path}: missing column {missing[0]!r}, a sensor the model reads; expected one "
            f"column per sensor of the model ({', '.join(sensors)})"
        )
    seconds = read_seconds(path, frame, time)
    columns = {s: read_numeric(path, frame, s, allow_empty=True) for s in sensors}
    samples = [{s: float(columns[s][i]) for s in sensors} for i in range(len(frame))]
    return seconds, samples


def replay(compensator: Compensator, seconds, samples) -> list[Step]:
    """The compensation cycle by cycle; the first cycle's temperatures are the reference."""
    return compensator.run(list(map(float, seconds)), samples, samples[0])


def controller_table(steps: list[Step]) -> pd.DataFrame:
    """One row per cycle: K0 [mm], tan(beta), P0 [mm], the state of the model and why."""
    return pd.DataFrame(
        {
            "cycle": np.arange(1, len(steps) + 1),
            "time_s": [s.time_s for s in steps],
            "status": [s.status for s in steps],
            "k0_mm": [s.parameters.k0_mm for s in steps],
            "tan_beta": [s.parameters.tan_beta for s in steps],
            "p0_mm": [s.parameters.p0_mm for s in steps],
            "line_gap_um": [s.parameters.line_gap_um for s in steps],
            "reasons": ["; ".join(s.reasons) for s in steps],
        }
    )


def replay_figure(table: pd.DataFrame, title: str):
    """K0 and tan(beta) over the log, the cycles on a fallback shaded."""
    from matplotlib.figure import Figure

    from thermaxis.figures.style import DOUBLE_COLUMN_IN

    fig = Figure(figsize=(DOUBLE_COLUMN_IN, 3.6), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    hours = table["time_s"].to_numpy(dtype=float) / 3600.0
    top.plot(hours, table["k0_mm"] * UM_PER_MM, color="#1f77b4")
    top.set_ylabel("K0 (µm)")
    bottom.plot(hours, table["tan_beta"] * UM_PER_MM * MM_PER_M, color="#d62728")
    bottom.set_ylabel("tan β (µm/m)")
    bottom.set_xlabel("Time since the log's first cycle (h)")
    fallback = (table["status"] != "ok").to_numpy()
    for ax in (top, bottom):
        ax.fill_between(
            hours, 0, 1, where=fallback, step="mid", color="0.85", transform=ax.get_xaxis_transform(),
            label="fallback (hold or ramp)",
        )  # fmt: skip
    if fallback.any():
        top.legend(loc="best")
    top.set_title(title)
    return fig
