"""ISO 230-2 positioning quantities that ONE bidirectional pass supports.

ISO 230-2 evaluates five approaches per target and direction. A thermal-drift
measurement is one forward (+, "up") and one backward (-, "down") pass, so its mean
unidirectional positional deviation at a target is the single reading x_i. From it:

* E_up = max x_up_i - min x_up_i, E_down likewise (unidirectional systematic positional
  deviation);
* E = max(x_up_i, x_down_i) - min(x_up_i, x_down_i) over both directions (bidirectional
  systematic positional deviation);
* M = max x_bar_i - min x_bar_i with x_bar_i = (x_up_i + x_down_i) / 2 (mean bidirectional
  positional deviation);
* B = max |B_i| with B_i = x_up_i - x_down_i (reversal value of the axis).

The quantities built on the standard uncertainty of repeated approaches cannot be
computed and are listed in :data:`NOT_COMPUTED`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["QUANTITIES", "NEEDS_READINGS", "NOT_COMPUTED", "single_pass_quantities"]

QUANTITIES = {
    "E_up": "unidirectional systematic positional deviation, + direction",
    "E_down": "unidirectional systematic positional deviation, - direction",
    "E": "bidirectional systematic positional deviation",
    "M": "mean bidirectional positional deviation",
    "B": "reversal value of the axis",
}

# What each quantity needs from one measurement, said where a measurement does not give it
# (a single-point record, one direction only, readings missing).
NEEDS_READINGS = {
    "E_up": "needs a + pass read at two targets or more",
    "E_down": "needs a - pass read at two targets or more",
    "E": "needs both passes, or one pass read at two targets or more",
    "M": "needs two targets or more read in both directions",
    "B": "needs a target read in both directions",
}

NEEDS_CYCLES = "needs repeated approaches (ISO 230-2: 5 per target and direction); a thermal-drift pass has one"
NOT_COMPUTED = {
    "s_up": "estimator of the unidirectional standard uncertainty, + direction",
    "s_down": "estimator of the unidirectional standard uncertainty, - direction",
    "R_up": "unidirectional repeatability of positioning, + direction",
    "R_down": "unidirectional repeatability of positioning, - direction",
    "R": "bidirectional repeatability of positioning",
    "A_up": "unidirectional accuracy of positioning, + direction",
    "A_down": "unidirectional accuracy of positioning, - direction",
    "A": "bidirectional accuracy of positioning",
}


def _span(values: np.ndarray) -> float:
    """max - min of the readings; a span needs two (one target in one direction has none)."""
    finite = values[np.isfinite(values)]
    return float(finite.max() - finite.min()) if finite.size >= 2 else float("nan")


def single_pass_quantities(up=None, down=None) -> dict[str, float]:
    """E_up, E_down, E, M and B (um) of one pass per direction at the same targets.

    ``up`` and ``down`` are deviations at the targets (NaN = no reading); either may be
    None when the measurement has no pass in that direction, and then only the other
    direction's E is defined (the rest are NaN). M and B use the targets read in both
    directions.
    """
    nan = float("nan")
    if up is None and down is None:
        raise ValueError("single_pass_quantities needs at least one pass (up or down)")
    if up is None or down is None:
        one = _span(np.asarray(up if up is not None else down, dtype=float))
        return {
            "E_up": one if up is not None else nan,
            "E_down": one if down is not None else nan,
            "E": nan,
            "M": nan,
            "B": nan,
        }
    up = np.asarray(up, dtype=float)
    down = np.asarray(down, dtype=float)
    if up.shape != down.shape:
        raise ValueError(
            f"forward pass has {up.size} targets, backward pass {down.size}; expected the same targets"
        )
    both = np.isfinite(up) & np.isfinite(down)
    reversal = up[both] - down[both]
    return {
        "E_up": _span(up),
        "E_down": _span(down),
        "E": _span(np.concatenate([up, down])),
        "M": _span((up[both] + down[both]) / 2.0),
        "B": float(np.max(np.abs(reversal))) if reversal.size else nan,
    }
