"""Validating reader for the raw-data layout documented in ``data/README.md``.

Every problem is reported as a :class:`DataError` whose message is ONE line naming
the file, the row (1-based line number in the file, header = line 1) or column, and
what was expected.  The reader never repairs anything: repairs belong to
:mod:`thermaxis.clean`, which reports what it did.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Mapping

import jsonschema
import numpy as np
import pandas as pd
import yaml

from . import guard

__all__ = [
    "DataError",
    "Dataset",
    "RawRun",
    "load_dataset",
    "read_run",
    "read_temperature_source",
    "read_measurement",
    "SCHEMA_DIR",
]

SCHEMA_DIR = Path(__file__).with_name("schemas")
RUN_COLUMNS = ("run", "condition", "feed_mm_min", "description")
ERROR_COLUMNS = ("time", "position_mm", "error_um")


class DataError(ValueError):
    """A raw input that does not follow the documented layout."""


@lru_cache(maxsize=None)
def load_schema(name: str) -> dict:
    with open(SCHEMA_DIR / f"{name}.schema.yaml", encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def _schema_error(path: Path, error: jsonschema.ValidationError, where: str = "") -> DataError:
    location = "/".join(str(p) for p in error.absolute_path) or "top level"
    prefix = f"{path}: {where}" if where else f"{path}: "
    return DataError(f"{prefix}{location}: {error.message}")


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

    def sensors_of(self, source: str) -> tuple[str, ...]:
        return tuple(s["id"] for s in self.meta["sensors"] if s["source"] == source)

    @property
    def sources(self) -> tuple[str, ...]:
        return tuple(s["name"] for s in self.meta["sources"])

    def clock_offsets_s(self) -> dict[str, float]:
        return {s["name"]: float(s.get("clock_offset_s", 0.0)) for s in self.meta["sources"]}

    def condition_of(self, run: str) -> int:
        return int(self.runs.loc[self.runs["run"] == run, "condition"].iloc[0])


def _read_yaml(path: Path) -> dict:
    if not path.exists():
        raise DataError(f"{path}: file not found (every dataset needs dataset.yaml)")
    doc = guard.load_yaml(path)
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
    sources = {s["name"] for s in meta["sources"]}
    for i, sensor in enumerate(meta["sensors"]):
        if sensor["source"] not in sources:
            raise DataError(
                f"{path}: sensors/{i}: source {sensor['source']!r} of sensor {sensor['id']!r} "
                f"is not one of the declared sources {sorted(sources)}"
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


def _read_runs(path: Path) -> pd.DataFrame:
    if not path.exists():
        raise DataError(f"{path}: file not found (every dataset needs runs.tsv)")
    guard.sniff_delimited(path, "\t", guard.MAX_SHEET_BYTES)
    with open(path, encoding="utf-8-sig", newline="") as fh:
        rows = list(csv.reader(fh, delimiter="\t"))
    if not rows:
        raise DataError(f"{path}: empty file, expected a tab-separated header {' '.join(RUN_COLUMNS)}")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in RUN_COLUMNS if c not in header]
    if missing:
        raise DataError(f"{path}: missing column {missing[0]!r} (expected tab-separated columns {', '.join(RUN_COLUMNS)})")
    if len(rows) < 2:
        raise DataError(f"{path}: no runs listed (expected one row per run)")
    schema = load_schema("runs")
    validator = jsonschema.Draft202012Validator(schema)
    records = []
    for lineno, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise DataError(f"{path}: line {lineno}: expected {len(header)} tab-separated fields, got {len(row)}")
        record = {}
        for name, cell in zip(header, row):
            kind = schema["properties"].get(name, {}).get("type", "string")
            try:
                record[name] = _coerce_cell(cell.strip(), kind)
            except ValueError:
                raise DataError(
                    f"{path}: line {lineno}, column {name!r}: expected {'an integer' if kind == 'integer' else 'a finite number'}, got {cell!r}"
                ) from None
        errors = list(validator.iter_errors(record))
        if errors:
            err = errors[0]
            column = err.absolute_path[0] if err.absolute_path else ""
            raise DataError(f"{path}: line {lineno}, column {column!r}: {err.message}")
        records.append(record)
    runs = pd.DataFrame.from_records(records)
    dup = runs["run"][runs["run"].duplicated()]
    if len(dup):
        raise DataError(f"{path}: run {dup.iloc[0]!r} listed more than once")
    return runs.sort_values("run", kind="stable").reset_index(drop=True)


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
            if (child / "errors").is_dir() or (child / "temperatures").is_dir():
                raise DataError(f"{child}: run folder is not listed in {root / 'runs.tsv'}")
    sensors = tuple(s["id"] for s in meta["sensors"])
    return Dataset(root=root, meta=meta, runs=runs, sensors=sensors)


def _read_csv(path: Path) -> pd.DataFrame:
    if guard.check_regular_file(path, what="data file") == 0:
        raise DataError(f"{path}: empty file, expected a header and data rows")
    guard.sniff_delimited(path, ",")
    try:
        frame = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise DataError(f"{path}: empty file, expected a header and data rows") from None
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: byte 0x{exc.object[exc.start]:02x} is not UTF-8; expected UTF-8 text") from None
    except pd.errors.ParserError as exc:
        raise DataError(f"{path}: not a valid CSV file ({str(exc).splitlines()[0]})") from None
    frame.columns = [str(c).strip() for c in frame.columns]
    if frame.empty:
        raise DataError(f"{path}: no data rows below the header")
    return frame


def _parse_time(path: Path, values: pd.Series) -> pd.Series:
    guard.check_time_zones(path, values)
    parsed = pd.to_datetime(values, format="ISO8601", errors="coerce")
    bad = parsed.isna().to_numpy()
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DataError(f"{path}: line {i + 2}, column 'time': expected an ISO 8601 time, got {values.iloc[i]!r}")
    if getattr(parsed.dt, "tz", None) is not None:
        raise DataError(f"{path}: column 'time': expected times without a time zone (one zone per dataset)")
    guard.check_time_range(path, parsed, values)
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
        raise DataError(f"{path}: line {i + 2}, column {column!r}: expected a number, got {frame[column].iloc[i]!r}")
    return numbers


def _check_time_order(path: Path, time: pd.Series) -> None:
    back = np.flatnonzero(np.diff(time.to_numpy().astype("int64")) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise DataError(
            f"{path}: line {i + 2}, column 'time': time goes backwards ({time.iloc[i]} after {time.iloc[i - 1]})"
        )


def read_temperature_source(path, expected_sensors, known_sensors) -> pd.DataFrame:
    """One source's log: ``time`` + one float column per sensor (NaN = missing)."""
    path = Path(path)
    frame = _read_csv(path)
    if "time" not in frame.columns:
        raise DataError(f"{path}: missing column 'time' (expected time + one column per sensor)")
    sensors = [c for c in frame.columns if c != "time"]
    for column in sensors:
        if column not in known_sensors:
            raise DataError(f"{path}: column {column!r}: unknown sensor id (not declared in dataset.yaml)")
        if column not in expected_sensors:
            raise DataError(f"{path}: column {column!r}: sensor is declared for another source in dataset.yaml")
    for sensor in expected_sensors:
        if sensor not in sensors:
            raise DataError(f"{path}: missing column {sensor!r} (declared for this source in dataset.yaml)")
    out = pd.DataFrame({"time": _parse_time(path, frame["time"])})
    _check_time_order(path, out["time"])
    for sensor in expected_sensors:
        out[sensor] = _parse_numbers(path, frame, sensor, allow_empty=True)
    return out


