"""The held-out evidence of a compensation: each held-out run's deviations before and after compensating."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from thermaxis.compensation.exports import siemens_840d, twincat
from thermaxis.compensation.runtime import ControllerParameters, Step
from thermaxis.config import ErrorCleaning
from thermaxis.method.metrics import METRIC_COLUMNS

__all__ = [
    "configured_accuracy",
    "candidate_accuracy",
    "held_out_accuracy",
    "run_states",
    "measurement_cycles",
    "largest_steps",
    "step_noise",
    "fallback_summary",
    "replay",
    "pass_deviations",
    "held_out_tables",
]


def configured_accuracy(metrics: pd.DataFrame, approach: str, algorithm: str) -> pd.DataFrame:
    """The folds' held-out metrics of this approach and algorithm (every target), from
    tables/metrics.csv: what the paper's configuration leaves on unseen runs."""
    rows = metrics[(metrics["approach"] == approach) & (metrics["algorithm"] == algorithm)]
    if rows.empty:
        raise ValueError(
            f"the metrics table: no rows for approach {approach!r} and algorithm {algorithm!r}"
        )
    return rows


def candidate_accuracy(scores: pd.DataFrame, name: str) -> pd.DataFrame:
    """A recommendation candidate's leave-one-condition-out errors, from its scores
    (:data:`thermaxis.method.nested.SCORE_COLUMNS`): one row per held-out run, of the error
    curve as a whole."""
    rows = scores.loc[(scores["kind"] == "loco") & (scores["candidate"] == name)]
    # A loco row's fold is its held-out run; "held_out" names it in every kind of row.
    return rows.drop(columns="fold").rename(columns={"held_out": "fold"}).assign(target="error")


def held_out_accuracy(rows: pd.DataFrame) -> list[dict]:
    """Held-out metric rows (:func:`configured_accuracy`, :func:`candidate_accuracy`) as
    model.json's held_out_accuracy."""
    return [
        {
            "fold": str(r["fold"]),
            "target": str(r["target"]),
            **{m: float(r[m]) for m in METRIC_COLUMNS},
        }
        for r in rows.to_dict("records")
    ]


def run_states(X_run: pd.DataFrame, sensors: Sequence[str]):
    """A run's measurement times [s], temperature samples and reference (its first measurement)."""
    ordered = X_run.sort_values("measurement", kind="stable")
    samples = [{s: float(row[s]) for s in sensors} for _, row in ordered.iterrows()]
    return (ordered["time_min"].to_numpy(dtype=float) * 60.0).tolist(), samples, samples[0]


def largest_steps(series: pd.DataFrame) -> dict[str, float]:
    """Each channel's largest change between consecutive samples of a run's cleaned log.

    ``series``: the clean rule's ``temperatures.parquet`` (``time``, ``elapsed_min``, a
    column per sensor); samples the cleaning left empty are skipped.
    """
    steps = {}
    for column in series.columns.drop(["time", "elapsed_min"], errors="ignore"):
        values = series[column].to_numpy(dtype=float)
        values = values[np.isfinite(values)]
        steps[str(column)] = float(np.abs(np.diff(values)).max()) if values.size > 1 else 0.0
    return steps


def step_noise(steps_by_run: Mapping[str, Mapping[str, float]], runs) -> dict[str, float]:
    """model.json ``noise_c``: each sensor's largest step in any of ``runs`` (the training runs).

    The controller's rate check allows this much on top of ``max_rate_c_per_min``: a
    sensor's noise and resolution are not faults (a 0.1 C step in a 10 s log is
    0.6 C/min), while a change larger than the training runs ever made, at more than
    the rate, still is.
    """
    noise: dict[str, float] = {}
    for run in runs:
        for sensor, step in steps_by_run[run].items():
            noise[sensor] = max(noise.get(sensor, 0.0), step)
    return noise


