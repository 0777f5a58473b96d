"""Validating reader for the raw-data layout documented in ``data/README.md``.

Every problem is reported as a :class:`DataError` whose message is ONE line naming
the file, the row (1-based line number in the file, header = line 1) or column, and
what was expected.  The reader never repairs anything: repairs belong to
:mod:`thermaxis.cleaning`, which reports what it did.
"""

from __future__ import annotations

import csv
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import jsonschema
import numpy as np
import pandas as pd

from thermaxis.dataset import layout, plausibility, safety
from thermaxis.errors import DataError, schema_message, shown
from thermaxis.labels import natural_key
from thermaxis.schemas import load_schema

__all__ = [
    "Dataset",
    "RawRun",
    "load_dataset",
    "read_run",
    "read_temperature_source",
    "read_measurement",
    "read_measurements",
    "read_measurements_of",
    "read_first_measurement",
]

RUN_COLUMNS = ("run", "condition", "description")
ERROR_COLUMNS = ("time", "position_mm", "error_um")
# One file per run holding every measurement, told apart by this column.
MEASUREMENT_COLUMN = "measurement"
# A clock put back an hour between two samples logged ``interval`` apart shows a step back
# of an hour less that interval; give or take a minute, or half an interval.
DST_S = 3600.0


def clock_back_hint(back_s: float, interval_s: float) -> str:
    """What a message adds for a clock that went back ``back_s`` seconds in a log sampled
    about every ``interval_s`` seconds: the step of a daylight-saving change, most often."""
    expected = DST_S - interval_s
    if expected > 0 and abs(back_s - expected) <= max(60.0, interval_s / 2):
        return "; a daylight-saving change? log in UTC or in standard time"
    return ""


def median_step_s(seconds: np.ndarray) -> float:
    """The median of a time series' forward steps, in seconds (0 without any)."""
    steps = np.diff(seconds)
    forward = steps[steps > 0]
    return float(np.median(forward)) if forward.size else 0.0


def _schema_error(path: Path, error: jsonschema.ValidationError, where: str = "") -> DataError:
    location = "/".join(str(p) for p in error.absolute_path) or "top level"
    prefix = f"{path}: {where}" if where else f"{path}: "
    return DataError(f"{prefix}{location}: {schema_message(error)}")


@dataclass(frozen=True)
class Dataset:
    """A validated dataset: metadata, the runs sheet and where it lives."""

    root: Path
    meta: dict
    runs: pd.DataFrame
    sensors: tuple[str, ...] = field(default=())

    @property
    def name(self) -> str:
        return self.meta["name"]

    @property
    def simulated(self) -> bool:
        return self.meta["provenance"]["kind"] == "simulated"

    @property
    def run_ids(self) -> tuple[str, ...]:
        return tuple(self.runs["run"])

    @property
    def reproduces(self) -> str | None:
        """The publication whose experiment this dataset reproduces (e.g. ``xu2023``), if any."""
        return self.meta.get("reproduces")

    @property
    def ambient_sensor(self) -> str | None:
        return self.meta.get("ambient_sensor")

    @property
    def temperature_kind(self) -> str:
        """``absolute`` (degrees C) or ``rise`` (degrees C above the logger's own reference)."""
        return self.meta.get("temperature_kind", "absolute")

    @property
    def signals(self) -> tuple[str, ...]:
        """Operating signals (spindle speed, feed programme, ...) logged over time like temperatures."""
        return tuple(s["id"] for s in self.meta.get("signals", ()))

    def signal_units(self) -> dict[str, str]:
        return {s["id"]: s["unit"] for s in self.meta.get("signals", ())}

    @property
    def descriptors(self) -> tuple[str, ...]:
        """Optional numeric columns of runs.tsv describing each run's operating condition."""
        return tuple(
            c
            for c in self.runs.columns
            if c not in RUN_COLUMNS and pd.api.types.is_float_dtype(self.runs[c])
        )

    def sensors_of(self, source: str) -> tuple[str, ...]:
        return tuple(s["id"] for s in self.meta["sensors"] if s["source"] == source)

    def signals_of(self, source: str) -> tuple[str, ...]:
        return tuple(s["id"] for s in self.meta.get("signals", ()) if s["source"] == source)

    @property
    def sources(self) -> tuple[str, ...]:
        return tuple(s["name"] for s in self.meta["sources"])

    def clock_offsets_s(self) -> dict[str, float]:
        return {s["name"]: float(s.get("clock_offset_s", 0.0)) for s in self.meta["sources"]}

    def condition_of(self, run: str) -> str:
        return str(self.runs.loc[self.runs["run"] == run, "condition"].iloc[0])


