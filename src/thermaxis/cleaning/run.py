"""From one run's raw logs to tidy tables: unzeroed errors and measurement temperatures.

The unzeroed error matrix keeps the drift the paper is about: the interferometer
datum is set once per run, so a later measurement's first-position reading is not 0.
The re-zeroed view (each measurement minus its own first-position reading, Fig. 8)
is kept beside it only to show what re-zeroing hides.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from thermaxis.cleaning import displacement, passes
from thermaxis.cleaning.signals import signals_on_grid
from thermaxis.cleaning.temperatures import clean_temperatures
from thermaxis.cleaning.windows import gap_overlaps, temperatures_in_windows
from thermaxis.config import CleaningSettings
from thermaxis.dataset.layout import log_file
from thermaxis.dataset.plausibility import check_run_plausibility
from thermaxis.dataset.reader import Dataset, RawRun, load_dataset, read_run
from thermaxis.errors import DataError
from thermaxis.labels import natural_key
from thermaxis.method import inputs as time_inputs

__all__ = [
    "CleanedRun",
    "RunTables",
    "clean_run",
    "clean_and_assemble_run",
    "tidy_errors",
    "tidy_temperatures",
    "unzeroed_matrix",
    "model_inputs",
    "tidy_signals",
    "logged_series",
    "derived_inputs",
    "cleaning_events",
]


@dataclass(frozen=True)
class RunTables:
    run: str
    series: pd.DataFrame  # cleaned temperatures on the common grid
    qc: pd.DataFrame
    gaps: pd.DataFrame
    errors: pd.DataFrame  # tidy, one row per measurement x position
    temperatures: pd.DataFrame  # tidy, one row per measurement x sensor
    windows: pd.DataFrame
    signals: pd.DataFrame  # tidy, one row per measurement x operating signal (may be empty)
    signal_series: pd.DataFrame  # time, elapsed_min and each operating signal on the grid
    notes: tuple[str, ...] = field(default=())


def minutes_since_first(times, windows: pd.DataFrame):
    """Minutes since the start of the run's first measurement (the paper's time axis)."""
    return (times - windows["start"].iloc[0]) / pd.Timedelta(minutes=1)


def tidy_errors(
    run: str, condition: str, windows: pd.DataFrame, combined: list[pd.Series]
) -> pd.DataFrame:
    """Unzeroed errors (passes combined) plus the re-zeroed view, one row per reading."""
    rows = []
    for (_, w), curve in zip(windows.iterrows(), combined, strict=False):
        first = curve.dropna()
        origin = first.iloc[0] if len(first) else np.nan
        time_min = minutes_since_first(w["start"], windows)
        for position, value in curve.items():
            rows.append(
                (
                    run,
                    condition,
                    int(w["measurement"]),
                    time_min,
                    float(position),
                    value,
                    value - origin,
                )
            )
    return pd.DataFrame(
        rows,
        columns=[
            "run",
            "condition",
            "measurement",
            "time_min",
            "position_mm",
            "error_um",
            "rezeroed_um",
        ],
    )


SIGNAL_COLUMNS = ["run", "condition", "measurement", "time_min", "signal", "value"]


def tidy_signals(
    run: str, condition: str, windows: pd.DataFrame, at_measurements: pd.DataFrame
) -> pd.DataFrame:
    """Operating signals (window means) per measurement, one row per measurement x signal."""
    time_min = minutes_since_first(windows["start"], windows).to_numpy()
    signals = [c for c in at_measurements.columns if c not in ("measurement", "start", "end")]
    frames = [
        pd.DataFrame(
            {
                "run": run,
                "condition": condition,
                "measurement": windows["measurement"].to_numpy(dtype=int),
                "time_min": time_min,
                "signal": signal,
                "value": at_measurements[signal].to_numpy(dtype=float),
            }
        )
        for signal in signals
    ]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=SIGNAL_COLUMNS)


def tidy_temperatures(
    run: str, condition: str, windows: pd.DataFrame, at_measurements: pd.DataFrame
) -> pd.DataFrame:
    """Absolute temperatures per measurement and their rise since the run's first measurement."""
    time_min = minutes_since_first(windows["start"], windows).to_numpy()
    sensors = [c for c in at_measurements.columns if c not in ("measurement", "start", "end")]
    frames = []
    for sensor in sensors:
        absolute = at_measurements[sensor].to_numpy(dtype=float)
        frames.append(
            pd.DataFrame(
                {
                    "run": run,
                    "condition": condition,
                    "measurement": windows["measurement"].to_numpy(dtype=int),
                    "time_min": time_min,
                    "sensor": sensor,
                    "absolute_c": absolute,
                    "relative_c": absolute - absolute[0],
                }
            )
        )
    return pd.concat(frames, ignore_index=True)


