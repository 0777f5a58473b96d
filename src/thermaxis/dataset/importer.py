"""Wide logger tables (CSV or XLSX, one row per sample) into the raw-data layout.

``thermaxis import MAPPING.yaml --out data/raw/<name>`` (:mod:`thermaxis.cli`) reads the table the
mapping names, splits it into runs (by an operating signal's rest-to-active steps, by
explicit time ranges, or one file per run), subsamples the error columns into
measurements every ``errors.every_s`` seconds, and writes ``dataset.yaml``,
``runs.tsv`` and one folder per run; with ``errors.channels``, one such dataset per
displacement channel of the same table.  Every assumption the import makes (an invented
clock, re-referencing, subsampling, how runs were cut) is appended to the generated
``dataset.yaml`` description, so it travels with the data.

Time is a column of elapsed time in ``time.unit`` (s, min or h), a column of clock
times (``time.format``: ``ISO8601`` or a strftime format; a date and a time of day in
columns of their own are ``time.columns``), or one row every ``time.interval_s``. A CSV
is read with the mapping's ``csv`` delimiter, decimal mark and encoding. After the import
each run is summarised (duration, samples, measurements) and a run too short or too long
for a thermal test, or with fewer measurements than the workflow needs, is warned about
with the likely unit mistake.

The output is validated by :func:`thermaxis.dataset.reader.load_dataset` before it is moved into
place; nothing half-written is left behind.
"""

from __future__ import annotations

import codecs
import copy
import datetime
import functools
import re
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import jsonschema
import numpy as np
import pandas as pd
import yaml

from thermaxis.config import fill_defaults
from thermaxis.dataset.reader import clock_back_hint, load_dataset, median_step_s
from thermaxis.errors import DataError, schema_message, shown
from thermaxis.schemas import load_schema

__all__ = [
    "TIME_UNITS_S",
    "ERROR_UNITS_UM",
    "RunSummary",
    "Imported",
    "ImportReport",
    "load_mapping",
    "read_table",
    "table_layout",
    "read_numeric",
    "read_seconds",
    "time_columns",
    "read_start",
    "split_runs",
    "measurements_of",
    "run_warnings",
    "summary_lines",
    "import_dataset",
]

TIME_UNITS_S = {"s": 1.0, "min": 60.0, "h": 3600.0}
# A temperature unit (temperature_unit) as degrees C = (value - offset) x scale; a rise
# takes the scale alone.
TEMPERATURE_UNITS = {"degC": (0.0, 1.0), "K": (273.15, 1.0), "degF": (32.0, 5.0 / 9.0)}
# The error columns' unit (errors.unit) in um, the raw layout's.
ERROR_UNITS_UM = {"um": 1.0, "mm": 1000.0, "nm": 0.001}
_UNIT_WORDS = {"s": "seconds", "min": "minutes", "h": "hours"}
# A thermal test heats the axis for half an hour at least and no bench run lasts a week;
# outside these a run's length is almost always a time column read in the wrong unit.
PLAUSIBLE_RUN_S = (30 * 60.0, 7 * 86400.0)
# check_dataset_shape's floor: the intercept b and every model need two measurements in a run.
MIN_MEASUREMENTS = 2
Progress = Callable[[int, int, str], None]


@dataclass(frozen=True)
class RunSummary:
    """What one imported run holds: its length on the record's clock, rows and measurements."""

    run: str
    duration_s: float
    samples: int
    measurements: int


@dataclass(frozen=True)
class Imported:
    """One dataset the import wrote (one per error channel)."""

    name: str
    folder: Path
    runs: tuple[RunSummary, ...]


@dataclass(frozen=True)
class ImportReport:
    """The import's result: the folder replaced, the datasets in it and the warnings about its runs."""

    out: Path
    datasets: tuple[Imported, ...]
    warnings: tuple[str, ...]


def load_mapping(path) -> dict:
    """Safe-load and validate a mapping; defaults from its schema are filled in."""
    path = Path(path)
    try:
        with open(path, encoding="utf-8") as fh:
            mapping = yaml.safe_load(fh)
    except (OSError, yaml.YAMLError) as exc:
        raise DataError(f"{path}: cannot read the mapping ({str(exc).splitlines()[0]})") from None
    if not isinstance(mapping, dict):
        raise DataError(f"{path}: expected a mapping at top level")
    schema = load_schema("import_mapping")
    errors = sorted(
        jsonschema.Draft202012Validator(schema).iter_errors(mapping),
        key=lambda e: list(e.absolute_path),
    )
    if errors:
        where = "/".join(map(str, errors[0].absolute_path)) or "top level"
        raise DataError(f"{path}: {where}: {schema_message(errors[0])}")
    fill_defaults(mapping, schema)
    mapping["time"].setdefault("column", None)
    try:
        codecs.lookup(mapping["csv"]["encoding"])
    except LookupError:
        raise DataError(
            f"{path}: csv/encoding: unknown encoding {mapping['csv']['encoding']!r} "
            "(expected a Python codec name, e.g. utf-8 or cp1252)"
        ) from None
    _check_ids(path, mapping)
    _check_columns(path, mapping)
    _check_ranges(path, mapping)
    _check_start_and_licence(path, mapping)
    return mapping