def _read_yaml(path: Path) -> dict:
    if not path.exists():
        raise DataError(f"{path}: file not found (every dataset needs dataset.yaml)")
    doc = safety.load_yaml(path)
    if not isinstance(doc, dict):
        raise DataError(f"{path}: expected a mapping at top level, got {type(doc).__name__}")
    return doc


def _validate_meta(path: Path, meta: dict) -> None:
    validator = jsonschema.Draft202012Validator(load_schema("dataset"))
    errors = sorted(validator.iter_errors(meta), key=lambda e: list(e.absolute_path))
    if errors:
        raise _schema_error(path, errors[0])
    ids = [s["id"] for s in meta["sensors"]]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise DataError(f"{path}: sensors: sensor id {dup[0]!r} declared more than once")
    signals = [s["id"] for s in meta.get("signals", ())]
    clash = sorted(set(signals) & set(ids) | {i for i in signals if signals.count(i) > 1})
    if clash:
        raise DataError(
            f"{path}: signals: id {clash[0]!r} declared more than once (sensor and signal ids share one namespace)"
        )
    sources = {s["name"] for s in meta["sources"]}
    for kind, items in (("sensors", meta["sensors"]), ("signals", meta.get("signals", ()))):
        for i, item in enumerate(items):
            if item["source"] not in sources:
                raise DataError(
                    f"{path}: {kind}/{i}: source {item['source']!r} of {item['id']!r} "
                    f"is not one of the declared sources {sorted(sources)}"
                )
    ambient = meta.get("ambient_sensor")
    if ambient is not None and ambient not in ids:
        raise DataError(
            f"{path}: ambient_sensor: {ambient!r} is not a declared sensor id (expected one of {', '.join(ids)})"
        )


def _coerce_cell(value: str, kind: str):
    if kind == "integer":
        number = int(value)
        if abs(number) >= 2**63:
            raise ValueError(value)  # beyond every table's 64-bit integers
        return number
    if kind == "number":
        number = float(value)
        if not np.isfinite(number):
            raise ValueError(value)
        return number
    return value


def _numeric_descriptors(runs: pd.DataFrame, path: Path) -> pd.DataFrame:
    """Optional columns whose every filled cell is a number become numeric (empty = NaN)."""
    for column in runs.columns:
        if column in RUN_COLUMNS:
            continue
        cells = runs[column].where(runs[column].notna(), "").astype(str).str.strip()
        numbers = pd.to_numeric(cells.where(cells != "", None), errors="coerce")
        if (numbers.notna() | (cells == "")).all() and numbers.notna().any():
            infinite = ~np.isfinite(numbers.fillna(0.0).to_numpy(dtype=float))
            if infinite.any():
                i = int(np.flatnonzero(infinite)[0])
                raise DataError(
                    f"{path}: run {runs['run'].iloc[i]!r}, column {column!r}: expected a finite number, got {shown(cells.iloc[i])}"
                )
            runs[column] = numbers.astype(float)
    return runs


