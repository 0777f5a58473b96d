"""The raw-data reader: valid datasets load; every bad input fails with ONE clear line."""

from __future__ import annotations

import shutil
import warnings
from dataclasses import replace

import numpy as np
import pytest
import yaml

from helpers import DEFAULTS
from helpers.builders import set_csv_cell
from thermaxis.cleaning.run import clean_run
from thermaxis.dataset.plausibility import check_run_plausibility
from thermaxis.dataset.raw_files import clock_back_hint, read_measurement, read_temperature_source
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.errors import DataError


def one_line(excinfo) -> str:
    message = str(excinfo.value)
    assert "\n" not in message, message
    return message


def edit_yaml(path, change):
    doc = yaml.safe_load(path.read_text())
    change(doc)
    path.write_text(yaml.safe_dump(doc, sort_keys=False))


def test_valid_dataset_loads(tiny_dataset):
    ds = load_dataset(tiny_dataset)
    assert ds.name == "tiny"
    assert ds.simulated
    assert ds.run_ids == ("R1", "R2")
    assert ds.sensors == ("S1", "S2", "S3")
    raw = read_run(ds, "R1")
    assert list(raw.measurements) == ["M01", "M02", "M03", "M04"]
    assert list(raw.sources["box"].columns) == ["time", "S1", "S2", "S3"]
    # 4 positions x 2 passes
    assert len(raw.measurements["M01"]) == 8


def test_wrong_type_in_runs_sheet(tiny_dataset):
    path = tiny_dataset / "runs.tsv"
    path.write_text(path.read_text().replace("R2\t2\t2000", "R2\t2\tfast"))
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    msg = one_line(exc)
    assert (
        "runs.tsv" in msg
        and "line 3" in msg
        and "'feed_mm_min'" in msg
        and "a finite number" in msg
    )


def test_negative_feed_violates_schema(tiny_dataset):
    path = tiny_dataset / "runs.tsv"
    path.write_text(path.read_text().replace("R2\t2\t2000", "R2\t2\t-5"))
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    msg = one_line(exc)
    assert "runs.tsv" in msg and "feed_mm_min" in msg


def test_missing_column_in_runs_sheet(tiny_dataset):
    path = tiny_dataset / "runs.tsv"
    lines = [line.split("\t") for line in path.read_text().splitlines()]
    path.write_text("\n".join("\t".join(f[:1] + f[2:]) for f in lines) + "\n")
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    msg = one_line(exc)
    assert "runs.tsv" in msg and "missing column 'condition'" in msg


def test_wrong_type_in_dataset_yaml(tiny_dataset):
    edit_yaml(tiny_dataset / "dataset.yaml", lambda d: d["provenance"].update(kind="guessed"))
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    msg = one_line(exc)
    assert "dataset.yaml" in msg and "provenance/kind" in msg and "guessed" in msg


def test_missing_key_in_dataset_yaml(tiny_dataset):
    edit_yaml(tiny_dataset / "dataset.yaml", lambda d: d.pop("sensors"))
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    assert "'sensors' is a required property" in one_line(exc)


def test_sensor_with_undeclared_source(tiny_dataset):
    edit_yaml(tiny_dataset / "dataset.yaml", lambda d: d["sensors"][0].update(source="nowhere"))
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    msg = one_line(exc)
    assert "nowhere" in msg and "S1" in msg


def test_run_without_folder(tiny_dataset):
    shutil.rmtree(tiny_dataset / "R2")
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    msg = one_line(exc)
    assert "runs.tsv" in msg and "'R2' has no folder" in msg


def test_folder_not_in_runs_sheet(tiny_dataset):
    shutil.copytree(tiny_dataset / "R2", tiny_dataset / "R3")
    with pytest.raises(DataError) as exc:
        load_dataset(tiny_dataset)
    msg = one_line(exc)
    assert "R3" in msg and "not listed" in msg