def _check_columns(path: Path, mapping: dict) -> None:
    """One id per table column: a column mapped twice would be one sensor under two names
    (two perfectly collinear inputs) or a temperature read as an error."""
    seen: dict[str, str] = {}
    named = [(s["column"], s["id"]) for s in (*mapping["sensors"], *mapping["signals"])]
    named += [
        (
            c["column"],
            f"an error column of channel {channel['id']}" if channel["id"] else "an error column",
        )
        for channel in _channels(mapping)
        for c in channel["columns"]
    ]
    for column, what in named:
        key = header_name(column)
        if key in seen:
            raise DataError(
                f"{path}: column {key!r} is mapped twice ({seen[key]} and {what}); expected "
                "each column of the table under one id"
            )
        seen[key] = what


def _check_ranges(path: Path, mapping: dict) -> None:
    """Runs cut by time ranges hold distinct samples: a sample in two runs would sit in a
    training run and in the run held out from it."""
    if mapping["split"]["by"] != "ranges":
        return
    for run in mapping["runs"]:
        if not run["start_s"] < run["end_s"]:
            raise DataError(
                f"{path}: run {run['name']!r}: start_s {run['start_s']:g} is not before end_s "
                f"{run['end_s']:g}; expected [start_s, end_s) in seconds since the record's start"
            )
    ordered = sorted(mapping["runs"], key=lambda r: (r["start_s"], r["end_s"]))
    for earlier, later in zip(ordered, ordered[1:], strict=False):
        if later["start_s"] < earlier["end_s"]:
            raise DataError(
                f"{path}: run {later['name']!r} [{later['start_s']:g}, {later['end_s']:g}) s "
                f"overlaps run {earlier['name']!r} [{earlier['start_s']:g}, {earlier['end_s']:g}) s; "
                "expected ranges that do not overlap (a sample belongs to one run)"
            )


def _check_start_and_licence(path: Path, mapping: dict) -> None:
    start = mapping["time"].get("start")
    if start is not None:
        try:
            parsed = pd.Timestamp(start)
        except (ValueError, TypeError):
            parsed = pd.NaT
        if pd.isna(parsed):  # pandas reads "" and "NaT" as no time at all
            raise DataError(f"{path}: time/start: expected an ISO 8601 time, got {shown(start)}")
    licence = mapping.get("licence_file")
    if licence and not (path.parent / licence).is_file():
        raise DataError(
            f"{path}: licence_file: {path.parent / licence} not found; expected the source's "
            "licence text (it travels with the data)"
        )


def _check_ids(path: Path, mapping: dict) -> None:
    ids = [s["id"] for s in mapping["sensors"]] + [s["id"] for s in mapping["signals"]]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise DataError(f"{path}: sensors/signals: id {dup[0]!r} given more than once")
    channels = [c["id"] for c in mapping["errors"].get("channels", [])]
    dup = sorted({c for c in channels if channels.count(c) > 1})
    if dup:
        raise DataError(
            f"{path}: errors/channels: id {dup[0]!r} given more than once (each channel is a dataset of its own)"
        )
    names = [r["name"] for r in mapping["runs"]]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise DataError(f"{path}: runs: run {dup[0]!r} given more than once")
    by = mapping["split"]["by"]
    if by == "signal" and mapping["split"].get("signal") not in {
        s["id"] for s in mapping["signals"]
    }:
        raise DataError(
            f"{path}: split/signal: expected the id of one of the mapping's signals, got {mapping['split'].get('signal')!r}"
        )
    needed = {"ranges": ("start_s", "end_s"), "files": ("file",)}.get(by, ())
    for i, run in enumerate(mapping["runs"]):
        for key in needed:
            if key not in run:
                raise DataError(
                    f"{path}: runs/{i}: split by {by} needs {key!r} for run {run['name']!r}"
                )
    if mapping.get("ambient_sensor") and mapping["ambient_sensor"] not in {
        s["id"] for s in mapping["sensors"]
    }:
        raise DataError(
            f"{path}: ambient_sensor: {mapping['ambient_sensor']!r} is not one of the mapping's sensor ids"
        )


@functools.cache
def _plain_csv() -> dict:
    """The ``csv`` section of a mapping that gives none: the schema's defaults."""
    section: dict = {}
    fill_defaults(section, load_schema("import_mapping")["properties"]["csv"])
    return section


# A cell such as 20,15 or -0,5: a number written with a decimal comma.
_DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d+$")