def _read_runs(path: Path) -> pd.DataFrame:  # noqa: PLR0915 -- reader.py is being split on branch layers
    if not path.exists():
        raise DataError(f"{path}: file not found (every dataset needs runs.tsv)")
    safety.sniff_delimited(path, "\t", safety.MAX_SHEET_BYTES)
    with open(path, encoding="utf-8-sig", newline="") as fh:
        rows = [row for _, row in _csv_rows(fh, path, "\t")]
    if not rows:
        raise DataError(
            f"{path}: empty file, expected a tab-separated header {' '.join(RUN_COLUMNS)}"
        )
    header = [h.strip() for h in rows[0]]
    missing = [c for c in RUN_COLUMNS if c not in header]
    if missing:
        raise DataError(
            f"{path}: missing column {missing[0]!r} (expected tab-separated columns {', '.join(RUN_COLUMNS)})"
        )
    if len(rows) < 2:
        raise DataError(f"{path}: no runs listed (expected one row per run)")
    schema = load_schema("runs")
    validator = jsonschema.Draft202012Validator(schema)
    records = []
    for lineno, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            # Only a surplus can come from a tab inside a text.
            hint = safety.field_count_hint("\t" if len(row) > len(header) else "", header)
            raise DataError(
                f"{path}: line {lineno}: {len(row)} tab-separated fields but the header has "
                f"{len(header)}{hint}"
            )
        record = {}
        for name, cell in zip(header, row, strict=False):
            kind = schema["properties"].get(name, {}).get("type", "string")
            if name not in RUN_COLUMNS and not cell.strip():
                continue  # an optional column left empty for this run
            try:
                record[name] = _coerce_cell(cell.strip(), kind)
            except ValueError:
                raise DataError(
                    f"{path}: line {lineno}, column {name!r}: expected {'an integer' if kind == 'integer' else 'a finite number'}, got {shown(cell)}"
                ) from None
        errors = list(validator.iter_errors(record))
        if errors:
            err = errors[0]
            column = err.absolute_path[0] if err.absolute_path else ""
            raise DataError(f"{path}: line {lineno}, column {column!r}: {schema_message(err)}")
        records.append(record)
    runs = pd.DataFrame.from_records(records, columns=header)
    dup = runs["run"][runs["run"].duplicated()]
    if len(dup):
        raise DataError(f"{path}: run {dup.iloc[0]!r} listed more than once")
    runs = _numeric_descriptors(runs, path)
    return runs.sort_values("run", kind="stable", key=lambda c: c.map(natural_key)).reset_index(
        drop=True
    )


def load_dataset(root) -> Dataset:
    """Read and validate ``dataset.yaml`` and ``runs.tsv`` and check run folders.

    A run listed without a folder, or a folder that is not listed, is an error: a
    silently ignored run would change every model without anyone noticing.
    """
    root = Path(root)
    if not root.is_dir():
        raise DataError(f"{root}: dataset folder not found")
    meta = _read_yaml(root / "dataset.yaml")
    _validate_meta(root / "dataset.yaml", meta)
    runs = _read_runs(root / "runs.tsv")
    listed = set(runs["run"])
    for run in runs["run"]:
        if not (root / run).is_dir():
            raise DataError(f"{root / 'runs.tsv'}: run {run!r} has no folder {root / run}")
    for child in sorted(root.iterdir()):
        if child.is_dir() and not child.name.startswith(".") and child.name not in listed:
            if (
                (child / "errors").is_dir()
                or (child / "errors.csv").exists()
                or (child / "temperatures").is_dir()
            ):
                raise DataError(f"{child}: run folder is not listed in {root / 'runs.tsv'}")
    sensors = tuple(s["id"] for s in meta["sensors"])
    return Dataset(root=root, meta=meta, runs=runs, sensors=sensors)


def _read_csv(
    path: Path, short_rows_missing: bool = False, header_only: bool = False
) -> pd.DataFrame:
    """A data file's cells as text. ``short_rows_missing``: a row with fewer fields than
    the header is read with its missing fields empty, with a warning (a log); otherwise
    it is refused (a measurement, whose every reading is needed). ``header_only``: a
    header without data rows is read as no rows rather than refused."""
    if safety.check_regular_file(path, what="data file") == 0:
        raise DataError(f"{path}: empty file, expected a header and data rows")
    safety.sniff_delimited(path, ",")
    try:
        frame = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise DataError(f"{path}: empty file, expected a header and data rows") from None
    except UnicodeDecodeError as exc:
        raise DataError(
            f"{path}: byte 0x{exc.object[exc.start]:02x} is not UTF-8; expected UTF-8 text"
        ) from None
    except pd.errors.ParserError as exc:
        raise DataError(f"{path}: not a valid CSV file ({str(exc).splitlines()[0]})") from None
    frame.columns = [str(c).strip() for c in frame.columns]
    if frame.empty and not header_only:
        raise DataError(f"{path}: no data rows below the header")
    # The parser pads a row that ends early with empty cells, as if they were blanks: a
    # line cut short (a logger stopped mid-write) would pass unsaid. Only a file with an
    # empty last cell can hold such a row, so only that one is scanned.
    if (frame.iloc[:, -1] == "").any():
        _check_short_rows(path, list(frame.columns), short_rows_missing)
    return frame


