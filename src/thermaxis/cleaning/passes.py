"""Combining an interferometer measurement's forward and backward passes at the target positions."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from thermaxis.config import ErrorCleaning
from thermaxis.errors import shown

__all__ = [
    "combine_passes",
    "foreign_targets",
    "run_targets",
    "without_strays",
]
# Positions closer than this are the same target (readings are logged to 1e-3 mm at best).
_POSITION_TOL_MM = 1e-6


# ----------------------------------------------------------------------------- errors


def _listed(positions) -> str:
    shown = ", ".join(f"{p:g}" for p in positions[:6])
    return shown + (f", ... ({len(positions)} in all)" if len(positions) > 6 else "")


def _read_levels(measurements: dict[str, pd.DataFrame]) -> dict[str, np.ndarray]:
    return {
        name: np.unique(np.round(m["position_mm"].to_numpy(dtype=float), 6))
        for name, m in measurements.items()
    }


def _own_levels(read: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The positions more than half of the measurements read, every position read, and
    how many measurements read each."""
    levels, counts = np.unique(np.concatenate(list(read.values())), return_counts=True)
    return levels[counts > len(read) / 2], levels, counts


def run_targets(measurements: dict[str, pd.DataFrame]) -> np.ndarray:
    """A run's targets: the positions more than half of its measurements read, as logged.

    A position fewer measurements read is a stray reading, not a target
    (:func:`without_strays`); when no position has a majority (measurements that share
    none), every position read is a target and the later checks name the mismatch.
    """
    own, levels, _ = _own_levels(_read_levels(measurements))
    logged = np.unique(
        np.concatenate([m["position_mm"].to_numpy(dtype=float) for m in measurements.values()])
    )
    return logged[np.isin(np.round(logged, 6), own if own.size else levels)]


def without_strays(
    measurements: dict[str, pd.DataFrame], targets: np.ndarray
) -> tuple[dict[str, pd.DataFrame], dict[str, str]]:
    """Each measurement without its readings at positions that are not ``targets``, and
    per measurement that had any, what was left out and why (for a warning)."""
    read = _read_levels(measurements)
    _, levels, counts = _own_levels(read)
    count = dict(zip(levels, counts, strict=True))
    kept, why = {}, {}
    for name, m in measurements.items():
        position = m["position_mm"].to_numpy(dtype=float)
        at_target = (np.abs(position[:, None] - targets[None, :]) <= _POSITION_TOL_MM).any(axis=1)
        kept[name] = m if at_target.all() else m[at_target]
        if not at_target.all():
            stray = np.unique(np.round(position[~at_target], 6))
            why[name] = (
                f"position(s) {_listed(stray)} mm read by {count[stray[0]]} of the run's "
                f"{len(read)} measurements, not one of its targets; left out"
            )
    return kept, why


def foreign_targets(
    measurements: dict[str, pd.DataFrame], max_missing_fraction: float
) -> tuple[str, str] | None:
    """The first measurement that reads other targets than the run's own, and why; None if all agree.

    The run's own targets are those more than half of its measurements read; the others
    are not its targets. A
    measurement whose positions miss more of them than ``max_missing_fraction`` allows
    would otherwise make every measurement of the run look incomplete; when its positions
    are the run's targets shifted by one distance, the message says by how much. A
    measurement that reads all of them and a stray position besides is not one
    (:func:`without_strays`).
    """
    read = _read_levels(measurements)
    own, _, _ = _own_levels(read)
    if own.size == 0:
        return None
    for name, positions in read.items():
        foreign = np.setdiff1d(positions, own)
        lacking = np.setdiff1d(own, positions)
        if foreign.size == 0 or lacking.size <= max_missing_fraction * own.size:
            continue
        offsets = foreign - lacking if foreign.size == lacking.size else np.empty(0)
        shifted = (
            f"; they look shifted by {offsets[0]:+g} mm"
            if offsets.size and np.allclose(offsets, offsets[0], atol=1e-6)
            else ""
        )
        return name, (
            f"reads {foreign.size} position(s) that are not the run's targets ({_listed(foreign)} mm) "
            f"and lacks {lacking.size} of the run's {own.size} targets ({_listed(lacking)} mm){shifted}; "
            f"expected the run's targets {_listed(own)} mm in every measurement"
        )
    return None


def _passes(measurement: pd.DataFrame, label: str) -> dict[str, pd.DataFrame]:
    """Split a measurement into its passes: {"+": ..., "-": ...} or {"single": ...}."""
    if "direction" not in measurement.columns or measurement["direction"].isna().all():
        return {"single": measurement}
    direction = measurement["direction"]
    if direction.isna().any():
        raise ValueError(
            f"{label}: column 'direction' is empty in some rows; expected '+' or '-' in all or none"
        )
    bad = ~direction.isin(["+", "-"])
    if bad.any():
        raise ValueError(
            f"{label}: column 'direction': expected '+' or '-', got {shown(direction[bad].iloc[0])}"
        )
    return {d: measurement[direction.to_numpy() == d] for d in ("+", "-") if (direction == d).any()}