def measurement_cycles(series: pd.DataFrame, windows: pd.DataFrame, sensors: Sequence[str]):
    """A controller's cycles over a held-out run, for a model with time-aware inputs.

    Every sample of the cleaned log (``series``: ``time`` and a column per sensor) up to
    the last measurement, with each measurement's middle instant added (the instant
    the offline lags are evaluated at, :func:`thermaxis.cleaning.run.derived_inputs`).
    Values there, and across gaps the cleaning left, are linear between samples, as
    offline. Returns (seconds since the log's start, samples, the cycle of each
    measurement in time order).
    """
    ordered = windows.sort_values("measurement", kind="stable")
    start = pd.to_datetime(ordered["start"]).to_numpy(dtype="datetime64[ns]").astype(np.int64)
    end = pd.to_datetime(ordered["end"]).to_numpy(dtype="datetime64[ns]").astype(np.int64)
    grid_ns = pd.to_datetime(series["time"]).to_numpy(dtype="datetime64[ns]").astype(np.int64)
    grid = (grid_ns - grid_ns[0]) / 1e9
    mids = (start + (end - start) // 2 - grid_ns[0]) / 1e9
    values = series[list(sensors)].interpolate(limit_direction="both").to_numpy(dtype=float)
    keep = grid <= mids.max()
    times = np.union1d(grid[keep], mids)
    columns = [np.interp(times, grid, values[:, j]) for j in range(len(sensors))]
    samples = [
        dict(zip(sensors, map(float, row), strict=True)) for row in zip(*columns, strict=True)
    ]
    return times.tolist(), samples, np.searchsorted(times, mids).tolist()


def replay(
    compensator, X_run: pd.DataFrame, cycles=None
) -> tuple[list[Step], list[ControllerParameters]]:
    """The compensator on a held-out run: its step at each measurement (fallback policy
    applied) and its parameters there without the policy.

    Without time-aware inputs one cycle per measurement, at its temperatures; with them
    every cycle of ``cycles`` (:func:`measurement_cycles`), homed at the first
    measurement's cycle, so each lag carries the run's history as it would on the machine.
    """
    times_s, samples, reference = run_states(X_run, compensator.sensors)
    if not compensator.derived:
        steps = compensator.run(times_s, samples, reference)
        return steps, [compensator.parameters(s, reference) for s in samples]
    times_s, samples, rows = cycles
    derived = compensator.derived_inputs(times_s, samples)
    home = {**samples[rows[0]], **derived[rows[0]]}
    steps = compensator.run(times_s, samples, home, derived=derived)
    states = [{**samples[r], **derived[r]} for r in rows]
    return [steps[r] for r in rows], [compensator.parameters(s, home) for s in states]


def fallback_summary(fold: str, steps: Sequence[Step]) -> list[str]:
    """One line per fallback status of a held-out run: how many cycles, when, and why.

    Each reason's sensor is named once, with its first occurrence (the cycle-by-cycle
    account is the fold's ``residuals.csv`` and log).
    """
    lines = []
    for status in dict.fromkeys(s.status for s in steps if s.reasons):
        cycles = [s for s in steps if s.status == status and s.reasons]
        first: dict[str, str] = {}
        for step in cycles:
            for reason in step.reasons:
                first.setdefault(reason.split(":", 1)[0], f"{reason} at t={step.time_s:g} s")
        lines.append(
            f"fold {fold}: {status} on {len(cycles)} of {len(steps)} cycles "
            f"(t={cycles[0].time_s:g} to {cycles[-1].time_s:g} s): first "
            + "; ".join(first.values())
        )
    return lines


def pass_deviations(
    raw_run, targets: Sequence[float], max_missing_fraction: float
) -> dict[int, dict[str, np.ndarray]]:
    """Per measurement (1-based, time order) and direction ("+", "-"), the deviation at each target [um]."""
    from thermaxis.cleaning.passes import combine_passes, without_strays

    # A stray reading (a position few of the run's measurements read) was left out of the
    # run by the clean job, which said so; it is left out here too.
    measurements, _ = without_strays(raw_run.measurements, np.asarray(targets, dtype=float))
    out = {}
    for number, (name, measurement) in enumerate(measurements.items(), start=1):
        label = raw_run.error_origin(name)
        passes = {}
        for direction in sorted(set(measurement["direction"]), reverse=True):  # "+" before "-"
            settings = ErrorCleaning(direction=direction, max_missing_fraction=max_missing_fraction)
            curve, _ = combine_passes(
                measurement[measurement["direction"] == direction], targets, settings, name=label
            )
            passes[direction] = curve.to_numpy(dtype=float)
        out[number] = passes
    return out


def _pitch_table(first: Mapping[str, np.ndarray]) -> np.ndarray:
    """The static pitch table: the reference measurement's deviation, mean of its passes."""
    return np.nanmean(np.vstack(list(first.values())), axis=0)


def _systematic(quantities: Mapping[str, float]) -> float:
    """E, or the one direction's E when the measurement has a single pass."""
    for name in ("E", "E_up", "E_down"):
        if np.isfinite(quantities[name]):
            return quantities[name]
    return float("nan")


def _controller_rows(label: dict, rows, final_rows, status: str) -> list[dict]:
    return [
        {
            **label,
            "parameter": p,
            "name": n,
            "unit": u,
            "value": v,
            "final_model_value": fv,
            "status": status,
        }
        for (p, n, v, u), (_, _, fv, _) in zip(rows, final_rows, strict=False)
    ]


def held_out_tables(
    fold: str,
    steps: Sequence[Step],
    time_min: Sequence[float],
    deviations: Mapping[int, Mapping[str, np.ndarray]],
    positions_mm: Sequence[float],
    final: Sequence[ControllerParameters],
) -> dict[str, pd.DataFrame]:
    """Exports, residuals, ISO 230-2 quantities and the drift summary of one held-out run.

    ``steps`` are the fold model's values per measurement (after the fallback policy),
    ``final`` the final model's parameters for the same temperatures (reference values).
    The pitch table is the first measurement's; compensation is what the controller
    computes from the exported K0, tan(beta), P0.
    """
    from thermaxis.compensation.iso230 import single_pass_quantities

    positions = np.asarray(positions_mm, dtype=float)
    table = _pitch_table(deviations[1])
    names = ("siemens_840d", "twincat", "residuals", "iso230_2", "summary")
    tables: dict[str, list[dict]] = {name: [] for name in names}
    for number, (step, minutes, reference) in enumerate(
        zip(steps, time_min, final, strict=False), start=1
    ):
        label = {"fold": fold, "run": fold, "measurement": number, "time_min": float(minutes)}
        siemens = _controller_rows(
            label, siemens_840d(step.parameters), siemens_840d(reference), step.status
        )
        tables["siemens_840d"] += siemens
        tables["twincat"] += _twincat_rows(label, step, reference)
        applied = step.parameters.at(positions)
        # The drift since the pitch table was taken, before and after the compensation is applied.
        before = {direction: values - table for direction, values in deviations[number].items()}
        after = {direction: drift + applied for direction, drift in before.items()}
        tables["residuals"] += _residual_rows(label, positions, before, applied, step.status)
        q_before = single_pass_quantities(before.get("+"), before.get("-"))
        q_after = single_pass_quantities(after.get("+"), after.get("-"))
        tables["iso230_2"] += _iso_rows(label, q_before, q_after)
        tables["summary"].append(_summary_row(label, step, before, after, q_before, q_after))
    return {name: pd.DataFrame(rows) for name, rows in tables.items()}


def _twincat_rows(label: dict, step: Step, reference: ControllerParameters) -> list[dict]:
    """The TwinCAT parameters of one measurement, with the integer each register holds."""
    rows = _controller_rows(label, twincat(step.parameters), twincat(reference), step.status)
    for row in rows:
        row["register"] = int(round(row["value"]))
    return rows


def _residual_rows(
    label: dict, positions: np.ndarray, drifts: Mapping[str, np.ndarray], applied, status: str
):
    """Per pass and target: the uncompensated drift, the compensation applied, and what remains."""
    return [
        {
            **label,
            "direction": direction,
            "position_mm": x,
            "uncompensated_um": d,
            "compensation_um": c,
            "residual_um": d + c,
            "status": status,
        }
        for direction, drift in drifts.items()
        for x, d, c in zip(positions, drift, applied, strict=False)
    ]


def _iso_rows(
    label: dict, q_before: Mapping[str, float], q_after: Mapping[str, float]
) -> list[dict]:
    """The ISO 230-2 quantities one measurement gives, before and after, and those it cannot give."""
    from thermaxis.compensation.iso230 import NEEDS_CYCLES, NEEDS_READINGS, NOT_COMPUTED, QUANTITIES

    def row(name, description, before, after, computed, note):
        return {**label, "quantity": name, "description": description, "uncompensated_um": before,
                "compensated_um": after, "computed": computed, "note": note}  # fmt: skip

    given = {name: bool(np.isfinite(q_before[name])) for name in QUANTITIES}
    computed = [
        row(
            name,
            description,
            q_before[name],
            q_after[name],
            given[name],
            "" if given[name] else NEEDS_READINGS[name],
        )
        for name, description in QUANTITIES.items()
    ]
    return computed + [
        row(name, description, np.nan, np.nan, False, NEEDS_CYCLES)
        for name, description in NOT_COMPUTED.items()
    ]


def _summary_row(label: dict, step: Step, before, after, q_before, q_after) -> dict:
    """One measurement's largest deviation and E, uncompensated and compensated, and the model's state."""
    return {
        **label,
        "status": step.status,
        "largest_abs_uncompensated_um": float(
            np.nanmax(np.abs(np.concatenate(list(before.values()))))
        ),
        "largest_abs_compensated_um": float(
            np.nanmax(np.abs(np.concatenate(list(after.values()))))
        ),
        "E_uncompensated_um": _systematic(q_before),
        "E_compensated_um": _systematic(q_after),
        "line_gap_um": step.parameters.line_gap_um,
        "reasons": "; ".join(step.reasons),
    }
