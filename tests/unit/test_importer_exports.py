"""The importer on real logger exports: time units, clock times, several error channels, the run summary."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from thermaxis.dataset.import_parsing import read_numeric, read_wide_table
from thermaxis.dataset.import_writing import RunSummary
from thermaxis.dataset.importer import import_dataset, run_warnings
from thermaxis.dataset.reader import load_dataset
from thermaxis.errors import DataError

RUNS = ("A", "B", "C")
MINUTES = np.arange(0.0, 362.0, 2.0)  # six hours, a sample every 2 min


def _per_run_csvs(folder: Path) -> None:
    """One CSV per run: minutes since the start, two temperatures, displacement in X and Z."""
    folder.mkdir(parents=True, exist_ok=True)
    for i, run in enumerate(RUNS, start=1):
        hours = MINUTES / 60.0
        pd.DataFrame(
            {
                "minutes": MINUTES,
                "temp A": 20.0 + 0.5 * i * hours,
                "temp B": 21.0 + 0.2 * hours,
                "dx (um)": 1.5 * i * hours,  # X grows 1.5 i um per hour
                "dz (um)": -0.4 * i * hours,
            }
        ).to_csv(folder / f"{run.lower()}.csv", index=False)


def _mapping(tmp_path: Path, time: dict, **changes) -> Path:
    _per_run_csvs(tmp_path / "logs")
    mapping = {
        "name": "rig",
        "source": "logs",
        "description": "Generated per-run logger exports.",
        "provenance": {"kind": "measured", "citation": "tests", "licence": "CC0"},
        "axis": {"name": "XZ"},
        "time": time,
        "sensors": [{"column": "temp A", "id": "TA"}, {"column": "temp B", "id": "TB"}],
        "errors": {
            "channels": [
                {"id": "X", "columns": [{"column": "dx (um)", "position_mm": 0}], "direction": "X"},
                {"id": "Z", "columns": [{"column": "dz (um)", "position_mm": 0}]},
            ],
            "every_s": 1800,
        },
        "split": {"by": "files"},
        "runs": [
            {"name": r, "condition": f"c{r}", "description": "x", "file": f"{r.lower()}.csv"}
            for r in RUNS
        ],
        **changes,
    }
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(mapping, allow_unicode=True))
    return path


def test_minutes_and_two_channels_import_into_two_datasets_of_six_hour_runs(tmp_path):
    mapping = _mapping(
        tmp_path, {"column": "minutes", "unit": "min", "start": "2030-01-01T08:00:00"}
    )
    report = import_dataset(mapping, tmp_path / "raw" / "rig")
    assert [d.name for d in report.datasets] == ["rig_X", "rig_Z"]
    assert report.warnings == ()
    for channel, per_hour in (("X", 1.5), ("Z", -0.4)):
        dataset = load_dataset(tmp_path / "raw" / "rig" / f"rig_{channel}")
        assert dataset.name == f"rig_{channel}" and dataset.run_ids == RUNS
        for i, run in enumerate(RUNS, start=1):
            errors = pd.read_csv(dataset.root / run / "errors.csv", parse_dates=["time"])
            # 0 .. 360 min every 30 min: 13 measurements over 6 h, from 08:00 to 14:00.
            assert len(errors) == 13
            assert errors["time"].iloc[0] == pd.Timestamp("2030-01-01T08:00:00")
            assert errors["time"].iloc[-1] == pd.Timestamp("2030-01-01T14:00:00")
            np.testing.assert_allclose(errors["error_um"], per_hour * i * np.arange(13) * 0.5)
    summary = report.datasets[0].runs
    assert summary[0] == RunSummary("A", 6 * 3600.0, len(MINUTES), 13)
    described = load_dataset(tmp_path / "raw" / "rig" / "rig_X").meta
    assert "minutes since the record's start" in described["description"]
    assert described["axis"]["direction"] == "X"


def test_the_same_mapping_without_a_unit_warns_naming_the_runs_and_the_unit(tmp_path):
    mapping = _mapping(tmp_path, {"column": "minutes", "start": "2030-01-01T08:00:00"})
    report = import_dataset(mapping, tmp_path / "raw" / "rig")
    # Read as seconds every run lasts 360 s = 6 min and yields one measurement (at 0 s).
    assert report.datasets[0].runs[0] == RunSummary("A", 360.0, len(MINUTES), 1)
    short = [w for w in report.warnings if "implausibly short" in w]
    assert len(short) == 2  # one per channel's dataset
    assert short[0].startswith("rig_X: run(s) A, B, C last 6 min to 6 min")
    assert "set time.unit: min (they would last 6 h to 6 h)" in short[0]
    few = [w for w in report.warnings if "fewer than 2 measurements" in w]
    assert few and "A (1), B (1), C (1)" in few[0]


def test_seconds_read_as_hours_suggest_seconds():
    # 18000 "h": 5 h runs in seconds.
    long = tuple(RunSummary(r, 5 * 3600 * 3600.0, 100, 9000) for r in ("R1", "R2"))
    (warning,) = run_warnings("d", {"column": "t", "unit": "h"}, 600.0, long)
    assert (
        "implausibly long" in warning and "set time.unit: s (they would last 5 h to 5 h)" in warning
    )


def _clock_table(path: Path, stamps: list[str]) -> None:
    n = len(stamps)
    pd.DataFrame(
        {"when": stamps, "temp A": np.linspace(20, 22, n), "temp B": 21.0, "dx (um)": np.arange(n)}
    ).to_csv(path, index=False)


def _clock_mapping(tmp_path: Path, fmt: str) -> Path:
    mapping = {
        "name": "clock",
        "source": "clock.csv",
        "description": "A record with clock times.",
        "provenance": {"kind": "measured", "citation": "tests"},
        "axis": {"name": "X"},
        "time": {"column": "when", "format": fmt},
        "sensors": [{"column": "temp A", "id": "TA"}, {"column": "temp B", "id": "TB"}],
        "errors": {"columns": [{"column": "dx (um)", "position_mm": 0}], "every_s": 1200},
        "split": {"by": "ranges"},
        "runs": [
            {"name": "R1", "condition": "a", "description": "x", "start_s": 0, "end_s": 3600},
            {"name": "R2", "condition": "b", "description": "y", "start_s": 3600, "end_s": 7200},
        ],
    }
    path = tmp_path / "clock.yaml"
    path.write_text(yaml.safe_dump(mapping))
    return path


def _assert_r2_read_as_logged(dataset) -> pd.DataFrame:
    """The record of _clock_table (every 10 min from 08:01:02, dx = the sample's index) after
    the import of _clock_mapping: R2 is [3600, 7200) s, samples 6 .. 11, a measurement
    every 20 min."""
    late = pd.read_csv(dataset.root / "R2" / "errors.csv")
    assert late["time"].tolist() == [
        "2020-06-15T09:01:02",
        "2020-06-15T09:21:02",
        "2020-06-15T09:41:02",
    ]
    assert late["error_um"].tolist() == [6.0, 8.0, 10.0]
    return late


def _assert_refused(mapping: Path, message: str) -> None:
    """The import of ``mapping`` stops with ``message`` and leaves no output folder."""
    out = mapping.parent / "raw"
    with pytest.raises(DataError, match=re.escape(message)):
        import_dataset(mapping, out)
    assert not out.exists()


def test_clock_times_are_read_as_logged_in_iso_8601_or_a_stated_format(tmp_path):
    start = pd.Timestamp("2020-06-15 08:01:02")
    times = [start + pd.Timedelta(minutes=10 * i) for i in range(12)]  # 08:01:02 .. 09:51:02
    _clock_table(tmp_path / "clock.csv", [t.strftime("%Y-%m-%d %H:%M:%S") for t in times])
    dataset = load_dataset(
        import_dataset(_clock_mapping(tmp_path, "ISO8601"), tmp_path / "iso").out
    )
    late = _assert_r2_read_as_logged(dataset)
    assert "logged clock times of column 'when'" in dataset.meta["description"]

    _clock_table(tmp_path / "clock.csv", [t.strftime("%d.%m.%Y %H:%M:%S") for t in times])
    stated = import_dataset(_clock_mapping(tmp_path, "%d.%m.%Y %H:%M:%S"), tmp_path / "stated")
    assert pd.read_csv(stated.out / "R2" / "errors.csv")["time"].tolist() == late["time"].tolist()


def test_a_bad_clock_time_names_the_row_and_column_and_leaves_nothing(tmp_path):
    stamps = [f"2020-06-15 08:{m:02d}:00" for m in range(0, 60, 10)]
    stamps[3] = "15/06/2020 08:30"
    _clock_table(tmp_path / "clock.csv", stamps)
    with pytest.raises(
        DataError,
        match=r"clock.csv: row 5, column 'when': expected an ISO 8601 clock time, got '15/06/2020 08:30'",
    ):
        import_dataset(_clock_mapping(tmp_path, "ISO8601"), tmp_path / "raw" / "clock")
    assert not (tmp_path / "raw").exists() or not any((tmp_path / "raw").iterdir())


def test_a_unit_beside_a_clock_format_is_refused(tmp_path):
    path = _clock_mapping(tmp_path, "ISO8601")
    mapping = yaml.safe_load(path.read_text())
    mapping["time"]["unit"] = "min"
    path.write_text(yaml.safe_dump(mapping))
    with pytest.raises(DataError, match="clock.yaml: time:"):
        import_dataset(path, tmp_path / "raw" / "clock")


def test_two_channels_of_one_id_are_refused_before_anything_is_written(tmp_path):
    path = _mapping(tmp_path, {"column": "minutes", "unit": "min", "start": "2030-01-01T08:00:00"})
    mapping = yaml.safe_load(path.read_text())
    mapping["errors"]["channels"][1]["id"] = "X"
    path.write_text(yaml.safe_dump(mapping))
    with pytest.raises(DataError, match=r"rig.yaml: errors/channels: id 'X' given more than once"):
        import_dataset(path, tmp_path / "raw" / "rig")
    assert not (tmp_path / "raw").exists()


def _european_export(path: Path, stamps: list[pd.Timestamp]) -> None:
    """The _clock_table record as a German spreadsheet writes it: ';' between columns, a
    decimal comma, the date and the time of day in columns of their own, Windows code page."""
    lines = ["Datum;Uhrzeit;Temp A [°C];Temp B [°C];dx (um)"]
    for i, t in enumerate(stamps):
        temp_a = f"{20 + 2 * i / (len(stamps) - 1):.4f}".replace(".", ",")
        lines.append(f"{t:%d.%m.%Y};{t:%H:%M:%S};{temp_a};21,0;{i},0")
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("cp1252"))


def _european_mapping(tmp_path: Path, csv: dict | None) -> Path:
    path = _clock_mapping(tmp_path, "%d.%m.%Y %H:%M:%S")
    mapping = yaml.safe_load(path.read_text())
    mapping["source"] = "export.csv"
    mapping["time"] = {"columns": ["Datum", "Uhrzeit"], "format": "%d.%m.%Y %H:%M:%S"}
    mapping["sensors"] = [
        {"column": "Temp A [°C]", "id": "TA"},
        {"column": "Temp B [°C]", "id": "TB"},
    ]
    if csv is not None:
        mapping["csv"] = csv
    path.write_text(yaml.safe_dump(mapping, allow_unicode=True), encoding="utf-8")
    return path


EUROPEAN = {"delimiter": ";", "decimal": ",", "encoding": "cp1252"}


def test_a_european_spreadsheet_export_imports_as_its_plain_twin(tmp_path):
    start = pd.Timestamp("2020-06-15 08:01:02")
    times = [start + pd.Timedelta(minutes=10 * i) for i in range(12)]
    _european_export(tmp_path / "export.csv", times)
    dataset = load_dataset(
        import_dataset(_european_mapping(tmp_path, EUROPEAN), tmp_path / "eu").out
    )
    _assert_r2_read_as_logged(dataset)
    logged = pd.read_csv(dataset.root / "R1" / "temperatures" / "logger.csv")
    assert logged["TA"].tolist()[:3] == [20.0, 20.1818, 20.3636]  # 20 + 2 i / 11, 4 decimals
    assert "logged clock times of columns 'Datum' + 'Uhrzeit'" in dataset.meta["description"]
    assert (
        "A CSV source was read with ';' between columns, a decimal comma and the cp1252 encoding"
        in dataset.meta["description"]
    )


@pytest.mark.parametrize(
    "csv, message",
    [
        (None, "export.csv: not utf-8 text (byte 0xb0 at offset 22); set csv.encoding in the mapping"),
        ({"encoding": "cp1252"}, "export.csv: one column 'Datum;Uhrzeit;Temp A [°C];Temp B [°C];dx (um)': "
                                 "looks ';'-separated; set csv.delimiter: ';' in the mapping"),
        ({"encoding": "cp1252", "delimiter": ";"}, "export.csv: row 2, column 'Temp A [°C]': expected a finite "
                                                   "number, got '20,0000'; a decimal comma? set csv.decimal: ','"),
        ({"encoding": "cp-9999"}, "clock.yaml: csv/encoding: unknown encoding 'cp-9999'"),
    ],
    ids=["encoding", "delimiter", "decimal", "unknown_encoding"],
)  # fmt: skip
def test_each_setting_a_european_export_needs_is_named_when_it_is_missing(tmp_path, csv, message):
    _european_export(
        tmp_path / "export.csv",
        [pd.Timestamp("2020-06-15 08:00") + pd.Timedelta(hours=i) for i in range(3)],
    )
    with pytest.raises(DataError, match=re.escape(message)):
        import_dataset(_european_mapping(tmp_path, csv), tmp_path / "raw" / "eu")
    assert not (tmp_path / "raw").exists() or not any((tmp_path / "raw").iterdir())


def test_a_date_without_its_time_of_day_is_named_as_a_coarse_clock(tmp_path):
    stamps = [pd.Timestamp("2020-06-15 08:00") + pd.Timedelta(minutes=10 * i) for i in range(3)]
    _european_export(tmp_path / "export.csv", stamps)
    path = _european_mapping(tmp_path, EUROPEAN)
    mapping = yaml.safe_load(path.read_text(encoding="utf-8"))
    mapping["time"] = {"column": "Datum", "format": "%d.%m.%Y"}
    path.write_text(yaml.safe_dump(mapping, allow_unicode=True), encoding="utf-8")
    with pytest.raises(
        DataError,
        match=re.escape(
            "export.csv: row 3, column 'Datum': time does not increase (0 after 0 s); a clock "
            "coarser than the logging (a date without its time of day, or whole seconds logged "
            "faster than once a second)?"
        ),
    ):
        import_dataset(path, tmp_path / "raw" / "eu")


def test_a_clock_put_back_an_hour_is_named_as_a_daylight_saving_change(tmp_path):
    start = pd.Timestamp("2020-10-25 01:40:00")
    times = [start + pd.Timedelta(minutes=10 * i) for i in range(12)]
    times[6:] = [t - pd.Timedelta(hours=1) for t in times[6:]]  # 02:30, then 01:40 again
    _clock_table(tmp_path / "clock.csv", [f"{t:%Y-%m-%d %H:%M:%S}" for t in times])
    _assert_refused(
        _clock_mapping(tmp_path, "ISO8601"),
        "clock.csv: row 8, column 'when': time does not increase (0 after 3000 s); "
        "a daylight-saving change? log in UTC or in standard time",
    )


def test_split_clock_columns_need_a_format(tmp_path):
    path = _european_mapping(tmp_path, EUROPEAN)
    mapping = yaml.safe_load(path.read_text(encoding="utf-8"))
    mapping["time"] = {"columns": ["Datum", "Uhrzeit"], "start": "2020-06-15T08:00:00"}
    path.write_text(yaml.safe_dump(mapping, allow_unicode=True), encoding="utf-8")
    with pytest.raises(DataError, match="clock.yaml: time:"):
        import_dataset(path, tmp_path / "raw" / "eu")


def test_a_workbooks_typed_date_and_time_cells_are_read_whatever_their_display_format(tmp_path):
    import datetime

    import openpyxl

    start = datetime.datetime(2020, 6, 15, 8, 1, 2)
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["Datum", "Uhrzeit", "temp A", "temp B", "dx (um)"])
    for i in range(12):
        t = start + datetime.timedelta(minutes=10 * i)
        sheet.append([t.date(), t.time(), 20 + 2 * i / 11, 21.0, float(i)])
        sheet.cell(row=i + 2, column=1).number_format = "DD.MM.YYYY"  # as Excel shows it
    book.save(tmp_path / "clock.xlsx")
    path = _clock_mapping(tmp_path, "%d.%m.%Y %H:%M:%S")
    mapping = yaml.safe_load(path.read_text())
    mapping["source"] = "clock.xlsx"
    mapping["time"] = {"columns": ["Datum", "Uhrzeit"], "format": "%d.%m.%Y %H:%M:%S"}
    path.write_text(yaml.safe_dump(mapping))
    dataset = load_dataset(import_dataset(path, tmp_path / "xlsx").out)
    _assert_r2_read_as_logged(dataset)


@pytest.mark.parametrize(
    "content, expected",
    [
        (b"time,temp A\n0,20.0\n", "Cannot detect file format"),  # a CSV given the suffix
        (b"PK\x03\x04 cut short", "Cannot detect file format"),  # a truncated zip
    ],
    ids=["csv_named_xlsx", "truncated_zip"],
)
def test_a_file_that_is_no_workbook_is_one_line_naming_it(tmp_path, content, expected):
    (tmp_path / "clock.xlsx").write_bytes(content)
    path = _clock_mapping(tmp_path, "ISO8601")
    mapping = yaml.safe_load(path.read_text())
    mapping["source"] = "clock.xlsx"
    path.write_text(yaml.safe_dump(mapping))
    with pytest.raises(DataError) as caught:
        import_dataset(path, tmp_path / "raw")
    message = str(caught.value)
    assert message.startswith(f"{tmp_path / 'clock.xlsx'}: cannot read the table (")
    assert expected in message and "\n" not in message
    assert not (tmp_path / "raw").exists()


def test_a_text_cell_among_decimal_commas_is_the_cell_named(tmp_path):
    start = pd.Timestamp("2020-06-15 08:01:02")
    _european_export(
        tmp_path / "export.csv", [start + pd.Timedelta(minutes=10 * i) for i in range(12)]
    )
    path = tmp_path / "export.csv"
    text = path.read_bytes().decode("cp1252").replace(";21,0;1,0", ";defekt;1,0")  # row 3, temp B
    path.write_bytes(text.encode("cp1252"))
    with pytest.raises(
        DataError,
        match=re.escape(
            "export.csv: row 3, column 'Temp B [°C]': expected a finite number, got 'defekt'"
        ),
    ):
        import_dataset(_european_mapping(tmp_path, EUROPEAN), tmp_path / "raw" / "eu")


def _logger_export(path: Path) -> None:
    """The _clock_table record as a logger writes it: its own lines above the header, a
    blank line among them, and a units row below the header."""
    start = pd.Timestamp("2020-06-15 08:01:02")
    lines = [
        "Instrument,GL220",
        "",
        "Channels,3",
        "when,temp A,temp B,dx (um)",
        "time,degC,degC,um",
    ]
    for i in range(12):
        t = start + pd.Timedelta(minutes=10 * i)
        lines.append(f"{t:%Y-%m-%d %H:%M:%S},{20 + 2 * i / 11:.4f},21.0,{i}")
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize(
    "layout, message",
    [
        ({}, "clock.csv: cannot read the table (Error tokenizing data. C error: Expected 2 fields in "
             "line 4, saw 4); lines above the header? set header_row"),
        ({"header_row": 4}, "clock.csv: row 5, column 'when': expected an ISO 8601 clock time, got 'time'; "
                            "a units row below the header? set units_rows: 1"),
        ({"header_row": 4, "units_rows": 1}, None),
    ],
    ids=["lines_above", "units_row", "both_set"],
)  # fmt: skip
def test_a_loggers_own_lines_and_units_row_are_skipped_when_the_mapping_says(
    tmp_path, layout, message
):
    _logger_export(tmp_path / "clock.csv")
    path = _clock_mapping(tmp_path, "ISO8601")
    mapping = {**yaml.safe_load(path.read_text()), **layout}
    path.write_text(yaml.safe_dump(mapping))
    if message:
        with pytest.raises(DataError, match=re.escape(message)):
            import_dataset(path, tmp_path / "raw")
        return
    _assert_r2_read_as_logged(load_dataset(import_dataset(path, tmp_path / "raw").out))


def test_a_units_row_is_named_when_a_number_column_starts_with_a_unit(tmp_path):
    _logger_export(tmp_path / "clock.csv")
    path = _clock_mapping(tmp_path, "ISO8601")
    mapping = yaml.safe_load(path.read_text())
    mapping["time"] = {"interval_s": 600, "start": "2020-06-15T08:01:02"}  # the clock aside
    mapping["header_row"] = 4
    path.write_text(yaml.safe_dump(mapping))
    with pytest.raises(
        DataError,
        match=re.escape(
            "clock.csv: row 5, column 'temp A': expected a finite number, got 'degC'; a units "
            "row below the header? set units_rows: 1"
        ),
    ):
        import_dataset(path, tmp_path / "raw")


def test_two_columns_of_one_name_are_refused(tmp_path):
    (tmp_path / "clock.csv").write_text(
        "when,temp A,temp B,temp A,dx (um)\n2020-06-15 08:00:00,20.0,21.0,22.0,0\n"
    )
    _assert_refused(
        _clock_mapping(tmp_path, "ISO8601"),
        "clock.csv: row 1: column 'temp A' is named more than once (columns 2 and 4); "
        "rename one so that the mapping can tell them apart",
    )


def test_a_line_break_in_a_header_cell_reads_as_a_space(tmp_path):
    start = pd.Timestamp("2020-06-15 08:01:02")
    lines = ['when,"temp\nA",temp  B ,dx (um)']  # a spreadsheet's wrapped header cell, double space
    lines += [
        f"{start + pd.Timedelta(minutes=10 * i):%Y-%m-%d %H:%M:%S},20,21,{i}" for i in range(12)
    ]
    (tmp_path / "clock.csv").write_text("\n".join(lines) + "\n")
    _assert_r2_read_as_logged(
        load_dataset(import_dataset(_clock_mapping(tmp_path, "ISO8601"), tmp_path / "raw").out)
    )


def test_a_tab_separated_table_is_named_so_before_its_names_are_normalised(tmp_path):
    from thermaxis.dataset.import_parsing import read_wide_table

    path = tmp_path / "tabs.csv"
    path.write_text("when\ttemp A\n2020-06-15 08:00:00\t20\n")
    with pytest.raises(
        DataError, match=re.escape("looks '\\t'-separated; set csv.delimiter: '\\t'")
    ):
        read_wide_table(path, 0, {})


def test_errors_logged_in_mm_are_written_in_um_and_the_description_says_so(tmp_path):
    start = pd.Timestamp("2020-06-15 08:01:02")
    times = [start + pd.Timedelta(minutes=10 * i) for i in range(12)]
    _clock_table(tmp_path / "clock.csv", [f"{t:%Y-%m-%d %H:%M:%S}" for t in times])
    table = pd.read_csv(tmp_path / "clock.csv")
    table["dx (um)"] = table["dx (um)"] / 1000.0  # the same displacement, logged in mm
    table.to_csv(tmp_path / "clock.csv", index=False)
    path = _clock_mapping(tmp_path, "ISO8601")
    mapping = yaml.safe_load(path.read_text())
    mapping["errors"]["unit"] = "mm"
    path.write_text(yaml.safe_dump(mapping))
    dataset = load_dataset(import_dataset(path, tmp_path / "raw").out)
    _assert_r2_read_as_logged(dataset)  # 0.006 mm is 6 um, as logged in um above
    assert "logged in mm and converted to um (x 1000)" in dataset.meta["description"]


@pytest.mark.parametrize(
    "unit, kind, logged",
    [
        ("K", "absolute", lambda c: c + 273.15),  # 294.15 K
        ("degF", "absolute", lambda c: c * 9.0 / 5.0 + 32.0),  # 69.8 F
        ("degF", "rise", lambda c: c * 9.0 / 5.0),  # a rise of 37.8 F is 21 C, no offset
    ],
)
def test_temperatures_logged_in_kelvin_or_fahrenheit_are_written_in_celsius(
    tmp_path, unit, kind, logged
):
    start = pd.Timestamp("2020-06-15 08:01:02")
    times = [start + pd.Timedelta(minutes=10 * i) for i in range(12)]
    _clock_table(tmp_path / "clock.csv", [f"{t:%Y-%m-%d %H:%M:%S}" for t in times])
    table = pd.read_csv(tmp_path / "clock.csv")
    table["temp B"] = logged(21.0)
    table.to_csv(tmp_path / "clock.csv", index=False)
    path = _clock_mapping(tmp_path, "ISO8601")
    mapping = {
        **yaml.safe_load(path.read_text()),
        "temperature_unit": unit,
        "temperature_kind": kind,
    }
    path.write_text(yaml.safe_dump(mapping))
    dataset = load_dataset(import_dataset(path, tmp_path / "raw").out)
    logs = pd.read_csv(dataset.root / "R1" / "temperatures" / "logger.csv")
    assert logs["TB"].to_numpy() == pytest.approx(21.0, abs=1e-9)
    assert f"Temperatures were logged in {unit} and converted to degrees C." in (
        dataset.meta["description"].replace("\n", " ")
    )


@pytest.mark.parametrize(
    "cell, quoted",
    [
        ("inf", "inf"),  # read as a number: named as one, not as numpy's np.float64(inf)
        ("x" * 5000, "'" + "x" * 59 + "... (5,000 characters)"),  # a pasted document, cut
        ("hot", "'hot'"),
    ],
    ids=["infinite", "long_text", "word"],
)
def test_a_cell_that_is_not_a_finite_number_is_quoted_readably(tmp_path, cell, quoted):
    path = tmp_path / "log.csv"
    path.write_text(f"time_s,T1\n0,20.1\n10,{cell}\n")
    with pytest.raises(DataError) as raised:
        read_numeric(path, read_wide_table(path), "T1", allow_empty=True)
    assert str(raised.value) == (
        f"{path}: row 3, column 'T1': expected a finite number, got {quoted}"
    )


def test_an_empty_table_is_one_line_saying_what_was_expected(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("")
    with pytest.raises(DataError, match=r"log\.csv: empty file, expected a header and data rows$"):
        read_wide_table(path)


def _edited_clock_mapping(tmp_path: Path, edit) -> Path:
    """_clock_mapping's ISO 8601 record (every 10 min from 08:01:02; R1 [0, 3600) s, R2
    [3600, 7200) s), edited."""
    start = pd.Timestamp("2020-06-15 08:01:02")
    _clock_table(
        tmp_path / "clock.csv",
        [(start + pd.Timedelta(minutes=10 * i)).strftime("%Y-%m-%d %H:%M:%S") for i in range(12)],
    )
    path = _clock_mapping(tmp_path, "ISO8601")
    mapping = yaml.safe_load(path.read_text())
    edit(mapping)
    path.write_text(yaml.safe_dump(mapping))
    return path


def _elapsed(start: str):
    return lambda mapping: mapping.update(time={"column": "temp B", "start": start})


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda m: m["runs"][1].update(start_s=1800),
         "run 'R2' [1800, 7200) s overlaps run 'R1' [0, 3600) s; expected ranges that do not "
         "overlap (a sample belongs to one run)"),
        (lambda m: m["runs"][1].update(start_s=7200, end_s=3600),
         "run 'R2': start_s 7200 is not before end_s 3600; expected [start_s, end_s) in seconds "
         "since the record's start"),
        (lambda m: m["sensors"].append({"column": "temp A", "id": "TA2"}),
         "column 'temp A' is mapped twice (TA and TA2); expected each column of the table under "
         "one id"),
        (lambda m: m["errors"]["columns"].append({"column": "temp B", "position_mm": 10}),
         "column 'temp B' is mapped twice (TB and an error column)"),
        (lambda m: m.update(licence_file="LICENSE"), "licence_file: "),
        (_elapsed("yesterday"), "time/start: expected an ISO 8601 time, got 'yesterday'"),
        (_elapsed(""), "time/start: expected an ISO 8601 time, got ''"),
    ],
    ids=["overlapping_runs", "reversed_range", "sensor_twice", "error_is_a_sensor",
         "licence_missing", "start_not_a_time", "start_empty"],
)  # fmt: skip
def test_a_mapping_that_contradicts_itself_is_refused_before_the_table_is_read(
    tmp_path, edit, message
):
    _assert_refused(_edited_clock_mapping(tmp_path, edit), f"clock.yaml: {message}")


def test_a_spreadsheets_trailing_empty_rows_are_no_samples(tmp_path):
    path = _edited_clock_mapping(tmp_path, lambda m: None)
    table = tmp_path / "clock.csv"
    table.write_text(table.read_text() + ",,,\n" * 3)
    late = _assert_r2_read_as_logged(load_dataset(import_dataset(path, tmp_path / "raw").out))
    assert len(late) == 3


def test_an_error_column_without_a_reading_in_a_run_is_refused(tmp_path):
    path = _edited_clock_mapping(tmp_path, lambda m: None)
    table = tmp_path / "clock.csv"
    lines = table.read_text().splitlines()
    # R2 is [3600, 7200) s: the rows from 09:01:02 on (file lines 8 to 13) lose their dx.
    table.write_text(
        "\n".join(lines[:7] + [line.rsplit(",", 1)[0] + "," for line in lines[7:]]) + "\n"
    )
    _assert_refused(
        path,
        "clock.csv: run 'R2': column(s) 'dx (um)' have no reading at any of the run's 3 "
        "measurement(s) (one every 1200 s); expected error readings",
    )


def test_a_single_run_is_warned_of_at_the_import():
    (warning,) = run_warnings(
        "d", {"column": "t", "unit": "s"}, 600.0, (RunSummary("R1", 5 * 3600.0, 100, 9),)
    )
    assert warning == (
        "d: 1 run; leave-one-condition-out needs at least 2, so the workflow refuses such a "
        "dataset (list more runs, or split the record)"
    )
