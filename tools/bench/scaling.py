"""The scale datasets: their shapes, the command that generates them, and how a cost grows
with the number of runs (a power law fitted on a log-log scale)."""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SCALE_RUNS = (10, 20, 43, 86)
# 5 h at 0.1 Hz with a measurement every 10 min from 5 min in: 30 measurements per run.
SCALE_SHAPES = {
    "one_position": {"sensors": 24, "positions": 1, "hours": 5.0, "rate_hz": 0.1, "measurement_min": 10.0, "seed": 0},
    "positions_14": {"sensors": 24, "positions": 14, "hours": 5.0, "rate_hz": 0.1, "measurement_min": 10.0, "seed": 0},
    # Many sensors: 60 logged points, 8 positions, 3 h, a measurement every 30 min. Not
    # run by default (86 such runs would take hours): --shapes sensors_60 --runs 12.
    "sensors_60": {"sensors": 60, "positions": 8, "hours": 3.0, "rate_hz": 0.1, "measurement_min": 30.0, "seed": 0},
}  # fmt: skip
#: The shapes whose growth with the runs the bench measures by default.
GROWTH_SHAPES = ("one_position", "positions_14")


def generate_command(out: Path, runs: int, spec: dict) -> list[str]:
    """``python -m thermaxis.twin scale`` writing ``runs`` runs of shape ``spec`` to ``out``."""
    options = ("sensors", "positions", "hours", "rate_hz", "measurement_min", "seed")
    flags = [[f"--{name.replace('_', '-')}", str(spec[name])] for name in options]
    return [sys.executable, "-m", "thermaxis.twin", "scale", "--out", str(out), "--runs", str(runs),
            *(part for flag in flags for part in flag)]  # fmt: skip


@dataclass(frozen=True)
class ScaleFit:
    """Least-squares line of cost against runs, and how far the cost bends away from it."""

    intercept_s: float
    slope_s_per_run: float
    r2: float
    marginal_s_per_run: list
    quadratic_share: float
    statement: str


def fit_scaling(runs, seconds, quantity: str = "wall time") -> ScaleFit:
    """Fit ``seconds = intercept + slope * runs`` and say how the cost grows.

    The verdict comes from a least-squares parabola through the same points: the share
    of its quadratic term in the cost at the largest size (0 for a straight line, 1 for
    pure ``runs**2``).  Below 0.2 in size the growth is called linear.  The marginal
    costs (seconds per added run between consecutive sizes) are reported as well; the
    first of them is noisy because small datasets leave cores idle.

    Raises
    ------
    ValueError
        With fewer than two distinct run counts.
    """
    order = np.argsort(np.asarray(runs, dtype=float), kind="stable")
    x = np.asarray(runs, dtype=float)[order]
    y = np.asarray(seconds, dtype=float)[order]
    if x.size != y.size or np.unique(x).size < 2:
        raise ValueError(f"scaling fit needs at least two distinct run counts, got runs={list(x)}")
    slope, intercept = np.polyfit(x, y, 1)
    residual = y - (intercept + slope * x)
    total = np.sum((y - y.mean()) ** 2)
    r2 = 1.0 - float(np.sum(residual**2) / total) if total > 0 else 1.0
    keep = np.diff(x) > 0
    marginal = [round(float(v), 3) for v in np.diff(y)[keep] / np.diff(x)[keep]]
    share = float("nan")
    if np.unique(x).size < 3:
        growth = "growth not judged: two sizes cannot show curvature"
    else:
        c2, c1, c0 = np.polyfit(x, y, 2)
        top = x[-1]
        share = float(c2 * top**2 / (c0 + c1 * top + c2 * top**2))
        if share < -0.2:
            growth = "cost grows less than linearly with the number of runs"
        elif share < 0.2:
            growth = "cost grows linearly with the number of runs"
        elif share < 0.5:
            growth = "cost grows somewhat faster than linearly with the number of runs"
        else:
            growth = "cost grows about quadratically (or faster) with the number of runs"
        growth += f" (quadratic share at {top:g} runs {share:.2f})"
    statement = (
        f"{quantity} = {intercept:.1f} s + {slope:.2f} s per run (least squares, R^2 = {r2:.3f}); {growth}; "
        f"marginal cost {', '.join(f'{v:.2f}' for v in marginal)} s per added run"
    )
    return ScaleFit(float(intercept), float(slope), r2, marginal, share, statement)