def test_unknown_sensor_id(tiny_dataset):
    path = tiny_dataset / "R1" / "temperatures" / "box.csv"
    path.write_text(path.read_text().replace("S3", "S9", 1))
    ds = load_dataset(tiny_dataset)
    with pytest.raises(DataError) as exc:
        read_run(ds, "R1")
    msg = one_line(exc)
    assert "box.csv" in msg and "'S9'" in msg and "unknown sensor" in msg


def test_a_missing_sensor_column_is_a_sensor_without_readings_in_that_run(tiny_dataset):
    # As an empty column (issue 33): cleaning names the sensor and it leaves that run's
    # folds; the dataset goes on (tests/workflow: temp_sensor_column_missing).
    path = tiny_dataset / "R1" / "temperatures" / "box.csv"
    lines = [line.rsplit(",", 1)[0] for line in path.read_text().splitlines()]
    path.write_text("\n".join(lines) + "\n")
    box = read_run(load_dataset(tiny_dataset), "R1").sources["box"]
    assert list(box.columns) == ["time", "S1", "S2", "S3"]
    assert box["S3"].isna().all() and box["S2"].notna().all()


def test_unparseable_time(tiny_dataset):
    path = tiny_dataset / "R1" / "errors" / "M02.csv"
    lines = path.read_text().splitlines()
    lines[3] = "yesterday noon" + lines[3][19:]
    path.write_text("\n".join(lines) + "\n")
    ds = load_dataset(tiny_dataset)
    with pytest.raises(DataError) as exc:
        read_run(ds, "R1")
    msg = one_line(exc)
    assert "M02.csv" in msg and "line 4" in msg and "ISO 8601" in msg and "yesterday noon" in msg


def test_non_numeric_value(tiny_dataset):
    set_csv_cell(tiny_dataset / "R2" / "temperatures" / "box.csv", 10, 2, "warm")
    ds = load_dataset(tiny_dataset)
    with pytest.raises(DataError) as exc:
        read_run(ds, "R2")
    msg = one_line(exc)
    assert (
        "box.csv" in msg
        and "line 11" in msg
        and "'S2'" in msg
        and "expected a number" in msg
        and "warm" in msg
    )


def test_empty_cell_is_a_missing_sample_not_an_error(tiny_dataset):
    set_csv_cell(tiny_dataset / "R2" / "temperatures" / "box.csv", 10, 2, "")
    raw = read_run(load_dataset(tiny_dataset), "R2")
    assert np.isnan(raw.sources["box"]["S2"].iloc[9])


def test_empty_file(tiny_dataset):
    (tiny_dataset / "R1" / "errors" / "M03.csv").write_text("")
    ds = load_dataset(tiny_dataset)
    with pytest.raises(DataError) as exc:
        read_run(ds, "R1")
    msg = one_line(exc)
    assert "M03.csv" in msg and "empty file" in msg


def test_header_only_file(tiny_dataset):
    (tiny_dataset / "R1" / "errors" / "M03.csv").write_text("time,position_mm,error_um,direction\n")
    with pytest.raises(DataError) as exc:
        read_run(load_dataset(tiny_dataset), "R1")
    assert "no data rows" in one_line(exc)


def test_time_going_backwards(tiny_dataset):
    path = tiny_dataset / "R1" / "temperatures" / "box.csv"
    lines = path.read_text().splitlines()
    lines[20], lines[21] = lines[21], lines[20]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError) as exc:
        read_run(load_dataset(tiny_dataset), "R1")
    msg = one_line(exc)
    assert "box.csv" in msg and "line 22" in msg and "backwards" in msg