def read_table(
    path, sheet=0, csv: dict | None = None, header_row: int = 1, units_rows: int = 0
) -> pd.DataFrame:
    """A wide table, one row per sample; column names as :func:`header_name` compares them.

    ``csv`` (the mapping's section: delimiter, decimal, encoding) says how a CSV is
    written; an XLSX workbook carries its own. ``header_row`` (1 = the first row) names
    the columns; the rows above it and the ``units_rows`` below it are skipped. The
    frame's ``attrs["first_row"]`` is the file's row of its first sample, for messages.
    """
    path = Path(path)
    # Read under an import mapping, a message may name the mapping's setting that fixes it.
    mapped = csv is not None
    csv = {**_plain_csv(), **(csv or {})}
    if not path.is_file():
        raise DataError(f"{path}: file not found (the mapping's source)")
    suffix = path.suffix.lower()
    # 0-based rows to skip: above the header, and between it and the first sample.
    skip = [*range(header_row - 1), *range(header_row, header_row + units_rows)]
    try:
        if suffix in (".xlsx", ".xlsm"):
            frame = pd.read_excel(path, sheet_name=sheet, skiprows=skip)
        elif suffix in (".csv", ".txt"):
            # utf-8-sig reads UTF-8 with or without the byte-order mark Excel writes.
            encoding = (
                "utf-8-sig" if codecs.lookup(csv["encoding"]).name == "utf-8" else csv["encoding"]
            )
            frame = pd.read_csv(
                path,
                sep=csv["delimiter"],
                decimal=csv["decimal"],
                encoding=encoding,
                skiprows=skip,
            )
        else:
            raise DataError(f"{path}: expected a .csv or .xlsx table, got {suffix or 'no suffix'}")
    except UnicodeDecodeError as exc:
        fix = (
            "; set csv.encoding in the mapping (cp1252 for a Windows export in Western Europe)"
            if mapped
            else ""
        )
        raise DataError(
            f"{path}: not {csv['encoding']} text (byte 0x{exc.object[exc.start]:02x} at offset "
            f"{exc.start}){fix}"
        ) from None
    except pd.errors.EmptyDataError:
        raise DataError(f"{path}: empty file, expected a header and data rows") from None
    except (ValueError, KeyError) as exc:
        first = str(exc).splitlines()[0]
        # The parser's "Expected 2 fields in line 12, saw 9": a logger's own lines above
        # the header set a narrower table than the samples.
        above = (
            "; lines above the header? set header_row"
            if mapped and "fields in line" in first
            else ""
        )
        raise DataError(f"{path}: cannot read the table ({first}){above}") from None
    if len(frame.columns) == 1:  # before names are normalised: a tab is white space
        only = str(frame.columns[0])
        other = next((d for d in (";", "\t", ",", "|") if d in only), None)
        if other and other != csv["delimiter"]:
            fix = (
                f"set csv.delimiter: {other!r} in the mapping"
                if mapped
                else f"expected {csv['delimiter']!r} between columns"
            )
            raise DataError(f"{path}: one column {only[:60]!r}: looks {other!r}-separated; {fix}")
    frame.columns = [header_name(c) for c in frame.columns]
    _check_unique_header(path, frame, header_row)
    frame.attrs.update(first_row=header_row + units_rows + 1, mapped=mapped, decimal=csv["decimal"])
    # A spreadsheet's export often ends in rows of empty cells (",,,"): no samples.
    filled = np.flatnonzero(frame.notna().any(axis=1).to_numpy())
    frame = frame.iloc[: filled[-1] + 1] if filled.size else frame.iloc[:0]
    if frame.empty:
        raise DataError(f"{path}: no data rows below the header")
    return frame


def header_name(name) -> str:
    """A column name as compared: white space around it and runs of it inside (a line
    break in a spreadsheet's header cell) read as one space."""
    return " ".join(str(name).split())


def _column(path: Path, frame: pd.DataFrame, name: str) -> pd.Series:
    """The table's column a mapping names, compared by :func:`header_name`."""
    key = header_name(name)
    if key not in frame.columns:
        raise DataError(
            f"{path}: missing column {key!r} (named in the mapping); the table has {', '.join(frame.columns)}"
        )
    return frame[key]


def _check_unique_header(path: Path, frame: pd.DataFrame, header_row: int) -> None:
    """Two columns of one name are refused: pandas would call the second 'T1.1', and a
    mapping naming 'T1' would take the first without a word."""
    names = list(frame.columns)
    for i, name in enumerate(names):
        base, dot, number = name.rpartition(".")
        if dot and number.isdigit() and base in names[:i]:
            raise DataError(
                f"{path}: row {header_row}: column {base!r} is named more than once "
                f"(columns {names.index(base) + 1} and {i + 1}); rename one so that the mapping "
                "can tell them apart"
            )