def clean_and_assemble_run(dataset: Dataset, raw: RawRun, cleaning: CleaningSettings) -> RunTables:
    """Clean one run's logs and assemble its unzeroed errors and measurement temperatures."""
    run, windows = raw.run, raw.windows()
    condition = dataset.condition_of(run)
    combined, notes = _combined_errors(raw, cleaning)
    combined, findings = _checked_displacement(raw, windows, combined, cleaning)
    notes.extend(
        displacement.finding_text(row, _finding_origin(raw, row)) for row in findings.itertuples()
    )
    cleaned, overlaps = _cleaned_temperatures(dataset, raw, windows, cleaning)
    offsets = dataset.clock_offsets_s()
    notes.extend(
        f"run {run}: {_temperature_file(dataset, run, source)}: clock offset not estimated: "
        f"{why}; the {offsets.get(source, 0.0):g} s that dataset.yaml declares is used (correct "
        "it there if the clock is off)"
        for source, why in cleaned.unestimated
    )
    at_measurements = temperatures_in_windows(cleaned.frame, windows, how=cleaning.window)
    sensors = [s for s in dataset.sensors if s in at_measurements.columns]
    if cleaning.allow_long_gaps:
        notes.extend(f"{run}: {o.text}" for o in overlaps)
        overlaps = []
    unusable = _unusable_sensors(dataset, raw, windows, at_measurements[sensors], overlaps)
    # A sensor that misses a measurement cannot be modelled on this run: it costs that
    # sensor, which leaves every fold's candidates (model_inputs), not the dataset.
    at_measurements[[u.sensor for u in unusable]] = np.nan
    notes.extend(
        f"{u.text}; {u.sensor} leaves the candidate sensors of every fold (it needs a reading in every "
        "measurement): raise temperatures.max_gap_s, or set temperatures.allow_long_gaps to average what "
        "the window has"
        for u in unusable
    )
    notes.extend(_excursion_text(raw, row) for row in cleaned.excursions.itertuples())
    notes.extend(_merged_text(dataset, raw, row) for row in cleaned.merged.itertuples())
    left_out = {u.sensor for u in unusable}
    flat = _flat_sensors(dataset, raw, cleaned.frame, [s for s in sensors if s not in left_out])
    notes.extend(f.text for f in flat)
    signal_frame = signals_on_grid(raw.signals, dataset.clock_offsets_s(), cleaned.frame["time"])
    signal_values = temperatures_in_windows(signal_frame, windows, how=cleaning.window)
    series = _with_elapsed(cleaned.frame, windows)
    return RunTables(
        run=run,
        series=series,
        qc=_with_run(
            _qc_table(cleaned.qc, findings, cleaned.excursions, cleaned.merged, unusable, flat), run
        ),
        gaps=_with_run(cleaned.gaps, run),
        errors=tidy_errors(run, condition, windows, combined),
        temperatures=tidy_temperatures(run, condition, windows, at_measurements[sensors]),
        windows=_with_run(windows, run),
        signals=tidy_signals(run, condition, windows, signal_values.drop(columns=["start", "end"])),
        signal_series=_with_elapsed(signal_frame, windows),
        notes=tuple(notes),
    )


