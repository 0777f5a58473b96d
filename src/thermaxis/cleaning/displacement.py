"""QC of the displacement channel: knocked readings and gauge resets within one run.

A run's unzeroed errors drift smoothly from one measurement to the next, because the
axis heats up slowly compared with the time between measurements. Two faults of real
records break that:

- an **outlier**: one reading (one target of one measurement) far from the trend of
  the neighbouring measurements at that target, which returns at the next measurement
  (a knocked probe, a beam briefly cut);
- a **step**: every target jumps between two measurements and stays at the new level (the
  interferometer or gauge was reset or re-zeroed mid-run): the unzeroed drift after it
  is measured from another datum.

Both are judged like temperature spikes (:func:`thermaxis.cleaning.spikes.spike_mask`):
by how far a value lies beyond both of its neighbours, so a drift however fast or
curved is never flagged. An outlier is a reading beyond both neighbouring readings at its
target; a step is a change between two measurements beyond both neighbouring changes of
the run's level (the median over targets, which one outlier does not move), changes
compared per minute so that a long pause between two measurements is no step. The first
and last measurements have one neighbour: a reading there, or a change into or out of
them, cannot be told from a real drift and is not judged.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from thermaxis.cleaning.spikes import (
    interior_excursions,
    neighbour_residuals,
    sigma_of_residuals,
)

__all__ = [
    "FINDING_COLUMNS",
    "displacement_findings",
    "apply_findings",
    "finding_text",
]

FINDING_COLUMNS = ["measurement", "position_mm", "finding", "size_um", "cause", "action"]
_CAUSES = {
    "outlier": "a single reading off its neighbours' trend: knocked probe or interrupted beam?",
    "step": "every target jumps and stays: gauge or interferometer reset or re-zeroed mid-run?",
}


def _limit(t_min: np.ndarray, errors: np.ndarray, threshold: float, min_um: float) -> float:
    """The departure a finding must exceed in one run: ``threshold`` noise sigmas, at least ``min_um``.

    The noise is pooled over every target: a run has few measurements, and one knocked
    reading or one step would spoil a large share of a single target's residuals.
    """
    residuals = []
    for column in errors.T:
        ok = np.isfinite(column)
        residuals.append(neighbour_residuals(t_min[ok], column[ok]))
    pooled = np.concatenate(residuals) if residuals else np.empty(0)
    return max(threshold * sigma_of_residuals(pooled), min_um)


def _excursions(x: np.ndarray, limit: float) -> list[tuple[int, float]]:
    """(index, signed size) of every finite interior value beyond both finite neighbours by more than ``limit``."""
    ok = np.flatnonzero(np.isfinite(x))
    v = x[ok]
    excursion = interior_excursions(v, 1)
    above = v[1:-1] > np.maximum(v[:-2], v[2:])
    signed = np.where(above, excursion, -excursion)
    return [(int(ok[j + 1]), float(signed[j])) for j in np.flatnonzero(excursion > limit)]


def _outliers(errors: np.ndarray, limit: float) -> list[tuple[int, int, float]]:
    """(measurement index, target index, signed size) of every single-reading outlier."""
    return [
        (i, k, size) for k in range(errors.shape[1]) for i, size in _excursions(errors[:, k], limit)
    ]


def _steps(t_min: np.ndarray, errors: np.ndarray, limit: float) -> list[tuple[int, float]]:
    """(index of the first measurement after the step, signed jump) of every step of the run's level.

    Changes are compared as rates, so a longer pause between two measurements is not a
    step for the drift it lets accumulate; the excursion is then taken over the step's
    own interval, in µm.
    """
    usable = np.isfinite(errors).any(axis=1)
    ok = np.flatnonzero(usable)
    if ok.size < 4:
        return []
    level = np.nanmedian(errors[ok], axis=1)
    changes, dt = np.diff(level), np.diff(t_min[ok])
    rates = np.divide(changes, dt, out=np.zeros_like(changes), where=dt > 0)
    excursion = interior_excursions(rates, 1) * dt[1:-1]
    return [(int(ok[j + 2]), float(changes[j + 1])) for j in np.flatnonzero(excursion > limit)]


def displacement_findings(
    times,
    curves: Sequence[pd.Series],
    *,
    threshold: float,
    min_um: float,
    outliers: str,
    steps: str,
) -> pd.DataFrame:
    """The outliers and steps of one run's error curves.

    Parameters
    ----------
    times : the start of each measurement, in measurement order.
    curves : each measurement's error per target (index ``position_mm``, NaN = no reading),
        all on the same targets.
    threshold : in noise sigmas of the series judged (config ``errors.qc_threshold``).
    min_um : departures up to this are never flagged (``errors.qc_min_deviation_um``).
    outliers, steps : what happens to each (``errors.outliers``, ``errors.steps``), named
        in the ``action`` column.

    Returns
    -------
    pd.DataFrame
        :data:`FINDING_COLUMNS`, one row per finding: the 1-based measurement, the target
        (NaN for a step, which moves every target), the signed size in µm (an outlier's
        departure beyond its neighbours, a step's jump), the likely cause and the action.
    """
    t = pd.to_datetime(pd.Series(list(times)))
    t_min = ((t - t.iloc[0]) / pd.Timedelta(minutes=1)).to_numpy(dtype=float)
    targets = curves[0].index.to_numpy(dtype=float) if curves else np.empty(0)
    errors = np.vstack([c.to_numpy(dtype=float) for c in curves]) if curves else np.empty((0, 0))
    limit = _limit(t_min, errors, threshold, min_um)
    knocked = _outliers(errors, limit)
    rows = [
        (i + 1, targets[k], "outlier", size, _CAUSES["outlier"], outliers) for i, k, size in knocked
    ]
    cleaned = errors.copy()
    for i, k, _ in knocked:
        cleaned[i, k] = np.nan
    rows += [
        (i + 1, np.nan, "step", size, _CAUSES["step"], steps)
        for i, size in _steps(t_min, cleaned, limit)
    ]
    findings = pd.DataFrame(rows, columns=FINDING_COLUMNS)
    findings["size_um"] = findings["size_um"].astype(float)
    findings["position_mm"] = findings["position_mm"].astype(float)
    return findings.sort_values(["measurement", "finding"], kind="stable", ignore_index=True)


def apply_findings(curves: Sequence[pd.Series], findings: pd.DataFrame) -> list[pd.Series]:
    """The curves with every outlier whose action is ``drop`` removed (NaN)."""
    out = [c.copy() for c in curves]
    for row in findings[
        (findings["finding"] == "outlier") & (findings["action"] == "drop")
    ].itertuples():
        curve = out[row.measurement - 1]
        curve[np.isclose(curve.index.to_numpy(dtype=float), row.position_mm)] = np.nan
    return out


def finding_text(row, origin: str) -> str:
    """One finding as the terminal states it: where, how large, the likely cause and what was done."""
    where = (
        f"position {row.position_mm:g} mm reads {row.size_um:+.1f} µm off its neighbouring measurements"
        if row.finding == "outlier"
        else f"every target jumps by {row.size_um:+.1f} µm since the previous measurement and stays"
    )
    done = {"warn": "kept", "drop": "dropped", "refuse": "refused"}[row.action]
    return f"{origin}: {row.finding}: {where} ({_CAUSES[row.finding]}); {done} (errors.{row.finding}s: {row.action})"