def read_numeric(path: Path, frame: pd.DataFrame, column: str, allow_empty: bool) -> np.ndarray:
    """Column ``column`` of ``frame`` (read from ``path``) as floats, with the decimal mark
    :func:`read_table` read the table with.

    A cell that is not a finite number raises one line naming the file, the row and the
    column; with ``allow_empty`` an empty cell is a missing reading (NaN) instead.
    """
    decimal = frame.attrs.get("decimal", ".")
    read = cells = _column(path, frame, column)
    column = read.name
    if decimal != "." and not pd.api.types.is_numeric_dtype(cells):
        # pandas leaves a column as text when one cell is not a number: read the others
        # with their decimal mark, so the message names the cell that is not.
        cells = cells.map(lambda v: v.replace(decimal, ".") if isinstance(v, str) else v)
    values = pd.to_numeric(cells, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values) & (read.notna().to_numpy() if allow_empty else True)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        cell = read.iloc[i]
        hint = (
            "; a decimal comma? set csv.decimal: ',' in the mapping"
            if frame.attrs.get("mapped")
            and decimal == "."
            and _DECIMAL_COMMA.match(str(cell).strip())
            else ""
        )
        hint = _units_hint(frame, i, cell) or hint
        raise DataError(
            f"{path}: row {_row(frame, i)}, column {column!r}: expected a finite number, got "
            f"{'an empty cell' if pd.isna(cell) else shown(cell)}{hint}"
        )
    return values


def _units_hint(frame: pd.DataFrame, i: int, cell) -> str:
    """A first sample that is a word (no digit, not inf or nan) is most often a unit."""
    word = str(cell).strip() if isinstance(cell, str) else ""
    if frame.attrs.get("mapped") and i == 0 and word and not any(ch.isdigit() for ch in word):
        if word.lower().lstrip("+-") not in {"inf", "infinity", "nan"}:
            return "; a units row below the header? set units_rows: 1"
    return ""


def _row(frame: pd.DataFrame, i: int) -> int:
    """The file's row (1 = the first) of the frame's i-th sample."""
    return frame.attrs.get("first_row", 2) + i


def time_columns(time: dict) -> list[str]:
    """The columns the mapping's ``time`` section reads the time from (none: ``interval_s``)."""
    if time.get("columns"):
        return list(time["columns"])
    return [time["column"]] if time.get("column") else []


def _words(columns: list[str]) -> str:
    """Columns as messages name them: column 'time', or columns 'Datum' + 'Uhrzeit'."""
    if len(columns) == 1:
        return f"column {columns[0]!r}"
    return "columns " + " + ".join(repr(c) for c in columns)


def _typed_clock(column: pd.Series) -> bool:
    """Whether a column holds a workbook's typed dates, times or timestamps, not text."""
    if pd.api.types.is_datetime64_any_dtype(column):
        return True
    return bool(column.map(lambda v: isinstance(v, (datetime.date, datetime.time))).all())


def _clock(path: Path, frame: pd.DataFrame, time: dict) -> pd.DatetimeIndex:
    """The clock-time column(s), parsed with the mapping's format; a zone is converted to UTC.

    Several columns (a date and a time) are joined with a space, as ``format`` expects.
    A workbook's own date and time cells (typed, whatever their display format) are
    read as they are, so ``format`` then describes text cells only.
    """
    read = [_column(path, frame, column) for column in time_columns(time)]
    columns, fmt = [r.name for r in read], time["format"]
    if all(_typed_clock(r) for r in read):
        fmt = "ISO8601"  # pandas renders typed dates and times as ISO 8601 text
    text = pd.concat(read, axis=1).astype(str).apply(lambda col: col.str.strip())
    text = text.agg(" ".join, axis=1)
    # utc=True: naive times stay as they are, zoned ones (even mixed offsets) become UTC.
    parsed = pd.to_datetime(text, format=fmt, errors="coerce", utc=True)
    if parsed.isna().any():
        i = int(np.flatnonzero(parsed.isna().to_numpy())[0])
        expected = "an ISO 8601 clock time" if fmt == "ISO8601" else f"a clock time in {fmt!r}"
        raise DataError(
            f"{path}: row {_row(frame, i)}, {_words(columns)}: expected {expected}, got "
            f"{shown(text.iloc[i])}{_units_hint(frame, i, text.iloc[i])}"
        )
    return pd.DatetimeIndex(parsed).tz_localize(None)


def _increasing(path: Path, frame: pd.DataFrame, columns: list[str], t: np.ndarray) -> np.ndarray:
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        hint = (
            "; a clock coarser than the logging (a date without its time of day, or whole "
            "seconds logged faster than once a second)?"
            if t[i] == t[i - 1]
            else clock_back_hint(t[i - 1] - t[i], median_step_s(t))
        )
        raise DataError(
            f"{path}: row {_row(frame, i)}, {_words(columns)}: time does not increase "
            f"({t[i]:g} after {t[i - 1]:g} s){hint}"
        )
    return t


def read_seconds(path: Path, frame: pd.DataFrame, time: dict) -> np.ndarray:
    """Each row's time in seconds after :func:`read_start` (the mapping's ``time`` section).

    An elapsed-time column is scaled from its ``unit``; a clock-time column counts from its
    first row; without a column row i is at i x ``interval_s``. Time must increase.
    """
    if not time_columns(time):
        return np.arange(len(frame), dtype=float) * float(time["interval_s"])
    if time.get("format"):
        clock = _clock(path, frame, time)
        t = (clock - clock[0]).total_seconds().to_numpy(dtype=float)
    else:
        t = (
            read_numeric(path, frame, time["column"], allow_empty=False)
            * TIME_UNITS_S[time["unit"]]
        )
    return _increasing(path, frame, time_columns(time), t)