@dataclass(frozen=True)
class CleanedRun:
    """One run through the clean stage: the warnings to log, in order, then its tables
    and time-aware inputs, or the error that stopped it (raised by the caller, in run
    order, after the warnings that explain it)."""

    run: str
    warnings: tuple[str, ...]
    tables: RunTables | None = None
    inputs: pd.DataFrame | None = None
    error: ValueError | None = None


def clean_run(folder, run: str, cleaning: CleaningSettings, lags_min) -> CleanedRun:
    """Read, check and clean one run of the dataset in ``folder`` (the clean rule's unit of
    work, one per worker process at a time). The plausibility warnings come before the
    cleaning, which may stop on what they explain (°F or kelvin readings)."""
    notes: tuple[str, ...] = ()
    try:
        dataset = load_dataset(folder)
        raw = read_run(dataset, run)
        notes = tuple(check_run_plausibility(dataset, raw, cleaning))
        tables = clean_and_assemble_run(dataset, raw, cleaning)
    except ValueError as exc:  # a DataError, or a reader's refusal
        return CleanedRun(run, notes, error=exc)
    # The time-aware inputs of the recommendation's candidates (recommend.lags_min and the
    # baseline's).
    inputs = derived_inputs(tables, lags_min, [])
    return CleanedRun(run, notes + tables.notes, tables, inputs)


def logged_series(series: pd.DataFrame, signal_series: pd.DataFrame) -> pd.DataFrame:
    """A run's cleaned log on its grid: ``time``, a column per sensor, then per operating signal.

    ``series`` and ``signal_series`` are the clean rule's ``temperatures.parquet`` and
    ``signals.parquet`` (the same grid, each with ``elapsed_min``, which is dropped).
    """
    frame = series.drop(columns="elapsed_min").reset_index(drop=True)
    signals = signal_series.drop(columns=["time", "elapsed_min"]).reset_index(drop=True)
    return pd.concat([frame, signals], axis=1)


def derived_inputs(tables: RunTables, lags_min, rates_min) -> pd.DataFrame:
    """Time-aware inputs of every temperature and operating signal at each measurement.

    First-order lags (time constants ``lags_min``) and rates of change (windows
    ``rates_min``) of the cleaned series on the run's grid, evaluated at the middle of
    each measurement window, the instant the window-mean temperature stands for. The
    filters start steady at the grid's first sample, a margin before the first
    measurement: the run's history starts where its measurements do. Gaps the cleaning
    left on the grid are bridged linearly for the filters, which need a value at every
    sample; a sensor unusable in the run (:func:`model_inputs`) gets none. One row per measurement x input
    (``input`` named like ``T5@lag30min``).
    """
    columns = ["run", "condition", "measurement", "time_min", "input", "value"]
    if not lags_min and not rates_min:
        return pd.DataFrame(columns=columns)
    frame = logged_series(tables.series, tables.signal_series)
    # A sensor unusable in this run (no temperature in some measurement) has no inputs.
    t = tables.temperatures
    unusable = pd.unique(t.loc[t["absolute_c"].isna(), "sensor"]).tolist()
    values = frame.drop(columns=["time", *unusable]).interpolate(limit_direction="both")
    if values.columns.empty:  # no sensor usable in this run and no signal: nothing to filter
        return pd.DataFrame(columns=columns)
    frame = pd.concat([frame[["time"]], values], axis=1)
    windows = tables.windows
    derived = time_inputs.inputs_at_measurements(
        frame,
        windows[["measurement", "start", "end"]],
        [60.0 * m for m in lags_min],
        [60.0 * m for m in rates_min],
        at="mid",
    )
    names = [c for c in derived.columns if "@" in c]
    long = derived.melt(
        id_vars=["measurement"], value_vars=names, var_name="input", value_name="value"
    )
    time_min = dict(
        zip(windows["measurement"], minutes_since_first(windows["start"], windows), strict=False)
    )
    long.insert(0, "run", tables.run)
    long.insert(1, "condition", tables.errors["condition"].iloc[0] if len(tables.errors) else "")
    long.insert(3, "time_min", long["measurement"].map(time_min).to_numpy(dtype=float))
    return long[columns].astype({"measurement": int, "value": float})


