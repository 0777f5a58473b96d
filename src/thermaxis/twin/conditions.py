"""The four experiments (conditions) of the paper and their timelines.

Times inside a run are seconds relative to the start of its first measurement (M1,
"warm-up 0 min").  The test protocol (paper, Sec. 2.1): the interferometer is zeroed at
the first target just before M1; after M1 the axis reciprocates at the condition's feed,
paused only for the seven further measurements, about every 23 min.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "TARGETS_MM",
    "FIRST_TARGET_MM",
    "Condition",
    "CONDITIONS",
    "Timeline",
    "timeline",
    "ambient_at",
    "reading_times",
]

#: The 14 interferometer targets, 185 ... 445 mm step 20 mm.
TARGETS_MM: np.ndarray = np.arange(185.0, 446.0, 20.0)
FIRST_TARGET_MM: float = 185.0

N_MEASUREMENTS = 8
MEASUREMENT_PERIOD_S = 23 * 60
#: Reading cadence of the interferometer: move 20 mm, settle, capture.
READING_INTERVAL_S = 6
#: Overrun and reversal between the forward and the backward pass.
REVERSAL_PAUSE_S = 10
#: The box log starts this long before M1 and ends this long after M8.
LOG_MARGIN_S = 600
#: Servo-on (the drive's standstill losses start) before M1.
SERVO_ON_S = -300
#: The interferometer datum is set at the first target this long before M1.
ZERO_S = -30
#: Reciprocation stops this long before a measurement and resumes this long after it.
MOTION_GUARD_S = 10
#: Step of the simulation grid, s (the network is integrated and sampled on it).
STEP_S = 10.0


@dataclass(frozen=True)
class Condition:
    """One experiment of the paper's Table 1, with the twin's fictitious calendar.

    ``ambient_knots`` are (minutes from M1, fraction of the Table 1 range): the workshop
    air follows the piecewise-linear curve through them, so over the log it spans the
    published range (to within a few hundredths of a degree).  ``jitter_s`` shifts each measurement off
    the nominal 23-min grid (an operator is never exactly on time).
    """

    run: str
    condition: int
    feed_mm_min: float
    ambient_range_c: tuple[float, float]
    date: str
    m1_clock: str
    ambient_knots: tuple[tuple[float, float], ...]
    jitter_s: tuple[int, ...]
    description: str


CONDITIONS: tuple[Condition, ...] = (
    Condition(
        run="E1",
        condition=1,
        feed_mm_min=2000.0,
        ambient_range_c=(30.4, 31.6),
        date="2022-03-14",
        m1_clock="09:20:00",
        # A warming morning: steady rise, flattening in the early afternoon.
        ambient_knots=((-10, 0.0), (40, 0.30), (100, 0.70), (150, 0.95), (175, 1.0)),
        jitter_s=(0, 12, -20, 31, 5, -14, 26, -8),
        description="2000 mm/min reciprocating, uncontrolled workshop (warming morning)",
    ),
    Condition(
        run="E2",
        condition=2,
        feed_mm_min=4000.0,
        ambient_range_c=(30.1, 31.2),
        date="2022-03-15",
        m1_clock="13:05:00",
        # Afternoon: the gate is opened for a delivery, then the sun heats the hall.
        ambient_knots=((-10, 0.45), (20, 0.30), (55, 0.0), (85, 0.35), (130, 0.80), (175, 1.0)),
        jitter_s=(0, -18, 9, 24, -6, 17, -27, 11),
        description="4000 mm/min reciprocating, uncontrolled workshop (afternoon, warming late)",
    ),
    Condition(
        run="E3",
        condition=3,
        feed_mm_min=6000.0,
        ambient_range_c=(27.4, 28.3),
        date="2022-03-17",
        m1_clock="08:40:00",
        # Cool morning; the workshop cooling is switched on at about 75 min.
        ambient_knots=((-10, 0.55), (40, 0.90), (75, 1.0), (110, 0.35), (140, 0.05), (175, 0.0)),
        jitter_s=(0, 7, -25, 15, 28, -11, 3, -19),
        description="6000 mm/min reciprocating, workshop cooling switched on at about 75 min",
    ),
    Condition(
        run="E4",
        condition=4,
        feed_mm_min=8000.0,
        ambient_range_c=(28.8, 30.5),
        date="2022-03-18",
        m1_clock="10:15:00",
        # Warm late morning; the workshop cooling is switched on at about 55 min.
        ambient_knots=((-10, 0.55), (30, 0.90), (55, 1.0), (95, 0.50), (135, 0.15), (175, 0.0)),
        jitter_s=(0, -9, 21, -16, 8, 30, -23, 14),
        description="8000 mm/min reciprocating, workshop cooling switched on at about 55 min",
    ),
)


@dataclass(frozen=True)
class Timeline:
    """Event times of one run (s from M1's start) and its simulation grid."""

    log_start_s: float
    log_end_s: float
    measurement_start_s: np.ndarray  # (8,)
    measurement_end_s: np.ndarray  # (8,)
    grid_s: np.ndarray  # step boundaries


def reading_times(start_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Times of the forward and the backward pass readings of one measurement."""
    n = TARGETS_MM.size
    forward = start_s + READING_INTERVAL_S * np.arange(n)
    backward = forward[-1] + REVERSAL_PAUSE_S + READING_INTERVAL_S * np.arange(n)
    return forward, backward


def timeline(condition: Condition, step_s: float = STEP_S) -> Timeline:
    """The run's schedule: measurements, log window and the simulation grid."""
    starts = MEASUREMENT_PERIOD_S * np.arange(N_MEASUREMENTS) + np.asarray(
        condition.jitter_s, dtype=float
    )
    ends = np.array([reading_times(s)[1][-1] for s in starts])
    log_start = starts[0] - LOG_MARGIN_S
    n_steps = int(np.ceil((ends[-1] + LOG_MARGIN_S - log_start) / step_s))
    grid = log_start + step_s * np.arange(n_steps + 1)
    return Timeline(
        log_start_s=float(log_start),
        log_end_s=float(grid[-1]),
        measurement_start_s=starts,
        measurement_end_s=ends,
        grid_s=grid,
    )


def ambient_at(condition: Condition, t_s: np.ndarray) -> np.ndarray:
    """Workshop air temperature (degC) at times ``t_s`` (s from M1)."""
    knots_min, fraction = np.array(condition.ambient_knots, dtype=float).T
    lo, hi = condition.ambient_range_c
    return lo + (hi - lo) * np.interp(np.asarray(t_s, dtype=float) / 60.0, knots_min, fraction)


def motion_fraction(tl: Timeline, step_s: float) -> np.ndarray:
    """Fraction of each step spent reciprocating (between measurements M1 ... M8)."""
    fine = tl.grid_s[0] + 0.5 + np.arange(int(round(tl.grid_s[-1] - tl.grid_s[0])))
    moving = np.zeros(fine.size, dtype=bool)
    for end, nxt in zip(tl.measurement_end_s[:-1], tl.measurement_start_s[1:], strict=False):
        moving |= (fine >= end + MOTION_GUARD_S) & (fine < nxt - MOTION_GUARD_S)
    per_step = int(round(step_s))
    return moving.reshape(-1, per_step).mean(axis=1)


def servo_fraction(tl: Timeline, step_s: float) -> np.ndarray:
    """Fraction of each step with the drive enabled (standstill losses)."""
    fine = tl.grid_s[0] + 0.5 + np.arange(int(round(tl.grid_s[-1] - tl.grid_s[0])))
    per_step = int(round(step_s))
    return (fine >= SERVO_ON_S).reshape(-1, per_step).mean(axis=1)
