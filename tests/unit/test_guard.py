"""thermaxis.dataset.safety: the checks that stand between an untrusted dataset and the pipeline."""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers import DEFAULTS
from thermaxis.dataset import plausibility, safety
from thermaxis.errors import DataError
from thermaxis.method import selection
from thermaxis.method.folds import select_for_fold
from thermaxis.tables import format_cell

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(
    "name", ["..", ".", "...", "a/b", "a\\b", "-rf", "", ".hidden", "x" * 129, "a b", "é", "E1\n"]
)
def test_unsafe_names_are_refused(name):
    with pytest.raises(DataError, match="is not a safe name"):
        safety.check_name(name, "run", "runs.tsv")


@pytest.mark.parametrize("name", ["E1", "twin", "run_1.v2", "_x", "9", "a-b", "x" * 128])
def test_safe_names_pass(name):
    assert safety.check_name(name, "run", "runs.tsv") == name


@pytest.mark.parametrize(
    "schema, path",
    [
        ("dataset", ("properties", "name")),
        ("dataset", ("properties", "sensors", "items", "properties", "id")),
        ("dataset", ("properties", "sensors", "items", "properties", "source")),
        ("dataset", ("properties", "sources", "items", "properties", "name")),
        ("runs", ("properties", "run")),
        ("import_mapping", ("properties", "name")),
        ("import_mapping", ("properties", "source_name")),
        ("import_mapping", ("properties", "sensors", "items", "properties", "id")),
        ("import_mapping", ("properties", "signals", "items", "properties", "id")),
        ("import_mapping", ("properties", "runs", "items", "properties", "name")),
    ],
)
def test_every_sheet_schema_uses_the_one_name_pattern(schema, path):
    node = yaml.safe_load(
        (REPO / "src" / "thermaxis" / "schemas" / f"{schema}.schema.yaml").read_text()
    )
    for key in path:
        node = node[key]
    assert node["pattern"] == safety.NAME_PATTERN


def test_yaml_duplicate_key_names_both_lines(tmp_path):
    path = tmp_path / "d.yaml"
    path.write_text("name: a\nother: 1\nname: b\n")
    with pytest.raises(
        DataError,
        match=re.escape(
            f"{path}: line 3, column 1: not valid YAML (duplicate key 'name' (first on line 1))"
        ),
    ):
        safety.load_yaml(path)


def test_yaml_nested_duplicate_key_is_refused(tmp_path):
    path = tmp_path / "d.yaml"
    path.write_text("axis:\n  name: X\n  name: Y\n")
    with pytest.raises(DataError, match="line 3.*duplicate key 'name'"):
        safety.load_yaml(path)


def test_yaml_alias_is_refused_before_expansion(tmp_path):
    path = tmp_path / "bomb.yaml"
    # 9**10 items if expanded; the first alias is at line 2, column 10 ("a1: &a1 [" is 9
    # characters).
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 10)]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match="line 2, column 10: .*found alias \\*a0"):
        safety.load_yaml(path)


def test_yaml_non_finite_number_is_refused_with_its_key(tmp_path):
    path = tmp_path / "d.yaml"
    path.write_text("sources:\n  - {name: box, clock_offset_s: .nan}\n")
    with pytest.raises(
        DataError, match=re.escape("sources/0/clock_offset_s: expected a finite number, got nan")
    ):
        safety.load_yaml(path)


def test_yaml_plain_document_loads(tmp_path):
    path = tmp_path / "d.yaml"
    path.write_text("\ufeffname: twin\nsensors:\n  - {id: T1, tags: [a, b]}\n", encoding="utf-8")
    assert safety.load_yaml(path) == {"name": "twin", "sensors": [{"id": "T1", "tags": ["a", "b"]}]}


def test_fifo_is_refused_without_opening_it(tmp_path):
    fifo = tmp_path / "M01.csv"
    os.mkfifo(fifo)
    # Opening a FIFO without a writer would block forever; the check must not open it.
    with pytest.raises(
        DataError, match=re.escape(f"{fifo}: not a regular file (a FIFO); expected a data file")
    ):
        safety.check_regular_file(fifo, what="data file")


def test_size_limit_is_checked_before_reading(tmp_path):
    path = tmp_path / "big.csv"
    path.write_bytes(b"x" * 101)
    with pytest.raises(DataError, match="101 bytes, larger than the limit of 100 bytes"):
        safety.check_regular_file(path, max_bytes=100)
    assert safety.check_regular_file(path, max_bytes=101) == 101