def read_start(path: Path, frame: pd.DataFrame, time: dict) -> pd.Timestamp:
    """The clock time at 0 s of :func:`read_seconds`: a clock column's first row, else ``time.start``."""
    if time.get("format"):
        return _clock(path, frame, time)[0]
    return pd.Timestamp(time["start"])


def _tidy(path: Path, frame: pd.DataFrame, mapping: dict) -> pd.DataFrame:
    """Seconds since the table's clock start, then every mapped column under its new id."""
    out = {"_t": read_seconds(path, frame, mapping["time"])}
    for item in (*mapping["sensors"], *mapping["signals"]):
        out[item["id"]] = read_numeric(path, frame, item["column"], allow_empty=True)
    for c, channel in enumerate(_channels(mapping)):
        for j, item in enumerate(channel["columns"]):
            out[_error_key(c, j)] = read_numeric(path, frame, item["column"], allow_empty=True)
    return pd.DataFrame(out)


def _error_key(channel: int, column: int) -> str:
    return f"_e{channel}.{column}"


def _channels(mapping: dict) -> list[dict]:
    """The error channels: ``errors.channels``, or ``errors.columns`` as the one unnamed channel."""
    errors = mapping["errors"]
    return errors.get("channels") or [{"id": None, "columns": errors["columns"]}]


def split_runs(rows: pd.DataFrame, mapping: dict, where: str = "mapping") -> list[pd.DataFrame]:
    """Cut one record into runs, in time order.

    ``by: signal``: a run starts where the signal leaves its rest value after being at
    rest (the first run starts with the record, so it keeps the standstill before the
    first step); ``by: ranges``: each run's ``[start_s, end_s)``.
    """
    split = mapping["split"]
    if split["by"] == "signal":
        # NaN (a missing reading) is never within the tolerance: it counts as active, as before.
        offset = np.abs(rows[split["signal"]].to_numpy(dtype=float) - float(split["rest"]))
        active = ~(offset <= float(split["tolerance"]))
        starts = np.flatnonzero(active[1:] & ~active[:-1]) + 1
        if not active[0] and starts.size and starts[0] > 0:
            starts = starts[1:]  # the standstill before the first step belongs to the first run
        bounds = [0, *starts.tolist(), len(rows)]
        pieces = [rows.iloc[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=False)]
    else:
        pieces = [
            rows[(rows["_t"] >= r["start_s"]) & (rows["_t"] < r["end_s"])] for r in mapping["runs"]
        ]
        for run, piece in zip(mapping["runs"], pieces, strict=False):
            if piece.empty:
                raise DataError(
                    f"{where}: run {run['name']!r}: no sample in [{run['start_s']:g}, {run['end_s']:g}) s"
                )
    if len(pieces) != len(mapping["runs"]):
        noisy = (
            f"; a signal that is not exactly {split['rest']:g} at rest? set split.tolerance"
            # More steps than runs, or no reading at rest at all: the rest value is rarely exact.
            if split["by"] == "signal" and (len(pieces) > len(mapping["runs"]) or active.all())
            else ""
        )
        raise DataError(
            f"{where}: split by signal {split['signal']!r} found {len(pieces)} run(s) but the mapping lists "
            f"{len(mapping['runs'])}; expected one entry in runs per rest-to-active step{noisy}"
        )
    return [p.reset_index(drop=True) for p in pieces]


def measurements_of(run_rows: pd.DataFrame, every_s: float) -> pd.DataFrame:
    """The samples taken as measurements: the first at or after each multiple of ``every_s`` since the run's start."""
    t = run_rows["_t"].to_numpy(dtype=float) - float(run_rows["_t"].iloc[0])
    marks = np.arange(0.0, t[-1] + 1e-9, float(every_s))
    picked = np.unique(np.searchsorted(t, marks - 1e-9, side="left"))
    return run_rows.iloc[picked[picked < len(t)]].reset_index(drop=True)


def _iso(start: pd.Timestamp, seconds) -> list[str]:
    times = start + pd.to_timedelta(np.asarray(seconds, dtype=float), unit="s")
    return [t.isoformat() for t in times]


def _celsius(values: pd.Series, mapping: dict) -> pd.Series:
    """Logged temperatures in degrees C (rises: by the unit's scale alone)."""
    offset, scale = TEMPERATURE_UNITS[mapping["temperature_unit"]]
    if mapping["temperature_unit"] == "degC":
        return values  # as logged, digit for digit
    if mapping["temperature_kind"] == "rise":
        offset = 0.0
    return (values - offset) * scale