@pytest.mark.parametrize(
    "back_s, interval_s, named",
    [
        (3590.0, 10.0, True),  # a 10 s log put back an hour: 10:09:30, then 09:09:40
        (3000.0, 600.0, True),  # a 10 min log: 02:30, then 01:40
        (1800.0, 1800.0, True),  # a 30 min log: the step back is half an hour
        (2400.0, 5.0, False),  # readings 5 s apart going back 40 min: no clock change
        (3600.0 - 10.0, 3600.0, False),  # hourly samples cannot show an hour put back
    ],
)
def test_a_step_back_is_named_a_daylight_saving_change_only_at_an_hour_less_the_interval(
    back_s, interval_s, named
):
    assert bool(clock_back_hint(back_s, interval_s)) is named


def test_same_position_twice_with_different_values(tiny_dataset):
    path = tiny_dataset / "R1" / "errors" / "M01.csv"
    lines = path.read_text().splitlines()
    # Repeat the 2nd reading of the forward pass, later in time, with another value.
    t, x, e, d = lines[2].split(",")
    lines.insert(3, ",".join([t, x, str(float(e) + 1.0), d]))
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError) as exc:
        read_run(load_dataset(tiny_dataset), "R1")
    msg = one_line(exc)
    assert "M01.csv" in msg and "50 mm" in msg and "twice" in msg


def test_missing_error_column(tiny_dataset):
    path = tiny_dataset / "R1" / "errors" / "M01.csv"
    path.write_text(path.read_text().replace("error_um", "err"))
    with pytest.raises(DataError) as exc:
        read_run(load_dataset(tiny_dataset), "R1")
    assert "missing column 'error_um'" in one_line(exc)


def test_bad_direction(tiny_dataset):
    path = tiny_dataset / "R1" / "errors" / "M01.csv"
    lines = path.read_text().splitlines()
    lines[1] = lines[1][:-1] + "forward"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError) as exc:
        read_run(load_dataset(tiny_dataset), "R1")
    assert "'direction'" in one_line(exc)


def test_too_few_measurements(tiny_dataset):
    ds = load_dataset(tiny_dataset)
    with pytest.raises(DataError) as exc:
        read_run(ds, "R1", min_measurements=5)
    assert "at least 5" in one_line(exc)


def test_measurements_ordered_by_time_not_name(tiny_dataset):
    err = tiny_dataset / "R1" / "errors"
    (err / "M01.csv").rename(err / "Z_first.csv")
    raw = read_run(load_dataset(tiny_dataset), "R1")
    assert list(raw.measurements)[0] == "Z_first"
    assert raw.windows()["measurement"].tolist() == [1, 2, 3, 4]


def _notes(dataset, run: str) -> list[str]:
    """The run's plausibility warnings under the default cleaning settings."""
    return check_run_plausibility(dataset, read_run(dataset, run), DEFAULTS.cleaning)


def _warns_of_r1_only(dataset, message: str) -> None:
    assert _notes(dataset, "R1") == [message]
    assert _notes(dataset, "R2") == []


def test_files_the_reader_skips_are_named(tiny_dataset):
    # Only *.csv is read: an XLSX beside the exports or an upper-case suffix would vanish
    # unsaid; a hidden file is left unmentioned.
    errors = tiny_dataset / "R1" / "errors"
    (errors / "M05.xlsx").write_bytes(b"PK")
    (errors / "M04.csv").rename(errors / "M04.CSV")
    (errors / ".DS_Store").write_bytes(b"")
    dataset = load_dataset(tiny_dataset)
    notes = _notes(dataset, "R1")
    assert notes == [
        f"{errors}: skipped M04.CSV, M05.xlsx: only .csv files are read "
        "(export a spreadsheet as CSV, with a lower-case .csv suffix)"
    ]
    other = _notes(dataset, "R2")
    assert other == []


def _probe_logs_s3(root) -> None:
    """tiny_dataset with S3 logged by a second source, ``probe``, at box's times."""

    def move_s3(meta):
        meta["sensors"][2]["source"] = "probe"
        meta["sources"].append({"name": "probe", "clock_note": "reference", "clock_offset_s": 0})

    edit_yaml(root / "dataset.yaml", move_s3)
    for run in ("R1", "R2"):
        box = root / run / "temperatures" / "box.csv"
        rows = [line.split(",") for line in box.read_text().splitlines()]
        box.write_text("".join(",".join(r[:3]) + "\n" for r in rows))
        (box.parent / "probe.csv").write_text("".join(f"{r[0]},{r[3]}\n" for r in rows))