@pytest.mark.parametrize(
    "content, delimiter, message",
    [
        (
            b"time;position_mm;error_um\n2022-01-01T00:00:00;1;2\n",
            ",",
            "line 1: looks semicolon-separated; expected comma-separated columns",
        ),
        (
            b"run,condition\nE1,1\n",
            "\t",
            "line 1: looks comma-separated; expected tab-separated columns",
        ),
        (
            b"time,T1,T2\n2022-01-01T00:00:00,20,5,21,0\n",
            ",",
            "line 2: 5 comma-separated fields but the header has 3; looks like decimal commas "
            "(expected '.' as the decimal mark)",
        ),
        (
            b"time,T1\n2022-01-01T00:00:00,20,x\n",
            ",",
            "line 2: 3 comma-separated fields but the header has 2; expected 2 fields (time, T1)",
        ),
        (
            b"time,T1\n2022-01-01T00:00:00,20\n2022-01-01T00:00:10,20,5\n",
            ",",
            "line 3: 3 comma-separated fields but the header has 2; expected 2 fields (time, T1)",
        ),
        (
            b"run\tcondition\tdescription\nE1\t1\twarm\tup\n",
            "\t",
            "line 2: 4 tab-separated fields but the header has 3; expected 3 fields (run, "
            "condition, description): a tab inside a text (a description?) is the likely cause; "
            "replace it with a space",
        ),
        (b"time,T1,T1\n", ",", "line 1: column 'T1' appears twice; expected each column once"),
        (b"time,,T1\n", ",", "line 1: column 2 has no name; expected a name for every column"),
        (
            "time,T1\n".encode("utf-16"),
            ",",
            "looks UTF-16-encoded (byte-order mark); expected UTF-8",
        ),
        (b"time,T1\nx,\xff\n", ",", "line 2: byte 0xff is not UTF-8; expected UTF-8 text"),
        (b"\n", ",", "line 1: empty header; expected a header row"),
    ],
)
def test_sniffing_names_what_the_file_looks_like(tmp_path, content, delimiter, message):
    path = tmp_path / "f.csv"
    path.write_bytes(content)
    # The whole message, so a decimal-comma hint where it does not belong fails.
    with pytest.raises(DataError, match=re.escape(f"{path}: {message}") + "$"):
        safety.sniff_delimited(path, delimiter)


def test_sniffing_accepts_utf8_bom_crlf_and_quoted_fields(tmp_path):
    path = tmp_path / "f.csv"
    path.write_bytes(b'\xef\xbb\xbftime,T1\r\n2022-01-01T00:00:00,"20,5"\r\n')
    safety.sniff_delimited(path, ",")


def test_check_within_normalises_before_comparing():
    assert safety.check_within("results/x/clean/{run}/qc.csv", ("results/x", "logs/x"), "rule r")
    for escaping in ("results/x/../y/a.csv", "/tmp/a.csv", "results/xy/a.csv", "results/x"):
        with pytest.raises(DataError, match="is outside"):
            safety.check_within(escaping, ("results/x", "logs/x"), "rule r")


def test_check_inside_follows_symlinks(tmp_path):
    root = tmp_path / "ds"
    root.mkdir()
    (tmp_path / "secret.csv").write_text("x")
    os.symlink(tmp_path / "secret.csv", root / "M01.csv")
    with pytest.raises(DataError, match=f"resolves to {tmp_path / 'secret.csv'}, outside {root}"):
        safety.check_inside(root / "M01.csv", root)
    assert safety.check_inside(root / "E1" / "M02.csv", root) == root / "E1" / "M02.csv"


def test_error_readings_beyond_the_bound_name_the_line():
    errors = np.array([0.5, -999.0, 1000.0, -1000.5])
    # Row 3 (index 3) is file line 5: header is line 1.
    with pytest.raises(
        DataError,
        match=re.escape(
            "M.csv: line 5, column 'error_um': -1000.5 um is beyond the plausible ±1000 um"
        ),
    ):
        plausibility.check_error_readings("M.csv", errors, 1000.0)
    with pytest.raises(DataError, match="line 2, column 'error_um': inf um"):
        plausibility.check_error_readings("M.csv", np.array([np.inf]), 1000.0)