def _combined_errors(raw: RawRun, cleaning: CleaningSettings) -> tuple[list[pd.Series], list[str]]:
    """Every measurement's passes combined at the run's targets, and the warnings of doing so."""
    foreign = passes.foreign_targets(raw.measurements, cleaning.errors.max_missing_fraction)
    if foreign is not None:
        name, why = foreign
        raise DataError(f"measurement {raw.error_origin(name)}: {why}")
    targets = passes.run_targets(raw.measurements)
    measurements, strays = passes.without_strays(raw.measurements, targets)
    combined, notes = [], []
    for name, measurement in measurements.items():
        if name in strays:
            notes.append(f"measurement {raw.error_origin(name)}: {strays[name]}")
        curve, warns = passes.combine_passes(
            measurement, targets, cleaning.errors, name=raw.error_origin(name)
        )
        notes.extend(warns)
        combined.append(curve)
    return combined, notes


def _checked_displacement(
    raw: RawRun, windows: pd.DataFrame, combined: list[pd.Series], cleaning: CleaningSettings
) -> tuple[list[pd.Series], pd.DataFrame]:
    """The curves after the displacement QC's actions, and its findings; a step refused stops here."""
    qc = cleaning.displacement
    findings = displacement.displacement_findings(
        windows["start"],
        combined,
        threshold=qc.threshold,
        min_um=qc.min_deviation_um,
        outliers=qc.outliers,
        steps=qc.steps,
    )
    refused = findings[findings["action"] == "refuse"]
    if len(refused):
        row = next(refused.itertuples())
        raise DataError(
            f"{displacement.finding_text(row, _finding_origin(raw, row))}; expected one datum per run: "
            "split the run's measurements at the step into two runs, or set errors.steps: warn"
        )
    return displacement.apply_findings(combined, findings), findings


def _finding_origin(raw: RawRun, row) -> str:
    """The measurement a finding is in, as messages name it (its file)."""
    return raw.error_origin(list(raw.measurements)[row.measurement - 1])


# The QC table's columns of the temperature findings (excursions, unusable sensors).
EVENT_COLUMNS = ["start", "end", "size_c"]
MERGED_ACTION = "merged into the mean of their readings"


def _qc_table(
    temperature_qc: pd.DataFrame,
    findings: pd.DataFrame,
    excursions: pd.DataFrame,
    merged: pd.DataFrame,
    unusable,
    flat,
) -> pd.DataFrame:
    """One QC table: a row per sensor, then a row per finding.

    Displacement findings have sensor ``error_um``; a temperature excursion, a sensor
    with repeated timestamps of different readings, an unusable or a flat sensor names
    its sensor, with ``start``, ``end`` and (excursions, repeated timestamps: the largest
    spread) ``size_c``.
    """
    events = [
        findings.assign(sensor="error_um", source="errors"),
        _finding_rows(
            "excursion",
            excursions["sensor"],
            excursions["source"],
            excursions["start"],
            excursions["end"],
            [
                f"departs {r.size_c:+.2f} C from its trend for {r.duration_s:.0f} s and returns: "
                "a real event, or a sensor fault?"
                for r in excursions.itertuples()
            ],
            excursions["action"],
            size_c=excursions["size_c"],
        ),
        _finding_rows(
            "repeated_timestamps",
            merged["sensor"],
            merged["source"],
            merged["first"],
            merged["first"],
            [
                f"{r.n_timestamps} timestamp(s) logged more than once with different readings, "
                f"up to {r.spread_c:.3g} C apart; start: the first"
                for r in merged.itertuples()
            ],
            MERGED_ACTION,
            size_c=merged["spread_c"],
        ),
        _sensor_rows(unusable, "unusable", "left out of every fold's candidate sensors"),
        _sensor_rows(flat, "flat", "kept"),
    ]
    events = [e for e in events if len(e)]
    table = pd.concat([temperature_qc, *events], ignore_index=True) if events else temperature_qc
    return table.reindex(
        columns=[*temperature_qc.columns, *displacement.FINDING_COLUMNS, *EVENT_COLUMNS]
    )