def _csv_rows(fh, path: Path, delimiter: str):
    """(line number, fields) of each row; a line the csv module refuses (a field longer
    than its limit) is a DataError naming it, as pandas, which read the file first, has
    no such limit."""
    rows = csv.reader(fh, delimiter=delimiter)
    kind = "tab" if delimiter == "\t" else "comma"
    while True:
        try:
            row = next(rows)
        except StopIteration:
            return
        except csv.Error as exc:
            raise DataError(
                f"{path}: line {rows.line_num}: {exc}; expected short {kind}-separated fields"
            ) from None
        yield rows.line_num, row


def _check_short_rows(path: Path, names: list[str], missing: bool) -> None:
    short = []
    with open(path, newline="", encoding="utf-8-sig") as fh:
        rows = _csv_rows(fh, path, ",")
        next(rows, None)
        for line, row in rows:
            if row and len(row) < len(names):
                short.append((line, len(row)))
                if not missing:
                    break
    if not short:
        return
    line, n_fields = short[0]
    what = f"{path}: line {line}: {n_fields} comma-separated fields but the header has {len(names)}"
    if not missing:
        raise DataError(
            f"{what}; expected {len(names)} fields ({', '.join(names)}), an empty one for a "
            "missing value (a line cut short?)"
        )
    more = f" (and {len(short) - 1} more line(s))" if len(short) > 1 else ""
    warnings.warn(
        f"{what}{more}; a line cut short? Its missing fields are read as missing samples",
        stacklevel=3,
    )


def _parse_time(path: Path, values: pd.Series) -> pd.Series:
    plausibility.check_time_zones(path, values)
    parsed = pd.to_datetime(values, format="ISO8601", errors="coerce")
    bad = parsed.isna().to_numpy()
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        cell = str(values.iloc[i]).strip()
        # A first row with no digit in its time is most often a units row under the header.
        units = (
            "; a units row? the layout has none (temperatures in degrees C, errors in um: "
            "data/README.md)"
            if i == 0 and not any(ch.isdigit() for ch in cell)
            else ""
        )
        raise DataError(
            f"{path}: line {i + 2}, column 'time': expected an ISO 8601 time, got "
            f"{shown(values.iloc[i])}{units}"
        )
    if getattr(parsed.dt, "tz", None) is not None:
        raise DataError(
            f"{path}: column 'time': expected times without a time zone (one zone per dataset)"
        )
    plausibility.check_time_range(path, parsed, values)
    return parsed.astype("datetime64[ns]")


def _parse_numbers(path: Path, frame: pd.DataFrame, column: str, allow_empty: bool) -> np.ndarray:
    raw = frame[column].str.strip()
    empty = raw == ""
    numbers = pd.to_numeric(raw.where(~empty, None), errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(numbers) & ~empty.to_numpy()
    if not allow_empty:
        bad |= empty.to_numpy()
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"{path}: line {i + 2}, column {column!r}: expected a number, got {shown(frame[column].iloc[i])}"
        )
    return numbers


def _check_time_order(path: Path, time: pd.Series, where: str = "") -> None:
    """Times must not go back; the series' index is the row's position in the file (header = line 1)."""
    ns = time.to_numpy().astype("int64")
    step = np.diff(ns)
    back = np.flatnonzero(step < 0)
    if back.size:
        i = int(back[0]) + 1
        raise DataError(
            f"{path}: line {int(time.index[i]) + 2}, column 'time': time goes backwards "
            f"({time.iloc[i]} after {time.iloc[i - 1]}){where}"
            f"{clock_back_hint(-step[i - 1] / 1e9, median_step_s(ns / 1e9))}"
        )