def test_a_source_without_a_log_in_one_run_costs_its_sensors_there(tiny_dataset):
    # Issue 33: one logger that recorded nothing in one run costs its sensors in that run
    # (they leave the candidates, as a sensor without a column does), not the dataset.
    _probe_logs_s3(tiny_dataset)
    missing = tiny_dataset / "R1" / "temperatures" / "probe.csv"
    missing.unlink()
    dataset = load_dataset(tiny_dataset)
    probe = read_run(dataset, "R1").sources["probe"]
    assert (len(probe), list(probe.columns)) == (0, ["time", "S3"])
    assert _notes(dataset, "R1") == [
        f"run R1: {missing}: no log of source probe in this run; its sensor(s) S3 have no "
        "reading here"
    ]
    assert _notes(dataset, "R2") == []
    cleaned = clean_run(tiny_dataset, "R1", DEFAULTS.cleaning, ())
    assert cleaned.error is None
    assert cleaned.tables.temperatures["sensor"].unique().tolist() == ["S1", "S2", "S3"]
    assert (
        cleaned.tables.temperatures.loc[cleaned.tables.temperatures["sensor"] == "S3", "absolute_c"]
        .isna()
        .all()
    )
    assert any("S3 leaves the candidate sensors of every fold" in w for w in cleaned.warnings)


def test_a_clock_offset_that_cannot_be_estimated_is_named_and_the_run_goes_on(tiny_dataset):
    _probe_logs_s3(tiny_dataset)
    probe = tiny_dataset / "R1" / "temperatures" / "probe.csv"
    rows = probe.read_text().splitlines()
    probe.write_text(
        "".join(f"{r.split(',')[0]},{'S3' if i == 0 else '25.0'}\n" for i, r in enumerate(rows))
    )
    settings = replace(
        DEFAULTS.cleaning,
        temperatures=replace(DEFAULTS.cleaning.temperatures, estimate_clock_offsets=True),
    )
    cleaned = clean_run(tiny_dataset, "R1", settings, ())
    assert cleaned.error is None
    assert [w for w in cleaned.warnings if "clock offset" in w] == [
        # S3 reads 25.0 throughout: nothing to align.
        f"run R1: {probe}: clock offset not estimated: the series overlap too little for a "
        "search of +/-120 s or do not vary; the 0 s that dataset.yaml declares is used "
        "(correct it there if the clock is off)"
    ]


def test_a_source_whose_log_has_only_its_header_costs_its_sensors_there(tiny_dataset):
    _probe_logs_s3(tiny_dataset)
    header_only = tiny_dataset / "R2" / "temperatures" / "probe.csv"
    header_only.write_text("time,S3\n")
    dataset = load_dataset(tiny_dataset)
    assert len(read_run(dataset, "R2").sources["probe"]) == 0
    assert _notes(dataset, "R2") == [
        f"run R2: {header_only}: no data rows below the header; its sensor(s) S3 have no "
        "reading here"
    ]


@pytest.mark.parametrize("empty", ["absent", "header only"])
def test_a_run_without_any_temperature_reading_is_refused(tiny_dataset, empty):
    folder = tiny_dataset / "R1" / "temperatures"
    if empty == "absent":
        (folder / "box.csv").unlink()
    else:
        (folder / "box.csv").write_text("time,S1,S2,S3\n")
    with pytest.raises(DataError) as exc:
        read_run(load_dataset(tiny_dataset), "R1")
    assert one_line(exc) == (
        f"{folder}: no temperature reading (every log absent or without data rows); expected "
        "one CSV per source that dataset.yaml declares sensors for (box.csv)"
    )