def _finding_rows(
    finding: str, sensor, source, start, end, cause, action, size_c=None
) -> pd.DataFrame:
    """The QC rows of temperature findings of one kind: the sensor and its source, where in
    time, why and what was done; ``size_c`` where the finding has a size."""
    sizes = {} if size_c is None else {"size_c": size_c}
    return pd.DataFrame(
        {
            "sensor": sensor,
            "source": source,
            "finding": finding,
            "start": start,
            "end": end,
            **sizes,
            "cause": cause,
            "action": action,
        }
    )


def _sensor_rows(found: list, finding: str, action: str) -> pd.DataFrame:
    """The QC rows of sensor findings (:class:`SensorFinding`) of one kind."""
    return _finding_rows(
        finding,
        [f.sensor for f in found],
        [f.source for f in found],
        [f.start for f in found],
        [f.end for f in found],
        [f.text for f in found],
        action,
    )


def cleaning_events(qc: pd.DataFrame) -> pd.DataFrame:
    """The findings of a QC table alone (``tables/cleaning_events.csv``), one row each.

    Excursions and unusable sensors (with their start, end and size in C), and the
    displacement findings (measurement, position, size in um): what a reader of the
    index must see without scanning a row per sensor.
    """
    columns = ["run", "sensor", "finding", *EVENT_COLUMNS, "measurement", "position_mm",
               "size_um", "cause", "action"]  # fmt: skip
    events = qc.loc[qc["finding"].notna()] if "finding" in qc.columns else qc.iloc[:0]
    return events.reindex(columns=columns).reset_index(drop=True)


def _excursion_text(raw: RawRun, row) -> str:
    """One line per excursion: where, when, how large, and what was done with it."""
    return (
        f"run {raw.run}: sensor {row.sensor} ({row.source}) departs {row.size_c:+.2f} C from its trend "
        f"from {row.start} to {row.end} ({row.duration_s:.0f} s) and returns: an excursion, "
        f"{row.action} (temperatures.excursions)"
    )


def _merged_text(dataset: Dataset, raw: RawRun, row) -> str:
    """One line per sensor whose log repeats a timestamp with different readings."""
    return (
        f"run {raw.run}: {_temperature_file(dataset, raw.run, row.source)}: sensor {row.sensor} has "
        f"{row.n_timestamps} repeated timestamp(s) with different readings, the first at {row.first} "
        f"(up to {row.spread_c:.3g} C apart); each was {MERGED_ACTION}"
    )


def _temperature_file(dataset: Dataset, run: str, source: str):
    return log_file(dataset.root / run, source)


def _cleaned_temperatures(
    dataset: Dataset, raw: RawRun, windows: pd.DataFrame, cleaning: CleaningSettings
):
    """The run's temperatures on the grid, and each sensor's long gaps during a measurement."""
    settings = cleaning.temperatures
    # The grid spans the measurements with a margin so window means never extrapolate.
    margin = pd.Timedelta(seconds=max(60.0, 3 * settings.interval_s))
    start, end = windows["start"].min() - margin, windows["end"].max() + margin
    try:
        cleaned = clean_temperatures(
            raw.sources, dataset.clock_offsets_s(), settings, start=start, end=end
        )
    except ValueError as exc:
        raise DataError(f"{dataset.root / raw.run / 'temperatures'}: {exc}") from None
    files = {
        s: _temperature_file(dataset, raw.run, source)
        for s, source in _source_of(dataset, raw).items()
    }
    overlaps = gap_overlaps(cleaned.gaps, windows, max_gap_s=settings.max_gap_s, files=files)
    return cleaned, overlaps