def _write_run(
    folder: Path, rows: pd.DataFrame, mapping: dict, start: pd.Timestamp, channel: int
) -> RunSummary:
    """A run's temperatures, signals and the measurements of error channel ``channel``."""
    times = _iso(start, rows["_t"])
    source = mapping["source_name"]
    (folder / "temperatures").mkdir(parents=True)
    temps = pd.DataFrame(
        {"time": times, **{s["id"]: _celsius(rows[s["id"]], mapping) for s in mapping["sensors"]}}
    )
    temps.to_csv(
        folder / "temperatures" / f"{source}.csv",
        index=False,
        float_format="%.6g",
        lineterminator="\n",
    )
    if mapping["signals"]:
        (folder / "signals").mkdir()
        signals = pd.DataFrame(
            {"time": times, **{s["id"]: rows[s["id"]] for s in mapping["signals"]}}
        )
        signals.to_csv(
            folder / "signals" / f"{source}.csv",
            index=False,
            float_format="%.6g",
            lineterminator="\n",
        )
    picked = measurements_of(rows, mapping["errors"]["every_s"])
    columns = mapping["errors"]["columns"]
    keys = [_error_key(channel, j) for j in range(len(columns))]
    reference = rows[keys].iloc[0].to_numpy(dtype=float)
    if mapping["errors"]["rereference"] == "run_start" and not np.isfinite(reference).all():
        raise DataError(
            f"{folder.name}: the run's first error reading is missing; cannot re-reference to it"
        )
    scale = ERROR_UNITS_UM[mapping["errors"]["unit"]]
    records = []
    for i, (_, sample) in enumerate(picked.iterrows(), start=1):
        for j, item in enumerate(columns):
            value = float(sample[keys[j]])
            if mapping["errors"]["rereference"] == "run_start":
                value -= reference[j]
            value *= scale
            if np.isfinite(value):
                records.append(
                    (f"M{i:03d}", _iso(start, [sample["_t"]])[0], item["position_mm"], value)
                )
    if not records:
        raise DataError(
            f"{mapping['source']}: run {folder.name!r}: column(s) "
            f"{', '.join(repr(c['column']) for c in columns)} have no reading at any of the run's "
            f"{len(picked)} measurement(s) (one every {mapping['errors']['every_s']:g} s); "
            "expected error readings"
        )
    errors = pd.DataFrame(records, columns=["measurement", "time", "position_mm", "error_um"])
    errors.to_csv(folder / "errors.csv", index=False, float_format="%.6g", lineterminator="\n")
    t = rows["_t"].to_numpy(dtype=float)
    return RunSummary(folder.name, float(t[-1] - t[0]), len(rows), len(picked))


def _assumptions(mapping: dict, counts: dict[str, int]) -> list[str]:
    """What the import assumed, in sentences for the dataset's description."""
    time = mapping["time"]
    notes = []
    if time.get("format"):
        notes.append(
            f"Times are the logged clock times of {_words(time_columns(time))} (format {time['format']}); "
            "a time zone, where given, was converted to UTC."
        )
    elif time["column"]:
        notes.append(
            f"Times are {_UNIT_WORDS[time['unit']]} since the record's start (column {time['column']!r}); "
            f"the clock time {time['start']} given to the first row is invented by the import, not measured."
        )
    else:
        notes.append(
            f"The source has no time column: row i is taken at i x {time['interval_s']:g} s after {time['start']}, "
            "an invented clock."
        )
    if mapping["temperature_unit"] != "degC":
        notes.append(
            f"Temperatures were logged in {mapping['temperature_unit']} and converted to degrees C."
        )
    unit = mapping["errors"]["unit"]
    if unit != "um":
        notes.append(
            f"The error columns were logged in {unit} and converted to um "
            f"(x {ERROR_UNITS_UM[unit]:g})."
        )
    if mapping["csv"] != _plain_csv():
        csv = mapping["csv"]
        notes.append(
            f"A CSV source was read with {csv['delimiter']!r} between columns, a decimal "
            f"{'comma' if csv['decimal'] == ',' else 'point'} and the {csv['encoding']} encoding, "
            "as the mapping states."
        )
    split = mapping["split"]
    if split["by"] == "signal":
        notes.append(
            f"The record was cut into {len(counts)} runs where signal {split['signal']!r} leaves its rest value "
            f"{split['rest']:g} (the first run keeps the record's start)."
        )
    elif split["by"] == "ranges":
        notes.append(
            "The record was cut into runs at the time ranges listed in the import mapping."
        )
    else:
        notes.append("Each run comes from its own file.")
    every = mapping["errors"]["every_s"]
    notes.append(
        f"Measurements are the error samples at (or just after) every {every:g} s of each run "
        f"({', '.join(f'{r}: {n}' for r, n in counts.items())} measurements)."
    )
    if mapping["errors"]["rereference"] == "run_start":
        notes.append(
            "The source zeroed the error once for the whole record; each run was re-referenced to its own first "
            "sample, so every run starts at 0 um, as an interferometer zeroed before each run would."
        )
    positions = [c["position_mm"] for c in mapping["errors"]["columns"]]
    if len(positions) == 1:
        notes.append(
            f"The record has one measuring point; it is stored as target position {positions[0]:g} mm."
        )
    return notes