def test_a_signal_log_without_data_rows_is_refused(tmp_path):
    # A signal is every model's input: unlike a temperature log, its log must have rows.
    log = tmp_path / "plc.csv"
    log.write_text("time,spindle_rpm\n")
    with pytest.raises(DataError) as exc:
        read_temperature_source(log, ["spindle_rpm"], {"spindle_rpm"}, "signal")
    assert one_line(exc) == f"{log}: no data rows below the header"


def test_a_missing_operating_signal_column_is_refused(tmp_path):
    # An operating signal is every model's input: a run without it cannot be modelled.
    log = tmp_path / "plc.csv"
    log.write_text("time,other\n2022-05-10T09:00:00,1\n")
    with pytest.raises(DataError) as exc:
        read_temperature_source(log, ["spindle_rpm", "other"], {"spindle_rpm", "other"}, "signal")
    assert one_line(exc) == (
        f"{log}: missing column 'spindle_rpm' (declared for this source in dataset.yaml)"
    )


def _with_signal(dataset_root, logged_from: str | None = None, empty_run: str | None = None):
    """tiny_dataset with a spindle speed logged beside the temperatures (box's times)."""
    edit_yaml(
        dataset_root / "dataset.yaml",
        lambda d: d.update(signals=[{"id": "spindle_rpm", "unit": "rpm", "source": "box"}]),
    )
    for run in ("R1", "R2"):
        times = [
            line.split(",")[0]
            for line in (dataset_root / run / "temperatures" / "box.csv")
            .read_text()
            .splitlines()[1:]
        ]
        if logged_from and run == "R1":
            times = [t for t in times if t >= logged_from]
        value = "" if run == empty_run else "1500"
        (dataset_root / run / "signals").mkdir()
        (dataset_root / run / "signals" / "box.csv").write_text(
            "time,spindle_rpm\n" + "".join(f"{t},{value}\n" for t in times)
        )
    return load_dataset(dataset_root)


def test_a_signal_with_no_reading_in_a_run_is_refused(tiny_dataset):
    dataset = _with_signal(tiny_dataset, empty_run="R2")
    assert _notes(dataset, "R1") == []
    with pytest.raises(DataError) as exc:
        _notes(dataset, "R2")
    assert one_line(exc).startswith(
        f"{tiny_dataset / 'R2' / 'signals' / 'box.csv'}: column 'spindle_rpm': no reading in any row"
    )


def test_a_signal_log_that_starts_inside_the_measurements_is_named(tiny_dataset):
    # The first measurement starts at 09:00; the speed is logged from 09:30 on. Held back
    # by max_gap_s / 2 (300 s) at most, as a temperature is, it would be silently invented.
    dataset = _with_signal(tiny_dataset, logged_from="2022-05-10T09:30:00")
    _warns_of_r1_only(
        dataset,
        f"run R1: {tiny_dataset / 'R1' / 'signals' / 'box.csv'}: signal spindle_rpm has no reading "
        "before 2022-05-10 09:30:00, 30 min after the first measurement starts; its first value "
        "stands for it before then",
    )


def _rewrite_r1_errors(dataset, row) -> None:
    """Every measurement of run R1 with each row's (time, position, error, direction) mapped by ``row``."""
    for path in (dataset / "R1" / "errors").glob("*.csv"):
        lines = path.read_text().splitlines()
        rows = [row(*line.split(",")) for line in lines[1:]]
        path.write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")


def test_errors_written_in_mm_are_named(tiny_dataset):
    # A few micrometres of drift written in mm: every reading below 0.05 um.
    _rewrite_r1_errors(tiny_dataset, lambda t, x, e, d: [t, x, f"{float(e) / 1000:.9f}", d])
    # The builder's largest R1 error, measurement 4 at 150 mm: -8.5 um/m x 0.15 m - 2.1 um
    # = -3.375 um, written 0.003375 (mm); shown to 3 digits, 0.003375 rounds down in binary.
    _warns_of_r1_only(
        load_dataset(tiny_dataset),
        f"run R1: {tiny_dataset / 'R1' / 'errors'}: every error reading is within ±0.00337 um, "
        "below the 0.05 um a thermal error reaches; error_um is in micrometres (readings in mm "
        "are 1000 times too small)",
    )