def test_fahrenheit_and_kelvin_hints_convert_the_median():
    # 86 °F = 30 °C exactly; 4 °C is outside [5, 60], 5 and 60 are inside.
    notes = plausibility.sensor_median_warnings(
        {"T1": 86.0, "T2": 5.0, "T3": 60.0, "T4": 4.0, "T5": float("nan"), "T6": 300.0},
        5,
        60,
        "box.csv",
    )
    assert len(notes) == 3
    assert notes[0].startswith(
        "box.csv: sensor T1: median 86.0 °C is outside the plausible 5-60 °C"
    )
    assert "that is 30.0 °C" in notes[0]
    assert notes[1].startswith("box.csv: sensor T4: median 4.0 °C")
    # 300 K = 26.85 °C.
    assert "if it is in kelvin, that is 26.9 °C" in notes[2]
    # A logger's overflow value: three significant digits, not two hundred.
    (huge,) = plausibility.sensor_median_warnings({"T1": 1e200}, 5, 60, "box.csv")
    assert huge.startswith("box.csv: sensor T1: median 1e+200 °C is outside")
    assert "if it is in kelvin, that is 1e+200 °C" in huge


def test_constant_sensor_is_left_out_with_a_warning():
    frame = pd.DataFrame(
        {"T1": [20.0, 21.0, 22.0], "T2": [25.0, 25.0, 25.0], "T3": [1.0, 1.0, 1.5]}
    )
    with pytest.warns(
        UserWarning, match="fold E2: sensor T2 is constant over the training measurements"
    ):
        assert selection.informative_sensors(frame, (), "fold E2") == ["T1", "T3"]


def test_more_clusters_than_varying_sensors_make_each_sensor_a_sensitive_point():
    # Two training runs of three measurements; T2 is constant, so two sensors vary.
    X = pd.DataFrame(
        {"run": ["E1"] * 3 + ["E2"] * 3 + ["E3"] * 3, "measurement": [1, 2, 3] * 3,
         "time_min": [0.0, 20.0, 40.0] * 3,
         "T1": [20.0, 21.0, 22.5, 20.2, 21.4, 22.1, 19.0, 20.0, 21.0],
         "T2": [25.0] * 9,
         "T3": [1.0, 1.2, 1.5, 1.1, 1.1, 1.6, 0.0, 1.0, 2.0]}
    )  # fmt: skip
    Y = pd.DataFrame({0.0: np.linspace(0.0, -4.0, 9), 100.0: np.linspace(0.0, -5.0, 9)})
    with pytest.warns(UserWarning) as caught:
        chosen = select_for_fold(X, Y, "E3", replace(DEFAULTS.selection, n_clusters=3), 1)
    messages = [str(w.message) for w in caught]
    assert "fold E3: sensor T2 is constant over the training measurements" in messages[0]
    assert (
        "fold E3: 3 clusters (selection.n_clusters) but only 2 sensors vary over its training "
        "measurements; each is a cluster of its own, and a sensitive point"
    ) in messages
    assert sorted(chosen.k_sensors) == sorted(chosen.b_sensors) == ["T1", "T3"]


def test_constant_fixed_sensor_is_refused():
    frame = pd.DataFrame({"T1": [20.0, 21.0], "T2": [25.0, 25.0]})
    with pytest.raises(DataError, match="config selection.fixed: sensor T2 is constant"):
        selection.informative_sensors(frame, ("T1", "T2"), "fold E2")


def test_one_training_measurement_is_named():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(
            DataError, match="fold E2: 1 training measurement; selection and models need at least 2"
        ):
            selection.informative_sensors(pd.DataFrame({"T1": [20.0]}), (), "fold E2")


def test_runs_with_different_targets_are_named():
    errors = pd.DataFrame(
        {"run": ["E1"] * 3 + ["E2"] * 3, "position_mm": [0.0, 50.0, 100.0, 0.0, 50.0, 101.0]}
    )
    with pytest.raises(
        DataError,
        match=re.escape(
            "ds/E2/errors: run E2 reads 3 target positions, run E1 3 "
            "(101 mm is not a target of run E1)"
        ),
    ):
        plausibility.check_same_targets(errors, "ds")
    same = errors.assign(position_mm=[0.0, 50.0, 100.0] * 2)
    plausibility.check_same_targets(same, "ds")


@pytest.mark.parametrize(
    "value, text",
    [
        (["a", "b"], "a, b"),
        ({"x": 1.5, "y": "z"}, "x: 1.50, y: z"),
        ((), ""),
        (float("nan"), ""),
        (2.0, "2.00"),
    ],
)
def test_format_cell_takes_free_form_properties(value, text):
    assert format_cell(value, "%.2f") == text


