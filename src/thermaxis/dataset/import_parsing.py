"""Reading a wide logger table and cutting it into runs.

A CSV or XLSX table (the mapping's dialect, header row and units rows), its numeric
columns, its time (elapsed time in a unit, clock times in one column or a date and a
time, or one row every ``interval_s``), then the record cut into runs (by an operating
signal, by time ranges, or one file per run) and each run's measurements picked. Every
refusal is one line naming the file, the row and the column.
"""

from __future__ import annotations

import codecs
import datetime
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
from python_calamine import CalamineError

from thermaxis.dataset.import_mapping import (
    _channels,
    _error_key,
    _plain_csv,
    header_name,
    table_layout,
)
from thermaxis.dataset.raw_files import clock_back_hint, median_step_s
from thermaxis.errors import DataError, shown

__all__ = [
    "TIME_UNITS_S",
    "Progress",
    "read_wide_table",
    "read_numeric",
    "read_seconds",
    "time_columns",
    "read_start",
    "split_runs",
    "measurements_of",
]

TIME_UNITS_S = {"s": 1.0, "min": 60.0, "h": 3600.0}
_UNIT_WORDS = {"s": "seconds", "min": "minutes", "h": "hours"}
Progress = Callable[[int, int, str], None]

# A cell such as 20,15 or -0,5: a number written with a decimal comma.
_DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d+$")


def read_wide_table(
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
    # 0-based rows to skip: above the header, and between it and the first sample.
    skip = [*range(header_row - 1), *range(header_row, header_row + units_rows)]
    frame = _parsed(path, sheet, csv, skip, mapped)
    _check_delimiter(path, frame, csv, mapped)
    frame.columns = [header_name(c) for c in frame.columns]
    _check_unique_header(path, frame, header_row)
    frame.attrs.update(first_row=header_row + units_rows + 1, mapped=mapped, decimal=csv["decimal"])
    # A spreadsheet's export often ends in rows of empty cells (",,,"): no samples.
    filled = np.flatnonzero(frame.notna().any(axis=1).to_numpy())
    frame = frame.iloc[: filled[-1] + 1] if filled.size else frame.iloc[:0]
    if frame.empty:
        raise DataError(f"{path}: no data rows below the header")
    return frame


def _parsed(path: Path, sheet, csv: dict, skip: list[int], mapped: bool) -> pd.DataFrame:
    """The table as pandas reads it, its errors turned into one-line messages on the file."""
    suffix = path.suffix.lower()
    try:
        if suffix in (".xlsx", ".xlsm"):
            # python-calamine reads FL_THERMAL's 11,115 x 23 workbook in 0.3 s against
            # openpyxl's 2.8 s, into the same frame (values and dtypes).
            frame = pd.read_excel(path, sheet_name=sheet, skiprows=skip, engine="calamine")
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
    except (ValueError, KeyError, CalamineError) as exc:
        first = str(exc).splitlines()[0]
        # The parser's "Expected 2 fields in line 12, saw 9": a logger's own lines above
        # the header set a narrower table than the samples.
        above = (
            "; lines above the header? set header_row"
            if mapped and "fields in line" in first
            else ""
        )
        raise DataError(f"{path}: cannot read the table ({first}){above}") from None
    return frame


def _check_delimiter(path: Path, frame: pd.DataFrame, csv: dict, mapped: bool) -> None:
    """One column holding another delimiter: the CSV was read with the wrong one."""
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
    :func:`read_wide_table` read the table with.

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


def _runs_rows(mapping_path: Path, mapping: dict, progress: Progress) -> list[tuple]:
    """Each run's tidy rows with the clock time of their 0 s, in the mapping's order."""
    source = (mapping_path.parent / mapping["source"]).resolve()
    if mapping["split"]["by"] == "files":
        pieces = []
        for i, run in enumerate(mapping["runs"]):
            table_path = source / run["file"]
            progress(i, len(mapping["runs"]), f"reading {run['file']}")
            frame = read_wide_table(table_path, *table_layout(mapping))
            pieces.append(
                (_tidy(table_path, frame, mapping), read_start(table_path, frame, mapping["time"]))
            )
        progress(len(mapping["runs"]), len(mapping["runs"]), "tables read")
        return pieces
    progress(0, 1, f"reading {source.name}")
    frame = read_wide_table(source, *table_layout(mapping))
    start = read_start(source, frame, mapping["time"])
    runs = split_runs(_tidy(source, frame, mapping), mapping, str(mapping_path))
    progress(1, 1, "table read")
    # Each run keeps its place on the record's clock, so runs follow each other in time.
    return [(rows, start) for rows in runs]