def read_temperature_source(
    path, expected_sensors, known_sensors, kind: str = "sensor"
) -> pd.DataFrame:
    """One source's log: ``time`` + one float column per sensor (or signal; NaN = missing)."""
    path = Path(path)
    # A temperature logger that recorded nothing in a run costs its sensors there, as an
    # absent log does (_read_logs); a signal's readings are every model's input.
    frame = _read_csv(path, short_rows_missing=True, header_only=kind == "sensor")
    if "time" not in frame.columns:
        raise DataError(f"{path}: missing column 'time' (expected time + one column per {kind})")
    columns = [c for c in frame.columns if c != "time"]
    for column in columns:
        if column not in known_sensors:
            raise DataError(
                f"{path}: column {column!r}: unknown {kind} id (not declared in dataset.yaml)"
            )
        if column not in expected_sensors:
            raise DataError(
                f"{path}: column {column!r}: {kind} is declared for another source in dataset.yaml"
            )
    if kind != "sensor":
        for signal in expected_sensors:
            if signal not in columns:
                raise DataError(
                    f"{path}: missing column {signal!r} (declared for this source in dataset.yaml)"
                )
    times = pd.DataFrame({"time": _parse_time(path, frame["time"])})
    _check_time_order(path, times["time"])
    readings = {}
    for sensor in expected_sensors:
        # A declared temperature sensor without a column in this run's log has no reading,
        # as an empty column has none: cleaning names it and it leaves this run's folds;
        # one sensor must not cost the dataset (issue 33). An operating signal is every
        # model's input: without it the run cannot be modelled, so it is refused above.
        readings[sensor] = (
            _parse_numbers(path, frame, sensor, allow_empty=True)
            if sensor in columns
            else np.full(len(times), np.nan)
        )
        if kind != "sensor" and np.isnan(readings[sensor]).all():
            raise DataError(
                f"{path}: column {sensor!r}: no reading in any row; expected the signal's readings "
                "(every model that uses the signal reads it)"
            )
    # Joined at once: a column added at a time fragments the frame of a 100-sensor log.
    return pd.concat([times, pd.DataFrame(readings, index=times.index)], axis=1)


def _parse_readings(path: Path, frame: pd.DataFrame) -> pd.DataFrame:
    """time, position_mm, error_um, direction of validated interferometer readings."""
    out = pd.DataFrame(
        {
            "time": _parse_time(path, frame["time"]),
            "position_mm": _parse_numbers(path, frame, "position_mm", allow_empty=False),
            "error_um": _parse_numbers(path, frame, "error_um", allow_empty=False),
        }
    )
    if "direction" in frame.columns:
        direction = frame["direction"].str.strip()
        bad = ~direction.isin(["+", "-"])
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise DataError(
                f"{path}: line {i + 2}, column 'direction': expected '+' or '-', got {shown(frame['direction'].iloc[i])}"
            )
        out["direction"] = direction.to_numpy(dtype=object)
    else:
        out["direction"] = "+"
    return out


def _require_error_columns(path: Path, frame: pd.DataFrame, columns) -> None:
    for column in columns:
        if column not in frame.columns:
            raise DataError(
                f"{path}: missing column {column!r} (expected {', '.join(columns)}[, direction])"
            )


def read_measurement(path) -> pd.DataFrame:
    """One interferometer measurement: time, position_mm, error_um, direction."""
    path = Path(path)
    frame = _read_csv(path)
    _require_error_columns(path, frame, ERROR_COLUMNS)
    out = _parse_readings(path, frame)
    _check_time_order(path, out["time"])
    _check_repeated_positions(path, out)
    return out


def read_measurements(path) -> dict[str, pd.DataFrame]:
    """Every measurement of a run from ONE file, told apart by its ``measurement`` column.

    Readings of one measurement must not go back in time; measurements may interleave
    only in the sense that the file is grouped by label, in any order.
    """
    return _read_run_file(Path(path))[0]


