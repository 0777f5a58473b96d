"""One raw file of the layout read and checked: a temperature or signal log, a measurement.

The cells of a CSV file are read as text and parsed column by column (the clock, the
numbers, their order), each problem a one-line :class:`DataError` naming the file, the
row (1-based line number in the file, header = line 1) or column, and what was
expected. :mod:`thermaxis.dataset.reader` assembles these files into a dataset's runs.
"""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.dataset import plausibility, safety
from thermaxis.errors import DataError, shown

__all__ = [
    "read_temperature_source",
    "read_measurement",
    "read_measurements",
    "clock_back_hint",
    "median_step_s",
]

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
    # Most files repeat no target: the test for any repeat is a fifth of the grouping's cost,
    # paid per measurement file (hundreds in a run of single-reading measurements).
    if not frame.duplicated(["direction", "position_mm"]).any():
        return
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