def _pass_at_targets(
    rows: pd.DataFrame, targets: np.ndarray, label: str, pass_name: str
) -> np.ndarray:
    """One pass's reading at each target (NaN where it has none)."""
    rows = rows[np.isfinite(rows["error_um"].to_numpy(dtype=float))]
    position = rows["position_mm"].to_numpy(dtype=float)
    error = rows["error_um"].to_numpy(dtype=float)
    match = np.abs(position[:, None] - targets[None, :]) <= _POSITION_TOL_MM
    unmatched = ~match.any(axis=1)
    if unmatched.any():
        raise ValueError(
            f"{label}: position {position[unmatched][0]:g} mm is not one of the targets"
        )
    target_of = match.argmax(axis=1)
    out = np.full(targets.size, np.nan)
    for k in np.unique(target_of):
        readings = np.unique(error[target_of == k])
        if readings.size > 1:
            raise ValueError(
                f"{label}: position {targets[k]:g} mm appears twice in the {pass_name} pass with different errors "
                f"{readings.tolist()} (expected one reading per target and pass)"
            )
        out[k] = readings[0]
    return out


def combine_passes(
    measurement: pd.DataFrame,
    targets: Sequence[float],
    settings: ErrorCleaning,
    name: str = "",
) -> tuple[pd.Series, list[str]]:
    """One error per target from one measurement's pass(es).

    Parameters
    ----------
    measurement : columns ``position_mm``, ``error_um`` (NaN = no reading), optional
        ``time`` and ``direction`` ("+" / "-").  Without directions (absent or all
        empty) the rows are one pass, used whatever ``settings.direction`` asks for;
        with one direction only, "mean" uses that pass and the other one is an error.
    targets : the target positions, mm.
    settings : :class:`ErrorCleaning`.
    name : the measurement's name for messages (e.g. its file).

    Returns
    -------
    (pd.Series, list of str)
        Errors indexed by ``position_mm`` in the targets' order (NaN = missing), with
        ``attrs["n_duplicate_rows"]``; and warnings.  With ``direction="mean"`` a target
        read in one pass only keeps that reading (with a warning): operators keep such a
        reading, although it carries that pass's reversal error instead of the mean.

    Raises
    ------
    ValueError
        A position that is no target, the same position twice in one pass with
        different errors, the requested direction absent, or more than
        ``max_missing_fraction`` of targets missing.
    """
    label = f"measurement {name}" if name else "measurement"
    targets = _checked_targets(measurement, targets, label)

    repeated = measurement.duplicated(keep="first")
    measurement = measurement[~repeated.to_numpy()]
    passes = {
        d: _pass_at_targets(rows, targets, label, d)
        for d, rows in _passes(measurement, label).items()
    }

    combined, warnings = _combine(passes, settings.direction, targets, label)
    missing = ~np.isfinite(combined)
    for k in np.flatnonzero(missing):
        warnings.append(
            f"{label}: position {targets[k]:g} mm has no reading; dropped from this measurement"
        )
    if missing.sum() > settings.max_missing_fraction * targets.size:
        raise ValueError(
            f"{label}: {int(missing.sum())} of {targets.size} targets have no reading, more than "
            f"max_missing_fraction={settings.max_missing_fraction:g}"
        )
    result = pd.Series(combined, index=pd.Index(targets, name="position_mm"), name="error_um")
    result.attrs["n_duplicate_rows"] = int(repeated.sum())
    return result, warnings


def _checked_targets(measurement: pd.DataFrame, targets, label: str) -> np.ndarray:
    """The targets as distinct finite positions (mm), the measurement with its columns."""
    targets = np.asarray(targets, dtype=float)
    if targets.ndim != 1 or targets.size == 0 or not np.isfinite(targets).all():
        raise ValueError(
            f"{label}: targets must be a non-empty 1-D sequence of finite positions in mm"
        )
    if np.unique(targets).size != targets.size:
        raise ValueError(f"{label}: targets must be distinct, got {targets.tolist()}")
    for column in ("position_mm", "error_um"):
        if column not in measurement.columns:
            raise ValueError(
                f"{label}: missing column {column!r} (expected position_mm, error_um[, direction])"
            )
    return targets


def _combine(
    passes: dict[str, np.ndarray], direction: str, targets: np.ndarray, label: str
) -> tuple[np.ndarray, list[str]]:
    """The configured pass, or (``direction="mean"``) the mean of both where both read a target."""
    if direction in ("+", "-") and "single" not in passes:
        if direction not in passes:
            (other,) = passes
            raise ValueError(
                f"{label}: no {direction} pass (only {other}); expected errors.direction 'mean' or {other!r}"
            )
        return passes[direction], []
    if len(passes) == 1:
        # One pass only (unlabelled, or every row in one direction): nothing to average.
        (combined,) = passes.values()
        return combined, []
    forward = passes.get("+", np.full(targets.size, np.nan))
    backward = passes.get("-", np.full(targets.size, np.nan))
    combined = np.where(
        np.isfinite(forward) & np.isfinite(backward),
        0.5 * (forward + backward),
        np.where(np.isfinite(forward), forward, backward),
    )
    warnings = []
    for k in np.flatnonzero(np.isfinite(forward) != np.isfinite(backward)):
        have, lack = ("+", "-") if np.isfinite(forward[k]) else ("-", "+")
        warnings.append(
            f"{label}: position {targets[k]:g} mm has no {lack} reading; using the {have} reading alone"
        )
    return combined, warnings