def _read_run_file(path: Path) -> tuple[dict[str, pd.DataFrame], dict[str, np.ndarray]]:
    """:func:`read_measurements`, and the file line of each measurement's readings (header = line 1)."""
    frame = _read_csv(path)
    _require_error_columns(path, frame, (MEASUREMENT_COLUMN, *ERROR_COLUMNS))
    labels = frame[MEASUREMENT_COLUMN].str.strip()
    # A label names the measurement as a file stem would, so it obeys the same rule.
    bad = ~labels.str.fullmatch(safety.NAME_PATTERN)
    if bad.any():
        i = int(np.flatnonzero(bad.to_numpy())[0])
        raise DataError(
            f"{path}: line {i + 2}, column {MEASUREMENT_COLUMN!r}: expected a measurement name matching "
            f"{safety.NAME_PATTERN}, got {shown(frame[MEASUREMENT_COLUMN].iloc[i])}"
        )
    readings = _parse_readings(path, frame)
    out, lines = {}, {}
    for label in dict.fromkeys(labels):
        rows = readings[(labels == label).to_numpy()]
        _check_time_order(path, rows["time"], f" within measurement {label!r}")
        _check_repeated_positions(path, rows.reset_index(drop=True), f"measurement {label!r}: ")
        out[label] = rows.reset_index(drop=True)
        lines[label] = rows.index.to_numpy() + 2
    return out, lines


def _check_repeated_positions(path: Path, frame: pd.DataFrame, where: str = "") -> None:
    """Exact repeats are harmless logging duplicates; conflicting ones are not."""
    grouped = frame.groupby(["direction", "position_mm"], sort=True)["error_um"]
    spread = grouped.max() - grouped.min()
    conflicting = spread[spread > 0]
    if len(conflicting):
        direction, position = conflicting.index[0]
        values = frame.loc[
            (frame["direction"] == direction) & (frame["position_mm"] == position), "error_um"
        ].tolist()
        raise DataError(
            f"{path}: {where}column 'position_mm': position {position:g} mm appears twice in the {direction!s} pass "
            f"with different errors {values} (expected one reading per target and pass)"
        )


@dataclass(frozen=True)
class RawRun:
    run: str
    sources: Mapping[str, pd.DataFrame]
    measurements: Mapping[str, pd.DataFrame]  # ordered by first reading's time
    signals: Mapping[str, pd.DataFrame] = field(default_factory=dict)
    # Measurement -> the file its readings are in (its own CSV, or the run's one errors.csv)
    # and the file line of each reading (header = line 1), so messages point at real lines.
    error_files: Mapping[str, Path] = field(default_factory=dict)
    error_lines: Mapping[str, np.ndarray] = field(default_factory=dict)

    def error_origin(self, name: str) -> str:
        """Measurement ``name`` as messages name it: its file, with its label when the run's
        measurements share one errors.csv (a measurement's own file is named after it)."""
        path = self.error_files.get(name)
        if path is None:
            return name  # a run built in memory
        return str(path) if path.stem == name else f"{name} in {path}"

    def windows(self) -> pd.DataFrame:
        """Measurement number, name and time window (first to last reading)."""
        rows = [
            (i, name, m["time"].iloc[0], m["time"].iloc[-1])
            for i, (name, m) in enumerate(self.measurements.items(), start=1)
        ]
        return pd.DataFrame(rows, columns=["measurement", "name", "start", "end"])


def _read_logs(folder: Path, dataset: Dataset, kind: str) -> dict[str, pd.DataFrame]:
    """Per-source logs of a run's sensors (``temperatures/``) or signals (``signals/``)."""
    of = dataset.sensors_of if kind == "sensor" else dataset.signals_of
    known = set(dataset.sensors if kind == "sensor" else dataset.signals)
    logs = {}
    for source in dataset.sources:
        expected = of(source)
        if expected:
            path = safety.check_inside(folder / f"{source}.csv", dataset.root, what=f"{kind} file")
            if kind == "sensor" and not path.is_symlink() and not path.exists():
                # A logger that recorded nothing in this run costs its sensors there, not the
                # run (issue 33): they have no reading, as a missing column has none. An
                # operating signal is every model's input: its log is required.
                logs[source] = _no_readings(expected)
                continue
            logs[source] = read_temperature_source(path, expected, known, kind)
    if kind == "sensor" and not any(len(log) for log in logs.values()):
        raise DataError(
            f"{folder}: no temperature reading (every log absent or without data rows); expected "
            f"one CSV per source that dataset.yaml declares sensors for ({', '.join(f'{s}.csv' for s in logs)})"
        )
    if folder.is_dir():
        for extra in sorted(folder.glob("*.csv")):
            if extra.stem not in dataset.sources:
                logged = "temperature" if kind == "sensor" else kind
                raise DataError(
                    f"{extra}: unknown {logged} source {extra.stem!r} (not declared in dataset.yaml)"
                )
            if not of(extra.stem):
                raise DataError(
                    f"{extra}: source {extra.stem!r} logs no {kind} declared in dataset.yaml"
                )
    return logs