def test_positions_written_in_metres_are_named(tiny_dataset):
    # The builder's targets 0, 50, 100 and 150 mm written in metres: 0.15 mm end to end.
    _rewrite_r1_errors(tiny_dataset, lambda t, x, e, d: [t, f"{float(x) / 1000:g}", e, d])
    _warns_of_r1_only(
        load_dataset(tiny_dataset),
        f"run R1: {tiny_dataset / 'R1' / 'errors'}: its 4 targets span 0.15 mm, below the 1 mm "
        "an axis's targets span; expected position_mm in millimetres (positions in metres are "
        "1000 times too small)",
    )


def test_a_line_cut_short_is_named_in_a_log_and_refused_in_a_measurement(tmp_path):
    log = tmp_path / "box.csv"
    log.write_text(
        "time,S1,S2\n2022-05-10T09:00:00,20.1,21.0\n2022-05-10T09:00:10,,21.1\n2022-05-10T09:00:20,20.3\n"
    )
    with pytest.warns(
        UserWarning, match=r"box.csv: line 4: 2 comma-separated fields but the header has 3"
    ):
        frame = read_temperature_source(log, ["S1", "S2"], {"S1", "S2"})
    np.testing.assert_array_equal(frame["S1"], [20.1, np.nan, 20.3])
    np.testing.assert_array_equal(frame["S2"], [21.0, 21.1, np.nan])
    # A blank written as such is a missing sample, without a word.
    log.write_text(log.read_text().replace("20.3\n", "20.3,\n"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_temperature_source(log, ["S1", "S2"], {"S1", "S2"})
    measurement = tmp_path / "M01.csv"
    measurement.write_text(
        "time,position_mm,error_um,direction\n2022-05-10T09:00:00,0,1.5,+\n2022-05-10T09:00:05,50\n"
    )
    with pytest.raises(DataError) as exc:
        read_measurement(measurement)
    assert one_line(exc) == (
        f"{measurement}: line 3: 2 comma-separated fields but the header has 4; expected 4 fields "
        "(time, position_mm, error_um, direction), an empty one for a missing value (a line cut short?)"
    )


def test_a_repeated_target_is_kept_when_exact_and_refused_when_it_conflicts(tmp_path):
    header = "time,position_mm,error_um,direction\n"
    rows = [
        "2022-05-10T09:00:00,0,1.5,+",
        "2022-05-10T09:00:05,50,2.5,+",
        "2022-05-10T09:00:10,50,-0.5,-",
    ]
    measurement = tmp_path / "M01.csv"
    # The same target in both passes is no repeat; logged twice with one value, a harmless
    # duplicate, read as written.
    measurement.write_text(header + "\n".join([*rows, "2022-05-10T09:00:15,50,-0.5,-"]) + "\n")
    frame = read_measurement(measurement)
    np.testing.assert_array_equal(frame["position_mm"], [0, 50, 50, 50])
    np.testing.assert_array_equal(frame["error_um"], [1.5, 2.5, -0.5, -0.5])
    # With another value it is two readings of one target in one pass: refused, naming both.
    measurement.write_text(header + "\n".join([*rows, "2022-05-10T09:00:15,50,-0.75,-"]) + "\n")
    with pytest.raises(DataError) as exc:
        read_measurement(measurement)
    assert one_line(exc) == (
        f"{measurement}: column 'position_mm': position 50 mm appears twice in the - pass with "
        "different errors [-0.5, -0.75] (expected one reading per target and pass)"
    )