def read_measurement(path) -> pd.DataFrame:
    """One interferometer measurement: time, position_mm, error_um, direction."""
    path = Path(path)
    frame = _read_csv(path)
    for column in ERROR_COLUMNS:
        if column not in frame.columns:
            raise DataError(f"{path}: missing column {column!r} (expected {', '.join(ERROR_COLUMNS)}[, direction])")
    out = pd.DataFrame(
        {
            "time": _parse_time(path, frame["time"]),
            "position_mm": _parse_numbers(path, frame, "position_mm", allow_empty=False),
            "error_um": _parse_numbers(path, frame, "error_um", allow_empty=False),
        }
    )
    _check_time_order(path, out["time"])
    if "direction" in frame.columns:
        direction = frame["direction"].str.strip()
        bad = ~direction.isin(["+", "-"])
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise DataError(f"{path}: line {i + 2}, column 'direction': expected '+' or '-', got {frame['direction'].iloc[i]!r}")
        out["direction"] = direction.to_numpy(dtype=object)
    else:
        out["direction"] = "+"
    _check_repeated_positions(path, out)
    return out


def _check_repeated_positions(path: Path, frame: pd.DataFrame) -> None:
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
            f"{path}: column 'position_mm': position {position:g} mm appears twice in the {direction!s} pass "
            f"with different errors {values} (expected one reading per target and pass)"
        )


@dataclass(frozen=True)
class RawRun:
    run: str
    sources: Mapping[str, pd.DataFrame]
    measurements: Mapping[str, pd.DataFrame]  # ordered by first reading's time

    def windows(self) -> pd.DataFrame:
        """Measurement number, name and time window (first to last reading)."""
        rows = [
            (i, name, m["time"].iloc[0], m["time"].iloc[-1])
            for i, (name, m) in enumerate(self.measurements.items(), start=1)
        ]
        return pd.DataFrame(rows, columns=["measurement", "name", "start", "end"])


def read_run(dataset: Dataset, run: str, min_measurements: int = 1) -> RawRun:
    folder = dataset.root / run
    temp_dir = folder / "temperatures"
    if not temp_dir.is_dir():
        raise DataError(f"{temp_dir}: folder not found (expected one CSV per temperature source)")
    guard.check_inside(folder, dataset.root, what="run folder")
    known = set(dataset.sensors)
    sources = {}
    for source in dataset.sources:
        expected = dataset.sensors_of(source)
        if not expected:
            continue
        path = guard.check_inside(temp_dir / f"{source}.csv", dataset.root, what="temperature file")
        sources[source] = read_temperature_source(path, expected, known)
    for extra in sorted(temp_dir.glob("*.csv")):
        if extra.stem not in dataset.sources:
            raise DataError(f"{extra}: unknown temperature source {extra.stem!r} (not declared in dataset.yaml)")
    err_dir = folder / "errors"
    if not err_dir.is_dir():
        raise DataError(f"{err_dir}: folder not found (expected one CSV per interferometer measurement)")
    files = sorted(err_dir.glob("*.csv"))
    if len(files) < min_measurements:
        raise DataError(f"{err_dir}: {len(files)} measurement file(s), expected at least {min_measurements}")
    for f in files:
        guard.check_name(f.stem, "measurement", f)
        guard.check_inside(f, dataset.root, what="measurement file")
    measurements = {f.stem: read_measurement(f) for f in files}
    ordered = dict(sorted(measurements.items(), key=lambda kv: (kv[1]["time"].iloc[0], kv[0])))
    return RawRun(run=run, sources=sources, measurements=ordered)