def _no_readings(sensors) -> pd.DataFrame:
    """A source's log with its sensors' columns and no reading (its file is absent)."""
    return pd.DataFrame(
        {
            "time": pd.Series([], dtype="datetime64[ns]"),
            **{s: pd.Series([], dtype=float) for s in sensors},
        }
    )


def _measurement_source(dataset: Dataset, run: str) -> tuple[Path, list[Path]]:
    """Where a run's measurements are: ``<run>/errors.csv`` (one file) or ``<run>/errors/*.csv``."""
    folder = dataset.root / run
    err_dir, err_file = folder / layout.ERRORS_FOLDER, folder / layout.ERRORS_FILE
    if err_dir.is_dir() and err_file.exists():
        raise DataError(
            f"{err_file}: the run also has a folder {err_dir}; expected one of the two layouts"
        )
    if layout.error_source(folder) == err_file:
        return err_file, [safety.check_inside(err_file, dataset.root, what="measurement file")]
    if not err_dir.is_dir():
        raise DataError(
            f"{err_dir}: folder not found (expected one CSV per interferometer measurement, or {err_file})"
        )
    files = sorted(err_dir.glob("*.csv"))
    for f in files:
        safety.check_name(f.stem, "measurement", f)
        safety.check_inside(f, dataset.root, what="measurement file")
    return err_dir, files


def _read_measurement_files(source: Path, files: list[Path]) -> tuple[dict, dict, dict]:
    """Measurements, the file of each and the file line of each reading, in either layout."""
    if source.is_file():
        measurements, lines = _read_run_file(files[0])
        return measurements, dict.fromkeys(measurements, files[0]), lines
    measurements = {f.stem: read_measurement(f) for f in files}
    lines = {name: np.arange(len(m)) + 2 for name, m in measurements.items()}
    return measurements, {f.stem: f for f in files}, lines


def read_measurements_of(
    dataset: Dataset, run: str, min_measurements: int = 1
) -> tuple[dict, dict, dict]:
    """A run's measurements, ordered by their first reading's time; the file of each; its file lines.

    Measurements come either from ``<run>/errors/<measurement>.csv`` (one file each) or
    from ``<run>/errors.csv`` with a ``measurement`` column (one file for the run).
    """
    source, files = _measurement_source(dataset, run)
    measurements, error_files, lines = _read_measurement_files(source, files)
    if len(measurements) < min_measurements:
        raise DataError(
            f"{source}: {len(measurements)} measurement(s), expected at least {min_measurements}"
        )
    ordered = dict(
        sorted(measurements.items(), key=lambda kv: (kv[1]["time"].iloc[0], natural_key(kv[0])))
    )
    return ordered, error_files, lines


def read_first_measurement(dataset: Dataset, run: str) -> pd.DataFrame:
    """One measurement of the run (its first file), validated: enough to know the targets."""
    source, files = _measurement_source(dataset, run)
    if not files:
        raise DataError(
            f"{source}: no measurement files (expected one CSV per interferometer measurement)"
        )
    return next(iter(_read_measurement_files(source, files[:1])[0].values()))


def read_run(dataset: Dataset, run: str, min_measurements: int = 1) -> RawRun:
    """Every log of one run: temperatures, operating signals and measurements."""
    temp_dir = dataset.root / run / "temperatures"
    if not temp_dir.is_dir():
        raise DataError(f"{temp_dir}: folder not found (expected one CSV per temperature source)")
    safety.check_inside(dataset.root / run, dataset.root, what="run folder")
    sources = _read_logs(temp_dir, dataset, "sensor")
    signals = (
        _read_logs(dataset.root / run / "signals", dataset, "signal") if dataset.signals else {}
    )
    measurements, error_files, lines = read_measurements_of(dataset, run, min_measurements)
    return RawRun(run, sources, measurements, signals, error_files=error_files, error_lines=lines)
