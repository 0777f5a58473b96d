"""``thermaxis check``: the workflow's parse-time gate on one dataset, and what it found."""

from __future__ import annotations

from thermaxis.dataset.plausibility import check_run_plausibility
from thermaxis.dataset.reader import read_run
from thermaxis.pipeline.preflight import Checked

__all__ = ["overview"]


def overview(checked: Checked) -> tuple[list[str], list[str]]:
    """Runs, measurements per run, sensors, positions, each run's time span and how often
    each of its logs sampled, as lines; and the warnings the clean job would give first.

    Reads every run's logs and measurements and makes the clean job's plausibility checks
    (:func:`~thermaxis.dataset.plausibility.check_run_plausibility`: readings out of range,
    overlapping measurements, errors that look like mm, implausible temperatures, a signal
    log that starts late), so a bad later file is named here too.
    """
    dataset = checked.dataset
    kind = "SIMULATED" if dataset.simulated else "MEASURED"
    lines = [
        f"dataset {dataset.name} ({kind}) in {dataset.root}",
        f"  {len(dataset.sensors)} sensors: {', '.join(dataset.sensors)}",
        f"  {checked.n_positions} target position(s)"
        + ("" if checked.n_positions >= 2 else ": point-by-point models only, no slope/intercept"),
        f"  {len(checked.runs)} runs (held-out folds: {', '.join(checked.folds)})",
    ]
    width = max(len(r) for r in checked.runs)
    warnings = []
    for run in checked.runs:
        raw = read_run(dataset, run)
        warnings += check_run_plausibility(dataset, raw, checked.settings.cleaning)
        measurements = raw.measurements
        firsts = [m["time"].min() for m in measurements.values()]
        lasts = [m["time"].max() for m in measurements.values()]
        span = (max(lasts) - min(firsts)).total_seconds() / 3600.0
        positions = {len(m["position_mm"].unique()) for m in measurements.values()}
        lines.append(
            f"  {run:<{width}}  {len(measurements):>4} measurements  {span:7.2f} h  "
            f"{min(firsts):%Y-%m-%d %H:%M} to {max(lasts):%Y-%m-%d %H:%M}  "
            f"{'/'.join(map(str, sorted(positions)))} position{'' if positions == {1} else 's'}  "
            f"logs: {_log_intervals({**raw.sources, **raw.signals})}"
        )
    return lines, warnings


def _log_intervals(logs: dict) -> str:
    """Each log file's median sample interval, by source: what the logger really did."""
    return ", ".join(
        f"{name} {log['time'].diff().median().total_seconds():.3g} s"
        if len(log) > 1
        else f"{name} one sample"
        for name, log in logs.items()
    )