def test_a_rule_writing_outside_the_dataset_folders_is_named():
    from types import SimpleNamespace

    inside = SimpleNamespace(
        name="clean_run",
        output=["results/x/clean/{run}/qc.csv"],
        log=["logs/x/clean/{run}.log"],
        benchmark="benchmarks/x/c.tsv",
    )
    escaping = SimpleNamespace(
        name="leak", output=["results/x/a.csv"], log=["logs/x/../leak.log"], benchmark=None
    )
    roots = ("results/x", "logs/x", "benchmarks/x")
    safety.check_rule_outputs([inside], roots)
    with pytest.raises(
        DataError,
        match=re.escape(
            "rule leak: output 'logs/x/../leak.log' is outside results/x, logs/x, benchmarks/x"
        ),
    ):
        safety.check_rule_outputs([inside, escaping], roots)


def _raw_run(starts, temperature_c, root=None):
    from thermaxis.dataset.reader import RawRun

    t0 = pd.Timestamp("2022-05-10T09:00:00")
    measurements = {
        f"M{k + 1}": pd.DataFrame(
            {
                "time": [t0 + pd.Timedelta(minutes=m), t0 + pd.Timedelta(minutes=m + 2)],
                "position_mm": [0.0, 100.0],
                "error_um": [0.0, -5.0],
            }
        )
        for k, m in enumerate(starts)
    }
    box = pd.DataFrame(
        {"time": [t0, t0 + pd.Timedelta(minutes=60)], "T1": [temperature_c, temperature_c + 1.0]}
    )
    files = {name: root / "E1" / "errors" / f"{name}.csv" for name in measurements} if root else {}
    return RawRun(run="E1", sources={"box": box}, measurements=measurements, error_files=files)


def _plausibility_config(interval_s=10.0):
    return replace(
        DEFAULTS.cleaning,
        temperatures=replace(DEFAULTS.cleaning.temperatures, interval_s=interval_s),
    )


def test_run_plausibility_warns_of_fahrenheit_unless_the_dataset_logs_rises(tmp_path):
    from types import SimpleNamespace

    # Median of 85 and 86 °F is 85.5 °F = 29.72 °C.
    absolute = SimpleNamespace(root=tmp_path, temperature_kind="absolute")
    (note,) = plausibility.check_run_plausibility(
        absolute, _raw_run([0, 20], 85.0), _plausibility_config()
    )
    assert note.startswith(
        f"{tmp_path / 'E1' / 'temperatures' / 'box.csv'}: sensor T1: median 85.5 °C"
    )
    assert "that is 29.7 °C" in note
    rise = SimpleNamespace(root=tmp_path, temperature_kind="rise")
    assert (
        plausibility.check_run_plausibility(rise, _raw_run([0, 20], 0.5), _plausibility_config())
        == []
    )


def test_run_plausibility_refuses_overlaps_and_a_grid_step_longer_than_the_run(tmp_path):
    from types import SimpleNamespace

    dataset = SimpleNamespace(root=tmp_path, temperature_kind="absolute")
    # M2 starts 1 min after M1, which lasts 2 min.
    with pytest.raises(
        DataError,
        match=re.escape(
            f"{tmp_path / 'E1' / 'errors' / 'M2.csv'}: "
            "readings from 2022-05-10 09:01:00 overlap measurement M1"
        ),
    ):
        plausibility.check_run_plausibility(
            dataset, _raw_run([0, 1], 20.0, tmp_path), _plausibility_config()
        )
    # The run spans 0 to 22 min = 1320 s.
    with pytest.raises(
        DataError,
        match=re.escape(
            "config temperatures.interval_s: 1321 s is longer than run E1 lasts (1320 s"
        ),
    ):
        plausibility.check_run_plausibility(
            dataset, _raw_run([0, 20], 20.0), _plausibility_config(interval_s=1321.0)
        )
    plausibility.check_run_plausibility(
        dataset, _raw_run([0, 20], 20.0), _plausibility_config(interval_s=1320.0)
    )


def test_a_schema_error_quotes_a_long_value_cut_with_its_length():
    import jsonschema

    from thermaxis.errors import schema_message

    (error,) = jsonschema.Draft202012Validator({"maxItems": 2}).iter_errors([1] * 100)
    # repr([1] * 100): "[" + 100 ones + 99 ", " + "]" = 300 characters; its first 60 are
    # "[" and 19 "1, " and "1,".
    assert schema_message(error) == "[" + "1, " * 19 + "1,... (300 characters) is too long"
    (short,) = jsonschema.Draft202012Validator({"maxItems": 2}).iter_errors([1, 2, 3])
    assert schema_message(short) == "[1, 2, 3] is too long"