def _dataset_yaml(mapping: dict, notes: list[str]) -> dict:
    description = (
        mapping["description"].strip()
        + "\n\nAssumptions made by the import (thermaxis.dataset.importer):\n"
        + "\n".join(f"- {n}" for n in notes)
    )
    meta = {"name": mapping["name"]}
    if mapping.get("title"):
        meta["title"] = mapping["title"]
    if mapping.get("reproduces"):
        meta["reproduces"] = mapping["reproduces"]
    if mapping.get("ambient_sensor"):
        meta["ambient_sensor"] = mapping["ambient_sensor"]
    meta["temperature_kind"] = mapping["temperature_kind"]
    meta["description"] = description
    meta["provenance"] = dict(mapping["provenance"])
    meta["axis"] = dict(mapping["axis"])
    source = mapping["source_name"]
    meta["sensors"] = [
        {"id": s["id"], "location": s["location"], "source": source, "column": s["column"]}
        for s in mapping["sensors"]
    ]
    if mapping["signals"]:
        meta["signals"] = [
            {"id": s["id"], "unit": s["unit"], "source": source, "column": s["column"]}
            for s in mapping["signals"]
        ]
    meta["sources"] = [
        {"name": source, "clock_note": "one logger; times from the import (see description)"}
    ]
    return meta


def _runs_tsv(mapping: dict) -> str:
    descriptor_names = sorted({k for r in mapping["runs"] for k in r.get("descriptors", {})})
    lines = ["\t".join(["run", "condition", *descriptor_names, "description"])]
    for run in mapping["runs"]:
        values = [
            format(run["descriptors"][k], "g") if k in run.get("descriptors", {}) else ""
            for k in descriptor_names
        ]
        text = [run["name"], run["condition"], *values, run["description"]]
        if any("\t" in v or "\n" in v for v in text):
            raise DataError(
                f"run {run['name']!r}: names, conditions and descriptions must not hold tabs or newlines"
            )
        lines.append("\t".join(text))
    return "\n".join(lines) + "\n"


def table_layout(mapping: dict) -> tuple:
    """:func:`read_table`'s arguments after the path, from the mapping."""
    return mapping["sheet"], mapping["csv"], mapping["header_row"], mapping["units_rows"]


def _runs_rows(mapping_path: Path, mapping: dict, progress: Progress) -> list[tuple]:
    """Each run's tidy rows with the clock time of their 0 s, in the mapping's order."""
    source = (mapping_path.parent / mapping["source"]).resolve()
    if mapping["split"]["by"] == "files":
        pieces = []
        for i, run in enumerate(mapping["runs"]):
            table_path = source / run["file"]
            progress(i, len(mapping["runs"]), f"reading {run['file']}")
            frame = read_table(table_path, *table_layout(mapping))
            pieces.append(
                (_tidy(table_path, frame, mapping), read_start(table_path, frame, mapping["time"]))
            )
        progress(len(mapping["runs"]), len(mapping["runs"]), "tables read")
        return pieces
    progress(0, 1, f"reading {source.name}")
    frame = read_table(source, *table_layout(mapping))
    start = read_start(source, frame, mapping["time"])
    runs = split_runs(_tidy(source, frame, mapping), mapping, str(mapping_path))
    progress(1, 1, "table read")
    # Each run keeps its place on the record's clock, so runs follow each other in time.
    return [(rows, start) for rows in runs]


def _channel_mapping(mapping: dict, channel: dict) -> dict:
    """The mapping of one channel's dataset: its own name, error columns and direction."""
    if channel["id"] is None:
        return mapping
    out = copy.deepcopy(mapping)
    out["name"] = f"{mapping['name']}_{channel['id']}"
    out["errors"]["columns"] = channel["columns"]
    if channel.get("direction"):
        out["axis"]["direction"] = channel["direction"]
    out["description"] = (
        mapping["description"].strip()
        + f"\n\nThis dataset holds error channel {channel['id']!r} of the record"
        + (f" ({channel['direction']})." if channel.get("direction") else ".")
    )
    return out


def _write_dataset(
    folder: Path, mapping: dict, mapping_path: Path, pieces: list, channel: int, progress: Progress
) -> Imported:
    summaries = []
    for i, (run, (rows, start)) in enumerate(zip(mapping["runs"], pieces, strict=False)):
        progress(i, len(pieces), f"{mapping['name']}: writing run {run['name']}")
        summaries.append(_write_run(folder / run["name"], rows, mapping, start, channel))
    progress(len(pieces), len(pieces), f"{mapping['name']}: runs written")
    counts = {r.run: r.measurements for r in summaries}
    meta = _dataset_yaml(mapping, _assumptions(mapping, counts))
    header = f"# Written by `python -m thermaxis.dataset.importer {mapping_path.name}` -- do not edit by hand.\n"
    (folder / "dataset.yaml").write_text(
        header + yaml.safe_dump(meta, sort_keys=False, allow_unicode=True, width=100),
        encoding="utf-8",
    )
    (folder / "runs.tsv").write_text(_runs_tsv(mapping), encoding="utf-8")
    if mapping.get("licence_file"):
        shutil.copyfile(mapping_path.parent / mapping["licence_file"], folder / "LICENSE")
    return Imported(mapping["name"], folder, tuple(summaries))


