"""The real-log faults seeded into the twin's raw files (documented in its README).

Every fault is listed here as data, so the README, the tests and the generator agree.
Times are minutes from the run's first measurement (M1).  A careful cleaning stage can
undo all of them: spikes and the open circuit are single samples far from their
neighbours, duplicated rows are exact copies, gaps are short compared with the
thermal time constants.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import conditions as cond

__all__ = [
    "Spike",
    "SPIKES",
    "OPEN_CIRCUIT",
    "OPEN_CIRCUIT_C",
    "DUPLICATED_ROWS",
    "WIRELESS_OUTAGE",
    "WIRELESS_LOSS_PROBABILITY",
    "MISSING_READING",
    "measurement_at",
    "apply_box_faults",
]


@dataclass(frozen=True)
class Spike:
    run: str
    sensor: str
    minute: float
    delta_c: float


#: Single-sample spikes (electromagnetic interference from the drives).  E4's T1 spike
#: falls inside measurement M07's window on purpose: a window mean must not take it.
SPIKES: tuple[Spike, ...] = (
    Spike("E1", "T3", 57.5, +5.3),
    Spike("E2", "T8", 101.0, -3.9),
    Spike("E3", "T5", 33.0, +6.8),
    Spike("E4", "T1", 140.0, +4.4),
    Spike("E4", "T9", 12.0, -5.2),
)
#: A loose terminal: one open-circuit reading (the box reports its full-scale value).
OPEN_CIRCUIT = ("E2", "T9", 130.0)
OPEN_CIRCUIT_C = 850.0
#: Rows the box wrote twice after a USB hiccup: (run, minute of the first row, rows).
#: Each affected row appears twice in a row (identical time and values).
DUPLICATED_ROWS: tuple[tuple[str, float, int], ...] = (("E1", 40.0, 3), ("E3", 120.0, 1))
#: The nut's wireless sensor lost its link: (run, first minute, last minute).
WIRELESS_OUTAGE = ("E2", 75.0, 82.5)
#: Lost wireless packets besides the outage.
WIRELESS_LOSS_PROBABILITY = 0.05
#: The laser missed one capture (beam interrupted): (run, measurement, pass, target mm).
MISSING_READING = ("E3", 6, "+", 345.0)


def measurement_at(run: str, minute: float) -> int | None:
    """The measurement (1-based) whose window contains ``minute``, if any."""
    condition = next(c for c in cond.CONDITIONS if c.run == run)
    tl = cond.timeline(condition)
    t = 60.0 * minute
    inside = (tl.measurement_start_s <= t) & (t <= tl.measurement_end_s)
    return int(np.flatnonzero(inside)[0]) + 1 if inside.any() else None


def _row_at(time_min: np.ndarray, minute: float) -> int:
    return int(np.argmin(np.abs(time_min - minute)))


def apply_box_faults(
    run: str, time_min: np.ndarray, values: dict[str, np.ndarray]
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Spikes and the open circuit in place of samples; then the duplicated rows.

    Returns the faulty columns and the row order (indices into the clean rows, with
    repeats for the duplicated rows), so that times are duplicated with their values.
    """
    out = {sensor: column.copy() for sensor, column in values.items()}
    for spike in SPIKES:
        if spike.run == run:
            out[spike.sensor][_row_at(time_min, spike.minute)] += spike.delta_c
    if OPEN_CIRCUIT[0] == run:
        out[OPEN_CIRCUIT[1]][_row_at(time_min, OPEN_CIRCUIT[2])] = OPEN_CIRCUIT_C
    repeats = np.ones(time_min.size, dtype=int)
    for dup_run, minute, n_rows in DUPLICATED_ROWS:
        if dup_run == run:
            first = _row_at(time_min, minute)
            # Each row is written twice in place: time never goes backwards.
            repeats[first : first + n_rows] = 2
    return out, np.repeat(np.arange(time_min.size), repeats)
