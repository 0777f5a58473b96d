"""Plausibility of a dataset's shape and readings: refusals and warnings before any model sees them."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.dataset.layout import error_source, log_file
from thermaxis.dataset.safety import _error, check_inside, check_name, check_regular_file
from thermaxis.errors import shown

__all__ = [
    "check_dataset_shape",
    "check_run_plausibility",
    "check_same_targets",
    "check_time_zones",
    "check_time_range",
    "check_error_readings",
    "sensor_median_warnings",
    "MAX_ABS_SIGNAL",
    "usable_signal_readings",
]
# No linear axis is a kilometre long: beyond this a position is a unit or logging fault.
MAX_ABS_POSITION_MM = 1e6
# A zone follows the clock time: "...T09:10:00Z", "... 09:10:00.5+02:00", "...T09:10-0500".
_TIME_ZONE = re.compile(
    r"[T\s]\d{1,2}:\d{2}(?::\d{2}(?:\.\d*)?)?\s*(?:Z|[+-]\d{2}(?::?\d{2})?)\s*$", re.IGNORECASE
)


def check_dataset_shape(dataset) -> None:
    """Dataset-level needs of the workflow, named before any job starts.

    Lists and stats the run folders' data files (safe names, regular files of bounded
    size, inside the dataset) and counts the measurements; nothing is read.
    """
    # The schemas' patterns again, strictly (a JSON-schema "$" accepts a trailing newline).
    sheet = dataset.root / "dataset.yaml"
    check_name(dataset.name, "dataset name", sheet)
    for name in dataset.sensors:
        check_name(name, "sensor", sheet)
    for name in dataset.sources:
        check_name(name, "source", sheet)
    for run in dataset.run_ids:
        check_name(run, "run", dataset.root / "runs.tsv")
        check_inside(dataset.root / run, dataset.root, what="run folder")
        for path in sorted((dataset.root / run / "errors").glob("*.csv")):
            check_name(path.stem, "measurement", path)
        folder = dataset.root / run
        data_files = [
            *folder.glob("errors/*.csv"),
            *folder.glob("errors.csv"),
            *folder.glob("temperatures/*.csv"),
            *folder.glob("signals/*.csv"),
        ]
        for path in sorted(data_files):
            check_inside(path, dataset.root, what="data file")
            check_regular_file(path, what="data file")
    runs_sheet = dataset.root / "runs.tsv"
    if len(dataset.run_ids) < 2:
        raise _error(
            runs_sheet,
            f"{len(dataset.run_ids)} run listed; leave-one-condition-out needs at least 2 runs",
        )
    # A run's measurements in one errors.csv are counted when it is read, not here.
    counts = {
        run: len(list((dataset.root / run / "errors").glob("*.csv"))) for run in dataset.run_ids
    }
    if (
        not any((dataset.root / run / "errors.csv").exists() for run in dataset.run_ids)
        and max(counts.values()) < 2
    ):
        raise _error(
            dataset.root,
            "one measurement per run; the drift (intercept b) and every model need at least 2 measurements "
            "in a run (expected several measurements while the axis heats up)",
        )


def missing_logs(dataset, raw) -> list[str]:
    """A note per temperature source whose log in the run is absent or has no data rows:
    its sensors have no reading there (the reader reads such a log as one without rows),
    which costs them, not the run."""
    notes = []
    for source, log in raw.sources.items():
        if log.empty:
            path = log_file(dataset.root / raw.run, source)
            what = (
                "no data rows below the header"
                if path.exists()
                else f"no log of source {source} in this run"
            )
            notes.append(
                f"run {raw.run}: {path}: {what}; its sensor(s) "
                f"{', '.join(dataset.sensors_of(source))} have no reading here"
            )
    return notes


def skipped_files(folder: Path) -> list[str]:
    """A note per data folder of a run holding files the reader skips: only ``*.csv`` is
    read, so an XLSX left beside the exports, or an ``M01.CSV``, would vanish unsaid.
    Hidden files (``.DS_Store``) are left unmentioned."""
    notes = []
    for name in ("errors", "temperatures", "signals"):
        sub = folder / name
        if not sub.is_dir():
            continue
        skipped = sorted(
            p.name for p in sub.iterdir() if p.suffix != ".csv" and not p.name.startswith(".")
        )
        if skipped:
            notes.append(
                f"{sub}: skipped {', '.join(skipped)}: only .csv files are read "
                "(export a spreadsheet as CSV, with a lower-case .csv suffix)"
            )
    return notes


def check_run_plausibility(dataset, raw, cleaning) -> list[str]:
    """Refuse implausible readings or a grid step longer than the run; warn of implausible
    medians and of files the reader skips."""
    folder = dataset.root / raw.run
    notes = skipped_files(folder) + missing_logs(dataset, raw)
    for name, measurement in raw.measurements.items():
        # The file and its lines as read; a run built in memory has neither.
        path = raw.error_files.get(name, name)
        lines, positions = raw.error_lines.get(name), measurement["position_mm"].to_numpy()
        check_error_readings(
            path, measurement["error_um"].to_numpy(), cleaning.max_abs_error_um, lines
        )
        _refuse_first_row(
            path,
            np.abs(positions) > MAX_ABS_POSITION_MM,
            "position_mm",
            # Called within this iteration, by _refuse_first_row.
            lambda i: (
                f"expected a position within ±{MAX_ABS_POSITION_MM:g} mm, got {positions[i]:g}"  # noqa: B023
            ),
            lines,
        )
    notes += error_scale_warnings(raw, folder)
    notes += position_scale_warnings(raw, folder)
    windows = raw.windows()
    overlapping = np.flatnonzero(windows["start"].to_numpy()[1:] < windows["end"].to_numpy()[:-1])
    if overlapping.size:
        earlier, later = windows.iloc[overlapping[0]], windows.iloc[overlapping[0] + 1]
        raise _error(
            raw.error_origin(later["name"]),
            f"readings from {later['start']} overlap measurement {earlier['name']} ({earlier['start']} to "
            f"{earlier['end']}); expected one measurement at a time (a copied file?)",
        )
    span_s = (windows["end"].max() - windows["start"].min()).total_seconds()
    interval_s = cleaning.temperatures.interval_s
    if 0 < span_s < interval_s:
        raise _error(
            "config temperatures.interval_s",
            f"{interval_s:g} s is longer than run {raw.run} lasts ({span_s:g} s from its first to its last reading); "
            "expected a grid step well below the time between measurements",
        )
    notes += signal_coverage(dataset, raw, windows, cleaning.temperatures.max_gap_s / 2.0)
    median_c = cleaning.plausible_median_c
    if not median_c[0] < median_c[1]:
        raise _error(
            "config temperatures.plausible_median_c",
            f"expected [low, high] with low < high, got [{median_c[0]:g}, {median_c[1]:g}]",
        )
    if dataset.temperature_kind == "rise":
        return notes  # rises since the start sit near 0 °C by design: no structure-temperature median to judge
    for source, frame in raw.sources.items():
        with np.errstate(
            over="ignore"
        ):  # the median of two readings near 1e308 is inf: still implausible
            medians = frame.drop(columns="time").median().to_dict()
        notes += sensor_median_warnings(medians, *median_c, where=str(log_file(folder, source)))
    return notes


# No operating signal a controller logs (a speed in rpm, a feed in mm/min, a load in %, a
# current in A, a power in W) reaches a billion in its unit: beyond it a reading is a
# logger's overflow or fault value, not an operating state.
MAX_ABS_SIGNAL = 1e9


def usable_signal_readings(values) -> np.ndarray:
    """Which readings of an operating signal are usable: finite and within ±:data:`MAX_ABS_SIGNAL`.

    Signals are set points and states with real steps, so no spike rule fits them; a reading
    beyond the bound is treated as missing (cleaning holds the reading before it).
    """
    values = np.asarray(values, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.isfinite(values) & (np.abs(values) <= MAX_ABS_SIGNAL)


def _signal_range_note(
    run: str, path, signal: str, times: pd.Series, values: np.ndarray, usable: np.ndarray
) -> list[str]:
    """Warn of a signal's readings beyond :data:`MAX_ABS_SIGNAL` (``usable``: those within,
    :func:`usable_signal_readings`); refuse a signal with no other."""
    beyond = ~np.isnan(values) & ~usable
    if not beyond.any():
        return []
    first = int(np.flatnonzero(beyond)[0])
    which = f"the first, {values[first]:g}, at {times.iloc[first]}"
    if not usable.any():
        raise _error(
            path,
            f"column {signal!r}: every reading is beyond ±{MAX_ABS_SIGNAL:g} ({which}); expected the "
            "signal in the unit dataset.yaml declares for it",
        )
    return [
        f"run {run}: {path}: signal {signal}: {int(beyond.sum())} reading(s) beyond "
        f"±{MAX_ABS_SIGNAL:g} ({which}) treated as missing, the reading before each held: a "
        "logger's overflow or fault value, not an operating state"
    ]


def signal_coverage(dataset, raw, windows: pd.DataFrame, hold_s: float) -> list[str]:
    """Warn of a signal's readings beyond :data:`MAX_ABS_SIGNAL` (treated as missing), and
    where a signal's log starts or ends more than ``hold_s`` (half of
    ``temperatures.max_gap_s``, the temperatures' rule) inside the measurements, since a
    signal is held at its first and last values there, which the log does not show. (The
    reader refuses a signal with no reading in a run; this, one with no usable reading.)"""
    if not raw.signals:
        return []
    notes = []
    first, last = windows["start"].min(), windows["end"].max()
    offsets = dataset.clock_offsets_s()
    for source, frame in raw.signals.items():
        path = log_file(dataset.root / raw.run, source, "signals")
        times = frame["time"] + pd.Timedelta(seconds=offsets.get(source, 0.0))
        for signal in (c for c in frame.columns if c != "time"):
            values = frame[signal].to_numpy(dtype=float)
            usable = usable_signal_readings(values)
            notes += _signal_range_note(raw.run, path, signal, frame["time"], values, usable)
            logged = times[usable]
            late = (logged.min() - first).total_seconds()
            early = (last - logged.max()).total_seconds()
            if late > hold_s:
                notes.append(
                    f"run {raw.run}: {path}: signal {signal} has no reading before {logged.min()}, "
                    f"{late / 60:.0f} min after the first measurement starts; its first value stands "
                    "for it before then"
                )
            if early > hold_s:
                notes.append(
                    f"run {raw.run}: {path}: signal {signal} has no reading after {logged.max()}, "
                    f"{early / 60:.0f} min before the last measurement ends; its last value stands "
                    "for it after then"
                )
    return notes


def check_same_targets(errors: pd.DataFrame, dataset_root) -> None:
    """Every run reads the same target positions, or the runs cannot share one model."""
    targets = errors.groupby("run", sort=True)["position_mm"].unique()
    first_run = targets.index[0]
    reference = np.sort(targets.iloc[0])
    for run, positions in targets.items():
        positions = np.sort(positions)
        if positions.shape != reference.shape or not np.allclose(
            positions, reference, rtol=0, atol=1e-6
        ):
            extra = np.setdiff1d(positions, reference)
            lacking = np.setdiff1d(reference, positions)
            detail = (
                f"{extra[0]:g} mm is not a target of run {first_run}"
                if extra.size
                else f"{lacking[0]:g} mm is never read"
            )
            raise _error(
                error_source(Path(dataset_root) / run),
                f"run {run} reads {positions.size} target positions, run {first_run} {reference.size} "
                f"({detail}); expected the same targets in every run",
            )


def check_time_zones(path, values: pd.Series, column: str = "time") -> None:
    """Times carry no zone (one zone per dataset); name the first that does."""
    zoned = values.astype(str).str.contains(_TIME_ZONE).to_numpy()
    _refuse_first_row(
        path,
        zoned,
        column,
        lambda i: (
            f"expected a time without a time zone (one zone per dataset), got {shown(values.iloc[i])}"
        ),
    )


def check_time_range(path, parsed: pd.Series, values: pd.Series, column: str = "time") -> None:
    """Times the nanosecond clock of the tables can hold (pandas: 1677-09-21 to 2262-04-11)."""
    years = parsed.dt.year.to_numpy()
    _refuse_first_row(
        path,
        (years < 1678) | (years > 2261),
        column,
        lambda i: f"expected a time between 1678 and 2261, got {shown(values.iloc[i])}",
    )


# A run whose every error reading is smaller than this (in um) was most likely written in
# mm: thermal drift over hours and expansion along a stroke reach micrometres, and an
# interferometer's noise alone is some hundredths of a micrometre.
MIN_LARGEST_ERROR_UM = 0.05


def error_scale_warnings(raw, folder: Path) -> list[str]:
    """A warning for a run whose errors are all below :data:`MIN_LARGEST_ERROR_UM`."""
    readings = [m["error_um"].to_numpy(dtype=float) for m in raw.measurements.values()]
    largest = max((float(np.nanmax(np.abs(r))) for r in readings if r.size), default=0.0)
    if largest >= MIN_LARGEST_ERROR_UM:
        return []
    return [
        f"run {raw.run}: {error_source(folder)}: every error reading is within ±{largest:.3g} um, "
        f"below the {MIN_LARGEST_ERROR_UM:g} um a thermal error reaches; error_um is in "
        "micrometres (readings in mm are 1000 times too small)"
    ]


# Targets of a linear axis (ISO 230-2) are spread along its stroke, tens of millimetres at
# the very least; a run whose targets all lie within this (in mm) was most likely written
# in metres.
MIN_TARGET_SPAN_MM = 1.0


def position_scale_warnings(raw, folder: Path) -> list[str]:
    """A warning for a run of three or more targets that all lie within :data:`MIN_TARGET_SPAN_MM`."""
    positions = np.unique(
        np.concatenate([m["position_mm"].to_numpy(dtype=float) for m in raw.measurements.values()])
    )
    positions = positions[np.isfinite(positions)]
    # Two close positions are a single point read with jitter more often than a stroke.
    if positions.size < 3 or positions[-1] - positions[0] >= MIN_TARGET_SPAN_MM:
        return []
    return [
        f"run {raw.run}: {error_source(folder)}: its {positions.size} targets span "
        f"{positions[-1] - positions[0]:.3g} mm, below the {MIN_TARGET_SPAN_MM:g} mm an axis's "
        "targets span; expected position_mm in millimetres (positions in metres are 1000 times "
        "too small)"
    ]


def check_error_readings(path, errors_um: np.ndarray, max_abs_um: float, lines=None) -> None:
    """Interferometer errors are finite and within ``max_abs_um`` (``lines``: as :func:`_refuse_first_row`)."""
    errors_um = np.asarray(errors_um, dtype=float)
    bad = ~np.isfinite(errors_um) | (np.abs(errors_um) > max_abs_um)
    _refuse_first_row(
        path,
        bad,
        "error_um",
        lambda i: (
            f"{errors_um[i]:g} um is beyond the plausible ±{max_abs_um:g} um (config errors.max_abs_error_um)"
        ),
        lines,
    )


def _refuse_first_row(path, bad: np.ndarray, column: str, what, lines=None) -> None:
    """The first flagged row as a file line: ``lines[i]``, or i + 2 (the header is line 1) for a whole file."""
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        line = int(lines[i]) if lines is not None else i + 2
        raise _error(path, f"line {line}, column {column!r}: {what(i)}")


def _degrees(value: float) -> str:
    # A logger's overflow value (1e200) in a hundred digits would bury the sentence.
    return f"{value:.1f}" if abs(value) < 1e5 else f"{value:.3g}"


def sensor_median_warnings(medians: dict, low_c: float, high_c: float, where: str) -> list[str]:
    """One warning per sensor whose median temperature is implausible for a machine structure."""
    notes = []
    for sensor, median in sorted(medians.items()):
        if not math.isnan(median) and not (low_c <= median <= high_c):
            # Above 200 a kelvin reading is likelier than a Fahrenheit one.
            unit, celsius = (
                ("kelvin", median - 273.15) if median > 200 else ("°F", (median - 32.0) * 5.0 / 9.0)
            )
            notes.append(
                f"{where}: sensor {sensor}: median {_degrees(median)} °C is outside the plausible {low_c:g}-{high_c:g} °C "
                f"of a machine structure (config temperatures.plausible_median_c); if it is in {unit}, "
                f"that is {_degrees(celsius)} °C: expected °C"
            )
    return notes
