"""Validating reader for the raw-data layout documented in ``data/README.md``.

Every problem is reported as a :class:`DataError` whose message is ONE line naming
the file, the row (1-based line number in the file, header = line 1) or column, and
what was expected.  The reader never repairs anything: repairs belong to
:mod:`thermaxis.cleaning`, which reports what it did.

The dataset's sheets (dataset.yaml, runs.tsv) are read here, and its runs assembled from
the files that :mod:`thermaxis.dataset.raw_files` reads one at a time.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import jsonschema
import numpy as np
import pandas as pd

from thermaxis.config import fill_defaults
from thermaxis.dataset import layout, safety
from thermaxis.dataset.raw_files import (
    _csv_rows,
    _read_run_file,
    read_measurement,
    read_temperature_source,
)
from thermaxis.errors import DataError, first_schema_error, schema_message, schema_where, shown
from thermaxis.labels import natural_key
from thermaxis.schemas import load_schema

__all__ = [
    "Dataset",
    "RawRun",
    "load_dataset",
    "read_run",
    "read_measurements_of",
    "read_first_measurement",
]

RUN_COLUMNS = ("run", "condition", "description")


def _schema_error(path: Path, error: jsonschema.ValidationError, where: str = "") -> DataError:
    prefix = f"{path}: {where}" if where else f"{path}: "
    return DataError(f"{prefix}{schema_where(error)}: {schema_message(error)}")


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
        return self.meta["temperature_kind"]

    @property
    def signals(self) -> tuple[str, ...]:
        """Operating signals (spindle speed, feed programme, ...) logged over time like temperatures."""
        return tuple(s["id"] for s in self.meta["signals"])

    def signal_units(self) -> dict[str, str]:
        return {s["id"]: s["unit"] for s in self.meta["signals"]}

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
        return tuple(s["id"] for s in self.meta["signals"] if s["source"] == source)

    @property
    def sources(self) -> tuple[str, ...]:
        return tuple(s["name"] for s in self.meta["sources"])

    def clock_offsets_s(self) -> dict[str, float]:
        return {s["name"]: float(s["clock_offset_s"]) for s in self.meta["sources"]}

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
    """Validate ``meta`` against the dataset schema, its defaults filled in first (in place)."""
    schema = load_schema("dataset")
    fill_defaults(meta, schema)
    error = first_schema_error(schema, meta)
    if error is not None:
        raise _schema_error(path, error)
    ids = [s["id"] for s in meta["sensors"]]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise DataError(f"{path}: sensors: sensor id {dup[0]!r} declared more than once")
    signals = [s["id"] for s in meta["signals"]]
    clash = sorted(set(signals) & set(ids) | {i for i in signals if signals.count(i) > 1})
    if clash:
        raise DataError(
            f"{path}: signals: id {clash[0]!r} declared more than once (sensor and signal ids share one namespace)"
        )
    sources = {s["name"] for s in meta["sources"]}
    for kind, items in (("sensors", meta["sensors"]), ("signals", meta["signals"])):
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