@dataclass(frozen=True)
class SensorFinding:
    """A sensor of a run that is unusable (no reading in some measurement) or flat, and why (``text``)."""

    sensor: str
    source: str
    start: pd.Timestamp
    end: pd.Timestamp
    text: str


def _source_of(dataset: Dataset, raw: RawRun) -> dict[str, str]:
    """The source (logger) of each sensor the run's logs hold."""
    return {s: src for src in raw.sources for s in dataset.sensors_of(src)}


def _unusable_sensors(
    dataset: Dataset, raw: RawRun, windows: pd.DataFrame, at_measurements: pd.DataFrame, overlaps
) -> list[SensorFinding]:
    """The sensors that miss a measurement: a long gap over it, or no value in its window."""
    source_of = _source_of(dataset, raw)
    out = [
        SensorFinding(
            o.sensor, source_of.get(o.sensor, ""), o.start, o.end, f"run {raw.run}: {o.text}"
        )
        for o in overlaps
    ]
    named = {u.sensor for u in out}
    missing = at_measurements.isna()
    for sensor in (s for s in at_measurements.columns if missing[s].any() and s not in named):
        window = windows.loc[missing[sensor].to_numpy()].iloc[0]
        source = source_of[sensor]
        out.append(
            SensorFinding(
                sensor,
                source,
                window["start"],
                window["end"],
                f"{_temperature_file(dataset, raw.run, source)}: sensor {sensor!r} of run {raw.run!r} has no "
                f"usable reading during measurement {window['measurement']} ({window['name']}, "
                f"{window['start']} to {window['end']})",
            )
        )
    return out


def _flat_sensors(
    dataset: Dataset, raw: RawRun, frame: pd.DataFrame, sensors: list[str]
) -> list[SensorFinding]:
    """Sensors that read one value through the whole run while another sensor's reading
    changes: a stuck sensor, or a place that stayed put (a 0.1 C display far from the
    heat). Kept, with a warning and a QC row: only the user can tell which."""
    values = {s: frame[s].to_numpy(dtype=float) for s in sensors}
    values = {s: v[np.isfinite(v)] for s, v in values.items()}
    spans = {s: float(np.ptp(v)) for s, v in values.items() if v.size > 1}
    if not any(span > 0.0 for span in spans.values()):
        return []  # nothing changes in this run: no sensor stands out
    source_of = _source_of(dataset, raw)
    start, end = frame["time"].iloc[0], frame["time"].iloc[-1]
    return [
        SensorFinding(
            sensor,
            source_of[sensor],
            start,
            end,
            f"{_temperature_file(dataset, raw.run, source_of[sensor])}: sensor {sensor} of "
            f"run {raw.run} reads {values[sensor][0]:g} C throughout the run while other sensors "
            "change: a stuck sensor? (kept)",
        )
        for sensor, span in spans.items()
        if span == 0.0
    ]


def _with_elapsed(frame: pd.DataFrame, windows: pd.DataFrame) -> pd.DataFrame:
    """``frame`` (time first) with the minutes since the run's first measurement beside its time."""
    out = frame.copy()
    out.insert(1, "elapsed_min", minutes_since_first(out["time"], windows))
    return out


def _with_run(frame: pd.DataFrame, run: str) -> pd.DataFrame:
    out = frame.copy()
    out.insert(0, "run", run)
    return out


def unzeroed_matrix(errors: pd.DataFrame, value: str = "error_um") -> pd.DataFrame:
    """Measurement x position matrix (rows (run, measurement), columns position_mm).

    Only the (run, measurement) pairs that exist get a row, so runs of different
    lengths stay as long as they are; a target a measurement lacks is NaN.
    """
    matrix = errors.set_index(["run", "measurement", "position_mm"])[value].unstack("position_mm")
    return matrix.sort_index(axis=0).sort_index(axis=1)