def _span(seconds: float) -> str:
    """A run's length as a reader would say it."""
    for limit, unit, size in ((120, "s", 1), (7200, "min", 60), (172800, "h", 3600)):
        if abs(seconds) < limit:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds / 86400:.3g} days"


def _unit_hint(time: dict, durations: list[float]) -> str:
    """The time unit under which every flagged run would last like a thermal test, if one does."""
    if time.get("format"):
        return f"check the clock format {time['format']!r}"
    if time["column"] is None:
        return f"check time.interval_s ({time['interval_s']:g} s per row)"
    low, high = PLAUSIBLE_RUN_S
    for unit, size in TIME_UNITS_S.items():
        scaled = [d * size / TIME_UNITS_S[time["unit"]] for d in durations]
        if unit != time["unit"] and all(low <= d <= high for d in scaled):
            return (
                f"if column {time['column']!r} is in {_UNIT_WORDS[unit]}, set time.unit: {unit} "
                f"(they would last {_span(min(scaled))} to {_span(max(scaled))})"
            )
    return f"check the unit of column {time['column']!r} (time.unit: {time['unit']})"


def run_warnings(name: str, time: dict, every_s: float, runs: tuple[RunSummary, ...]) -> list[str]:
    """Warnings about runs a thermal test would not give: implausible lengths, too few measurements."""
    low, high = PLAUSIBLE_RUN_S
    out = []
    for flagged, what in (
        ([r for r in runs if r.duration_s < low], "short"),
        ([r for r in runs if r.duration_s > high], "long"),
    ):
        if flagged:
            durations = [r.duration_s for r in flagged]
            out.append(
                f"{name}: run(s) {', '.join(r.run for r in flagged)} last {_span(min(durations))} to "
                f"{_span(max(durations))}, implausibly {what} for a thermal test (expected "
                f"{_span(low)} to {_span(high)}); {_unit_hint(time, durations)}"
            )
    if len(runs) < 2:
        out.append(
            f"{name}: {len(runs)} run; leave-one-condition-out needs at least 2, so the "
            "workflow refuses such a dataset (list more runs, or split the record)"
        )
    few = [r for r in runs if r.measurements < MIN_MEASUREMENTS]
    if few:
        out.append(
            f"{name}: run(s) {', '.join(f'{r.run} ({r.measurements})' for r in few)} have fewer than "
            f"{MIN_MEASUREMENTS} measurements at errors.every_s = {every_s:g} s; the workflow refuses "
            "such a dataset"
        )
    return out


def _no_progress(done: int, total: int, what: str) -> None:
    """The default: an import called from code reports nothing."""


def import_dataset(mapping_path, out, progress: Progress = _no_progress) -> ImportReport:
    """Write the dataset(s) the mapping describes into ``out`` (replaced only when complete and valid).

    One dataset goes into ``out`` itself; with ``errors.channels`` each channel's dataset
    goes into ``out/<name>_<channel>``. ``progress(done, total, what)`` is told each step.
    """
    mapping_path = Path(mapping_path)
    mapping = load_mapping(mapping_path)
    pieces = _runs_rows(mapping_path, mapping, progress)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        written = []
        for c, channel in enumerate(_channels(mapping)):
            channel_mapping = _channel_mapping(mapping, channel)
            folder = tmp if channel["id"] is None else tmp / channel_mapping["name"]
            written.append(
                _write_dataset(folder, channel_mapping, mapping_path, pieces, c, progress)
            )
        for dataset in written:
            load_dataset(
                dataset.folder
            )  # the layout's own validation, before anything replaces `out`
        if out.exists():
            shutil.rmtree(out)
        tmp.rename(out)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)
    datasets = tuple(Imported(d.name, out / d.folder.relative_to(tmp), d.runs) for d in written)
    found = [
        w
        for d in datasets
        for w in run_warnings(d.name, mapping["time"], mapping["errors"]["every_s"], d.runs)
    ]
    return ImportReport(out, datasets, tuple(found))


def summary_lines(report: ImportReport) -> list[str]:
    """The per-run summary printed after an import: duration, samples, measurements."""
    lines = []
    for dataset in report.datasets:
        lines.append(f"{dataset.name}: {len(dataset.runs)} runs in {dataset.folder}")
        width = max(len(r.run) for r in dataset.runs)
        lines.extend(
            f"  {r.run:<{width}}  {_span(r.duration_s):>10}  {r.samples:>7} samples  "
            f"{r.measurements:>4} measurements"
            for r in dataset.runs
        )
    return lines
