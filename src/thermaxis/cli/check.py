"""``thermaxis check``: the workflow's parse-time gate on one dataset, and what it found."""

from __future__ import annotations

import os
from functools import partial

import pandas as pd

from thermaxis.cleaning.passes import run_targets
from thermaxis.config import CleaningSettings
from thermaxis.dataset.plausibility import check_run_plausibility, check_same_targets
from thermaxis.dataset.reader import Dataset, read_run
from thermaxis.errors import recorded
from thermaxis.pipeline.parallel import fold_workers, map_folds
from thermaxis.pipeline.preflight import Checked

__all__ = ["overview"]


def overview(checked: Checked) -> tuple[list[str], list[str]]:
    """Runs, measurements per run, sensors, positions, each run's time span and how often
    each of its logs sampled, as lines; and the warnings the clean job would give first.

    Reads every run's logs and measurements and makes the clean job's plausibility checks
    (:func:`~thermaxis.dataset.plausibility.check_run_plausibility`: readings out of range,
    overlapping measurements, errors that look like mm, implausible temperatures, a signal
    log that starts late), so a bad later file is named here too, and compares the runs'
    targets as the assemble job does. Runs are read on the cores the clean job would use;
    the first bad run's error is raised, as in one process.
    """
    dataset = checked.dataset
    kind = "SIMULATED" if dataset.simulated else "MEASURED"
    lines = [
        f"dataset {dataset.name} ({kind}) in {dataset.root}",
        f"  {len(dataset.sensors)} sensor{'' if len(dataset.sensors) == 1 else 's'}: "
        f"{', '.join(dataset.sensors)}",
        f"  {checked.n_positions} target position(s)"
        + ("" if checked.n_positions >= 2 else ": point-by-point models only, no slope/intercept"),
        f"  {len(checked.runs)} runs (held-out folds: {', '.join(checked.folds)})",
    ]
    width = max(len(r) for r in checked.runs)
    workers = fold_workers(os.cpu_count() or 1, len(checked.runs), "clean")
    read = partial(_run_overview, dataset=dataset, cleaning=checked.settings.cleaning)
    warnings, targets = [], []
    for run, (line, notes, positions) in zip(
        checked.runs, map_folds(read, checked.runs, workers), strict=True
    ):
        lines.append(f"  {run:<{width}}  {line}")
        warnings += notes
        targets.append(pd.DataFrame({"run": run, "position_mm": positions}))
    check_same_targets(pd.concat(targets, ignore_index=True), dataset.root)
    return lines, warnings


def _run_overview(run: str, dataset: Dataset, cleaning: CleaningSettings) -> tuple:
    """One run's summary (after its name), its plausibility warnings and its targets."""
    # The reader's own warnings (a log line cut short) join the plausibility notes.
    raw, raised = recorded(read_run, dataset, run)
    notes = [message for message, *_ in raised] + check_run_plausibility(dataset, raw, cleaning)
    measurements = raw.measurements
    firsts = [m["time"].min() for m in measurements.values()]
    lasts = [m["time"].max() for m in measurements.values()]
    span = (max(lasts) - min(firsts)).total_seconds() / 3600.0
    positions = {len(m["position_mm"].unique()) for m in measurements.values()}
    line = (
        f"{len(measurements):>4} measurements  {span:7.2f} h  "
        f"{min(firsts):%Y-%m-%d %H:%M} to {max(lasts):%Y-%m-%d %H:%M}  "
        f"{'/'.join(map(str, sorted(positions)))} position{'' if positions == {1} else 's'}  "
        f"logs: {_log_intervals(raw.sources)}"
        + (f", signals: {_log_intervals(raw.signals)}" if raw.signals else "")
    )
    return line, notes, run_targets(measurements)


def _log_intervals(logs: dict) -> str:
    """Each log file's median sample interval, by source: what the logger really did."""
    return ", ".join(
        f"{name} {log['time'].diff().median().total_seconds():.3g} s"
        if len(log) > 1
        else f"{name} {'one sample' if len(log) else 'no readings'}"
        for name, log in logs.items()
    )