def model_inputs(
    errors: pd.DataFrame,
    temperatures: pd.DataFrame,
    sensors=None,
    signals: pd.DataFrame | None = None,
    inputs: pd.DataFrame | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The estimators' view: X (run, measurement, time_min, absolute temperature per sensor) and Y.

    Relative temperatures are NOT passed: the models derive them from each run's own
    first measurement, so a held-out run can never borrow another run's start.
    ``signals`` (the tidy operating-signal table) adds one column per signal after the
    sensors, for models asked to use them as inputs; ``inputs`` (the tidy table of
    :func:`derived_inputs`) one column per time-aware input after those.

    A sensor without a temperature in some measurement of some run (the clean rule
    named it unusable there, and why) is left out, with its time-aware inputs: with
    leave-one-condition-out every fold trains or tests on every run, so it is no
    candidate of any fold. It costs that sensor only; none left is an error.
    """
    wide = _absolute_by_measurement(temperatures)
    if sensors is None:
        # Natural order (T2 before T10), so clusters and tables read like the paper's.
        sensors = sorted(wide.columns, key=natural_key)
    times = errors.groupby(["run", "measurement"], sort=True)["time_min"].first()
    Y = unzeroed_matrix(errors)
    index = Y.index.intersection(wide.index)
    if len(index) != len(Y.index):
        missing = Y.index.difference(wide.index)[0]
        raise DataError(
            f"assembled tables: run {missing[0]!r} measurement {missing[1]} has errors but no temperatures"
        )
    X = wide.loc[index, list(sensors)]
    unusable = [s for s in X.columns if X[s].isna().any()]
    if len(unusable) == X.shape[1]:
        raise DataError(
            f"assembled tables: every sensor ({', '.join(map(str, unusable))}) misses a measurement in some run "
            "(tables/cleaning_qc.csv, finding 'unusable'); expected at least one sensor read in every measurement"
        )
    X = X.drop(columns=unusable)
    X = _with_inputs(X, index, signals, inputs, unusable)
    X = X.reset_index()
    X.insert(2, "time_min", times.loc[index].to_numpy())
    X.columns.name = None
    Y = Y.loc[index].reset_index(drop=True)
    Y.columns = [float(c) for c in Y.columns]
    Y.columns.name = None
    return X, Y


def _absolute_by_measurement(temperatures: pd.DataFrame) -> pd.DataFrame:
    """Absolute temperature per (run, measurement) row and sensor column."""
    wide = temperatures.pivot_table(
        index=["run", "measurement"], columns="sensor", values="absolute_c", sort=True
    )
    # A sensor unusable in every run has no value to pivot, and is still a column; a
    # measurement no sensor was read in (every log of the run starts late) is still a row.
    read = pd.MultiIndex.from_frame(temperatures[["run", "measurement"]].drop_duplicates())
    wide = wide.reindex(index=wide.index.union(read), columns=pd.unique(temperatures["sensor"]))
    return wide


def _with_inputs(X: pd.DataFrame, index, signals, inputs, unusable: list) -> pd.DataFrame:
    """X with the operating signals, then the time-aware inputs of the usable sensors."""
    if signals is not None and len(signals):
        signal_wide = signals.pivot_table(
            index=["run", "measurement"], columns="signal", values="value", sort=True
        )
        X = X.join(signal_wide.reindex(index)[sorted(signal_wide.columns, key=natural_key)])
    if inputs is not None and len(inputs):
        derived = inputs.pivot_table(
            index=["run", "measurement"], columns="input", values="value", sort=True
        )
        kept = [c for c in derived.columns if time_inputs.base_of(c) not in unusable]
        X = X.join(derived.reindex(index)[sorted(kept, key=natural_key)])
    return X
