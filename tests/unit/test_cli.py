"""The ``thermaxis`` command: ``check`` as the workflow's gate, ``import``'s summary, help texts."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers import REPO
from thermaxis.cli import build_parser, main
from thermaxis.cli.progress import ProgressBar


def _thermaxis(*args, cwd=REPO) -> subprocess.CompletedProcess:
    env = {
        **os.environ,
        "PYTHONPATH": f"{REPO / 'src'}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
    }
    return subprocess.run(
        [sys.executable, "-m", "thermaxis.cli", *args], cwd=cwd, env=env, capture_output=True,
        text=True, timeout=120,
    )  # fmt: skip


@pytest.mark.parametrize(
    "dataset, expected",
    [
        ("data/raw/twin", ["dataset twin (SIMULATED)", "12 sensors: T1, T2", "14 target position(s)",
                           "4 runs (held-out folds: E1, E2, E3, E4)", "E1     8 measurements",
                           # the twin's README: the box logs every 10 s, the HMI every 60 s
                           "14 positions  logs: box 10 s, wireless 3", ", hmi 60 s\n"]),
        ("data/raw/fl_thermal", ["dataset fl_thermal (MEASURED)", "16 sensors", "1 target position(s): point-by-point",
                                 "6 runs", "R6_variable    38 measurements",
                                 # its README: every 15 s, the speed with the temperatures
                                 "1 position  logs: logger 15 s, signals: logger 15 s\n"]),
    ],
)  # fmt: skip
def test_check_passes_an_embedded_dataset_and_says_what_it_holds(dataset, expected):
    if not (REPO / dataset).is_dir():
        pytest.skip(f"{dataset} is not in this checkout")
    proc = _thermaxis("check", dataset)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(f"thermaxis: {dataset}: every check before any job passed\n")
    for line in expected:
        assert line in proc.stdout


def _comma_separated(ds: Path) -> None:
    path = ds / "runs.tsv"
    path.write_text(
        path.read_text().replace(
            "run\tcondition\tfeed_mm_min\tdescription", "run,condition,feed_mm_min,description", 1
        )
    )


def _bad_kind(ds: Path) -> None:
    meta = yaml.safe_load((ds / "dataset.yaml").read_text())
    meta["provenance"]["kind"] = "guessed"
    (ds / "dataset.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))


def _leading_dash(ds: Path) -> None:
    (ds / "E2/errors/M03.csv").rename(ds / "E2/errors/-M03.csv")


def _blank_later_error(ds: Path) -> None:
    path = ds / "E4/errors/M07.csv"
    lines = path.read_text().splitlines()
    lines[4] = "2022-03-18T12:32:55,245,,+"  # file line 5
    path.write_text("\n".join(lines) + "\n")


def _clock_put_back_an_hour(ds: Path) -> None:
    """E3's box log from file line 600 (10:09:40, every 10 s from 08:30:00) an hour earlier."""
    path = ds / "E3/temperatures/box.csv"
    lines = path.read_text().splitlines()
    for i in range(599, len(lines)):
        hour = int(lines[i][11:13]) - 1
        lines[i] = f"{lines[i][:11]}{hour:02d}{lines[i][13:]}"
    path.write_text("\n".join(lines) + "\n")


def _copied_measurement(ds: Path) -> None:
    shutil.copy(ds / "E2/errors/M03.csv", ds / "E2/errors/M09.csv")


def _targets_differ(ds: Path) -> None:
    for path in (ds / "E3/errors").glob("*.csv"):
        path.write_text(path.read_text().replace(",445,", ",455,"))


def _units_row(ds: Path) -> None:
    path = ds / "E2/temperatures/hmi.csv"
    lines = path.read_text().splitlines()
    path.write_text("\n".join([lines[0], ",degC", *lines[1:]]) + "\n")


# The messages of tests/workflow/CATALOGUE.md for the same edits (<ds> is the dataset folder).
@pytest.mark.parametrize(
    "edit, message",
    [
        (_comma_separated, "thermaxis error: <ds>/runs.tsv: line 1: looks comma-separated; expected tab-separated columns"),
        (_bad_kind, "thermaxis error: <ds>/dataset.yaml: provenance/kind: 'guessed' is not one of ['simulated', 'measured']"),
        (_leading_dash, "thermaxis error: <ds>/E2/errors/-M03.csv: measurement '-M03' is not a safe name (expected "
                        "letters, digits, '_', '.', '-', starting with a letter, digit or '_', at most 128 characters)"),
        # Files `check` reads beyond each run's first measurement: nothing is said to pass.
        (_blank_later_error, "thermaxis error: <ds>/E4/errors/M07.csv: line 5, column 'error_um': expected a number, got ''"),
        (_clock_put_back_an_hour, "thermaxis error: <ds>/E3/temperatures/box.csv: line 600, column 'time': time goes backwards "
                                  "(2022-03-17 09:09:40 after 2022-03-17 10:09:30); a daylight-saving change? log in UTC or in standard time"),
        # The clean job's plausibility checks, made by `check` as well.
        (_copied_measurement, "thermaxis error: <ds>/E2/errors/M09.csv: readings from 2022-03-15 13:51:09 overlap "
                              "measurement M03 (2022-03-15 13:51:09 to 2022-03-15 13:53:55); expected one "
                              "measurement at a time (a copied file?)"),
        (_units_row, "thermaxis error: <ds>/E2/temperatures/hmi.csv: line 2, column 'time': expected an ISO 8601 time, "
                     "got ''; a units row? the layout has none (temperatures in degrees C, errors in um: data/README.md)"),
        # The assemble job's comparison of the runs' targets.
        (_targets_differ, "thermaxis error: <ds>/E3/errors: run E3 reads 14 target positions, run E1 14 (455 mm is not "
                          "a target of run E1); expected the same targets in every run"),
    ],
    ids=["runs_comma_separated", "yaml_bad_kind", "measurement_leading_dash", "later_error_blank", "log_clock_dst",
         "copied_measurement", "log_units_row", "targets_differ"],
)  # fmt: skip
def test_check_refuses_a_bad_dataset_with_the_workflows_one_line(edit, message, tmp_path):
    ds = tmp_path / "cut"
    shutil.copytree(REPO / "data/raw/twin", ds)
    edit(ds)
    proc = _thermaxis("check", str(ds))
    assert proc.returncode == 1 and proc.stdout == ""
    assert proc.stderr == message.replace("<ds>", str(ds)) + "\n"


def test_check_warns_as_the_clean_job_would_of_a_sensor_logged_in_fahrenheit(tmp_path):
    ds = tmp_path / "cut"
    shutil.copytree(REPO / "data/raw/twin", ds)
    log = ds / "E2/temperatures/box.csv"
    table = pd.read_csv(log, dtype=str)
    celsius = pd.to_numeric(table["T3"])
    table["T3"] = (celsius * 9 / 5 + 32).map("{:.3f}".format)
    table.to_csv(log, index=False)
    proc = _thermaxis("check", str(ds))
    assert proc.returncode == 0, proc.stderr
    median_f = float(np.median(np.round(celsius.to_numpy() * 9 / 5 + 32, 3)))
    assert (
        f"thermaxis warning: {log}: sensor T3: median {median_f:.1f} °C is outside the plausible "
        f"5-60 °C of a machine structure (config temperatures.plausible_median_c); if it is in "
        f"°F, that is {(median_f - 32) * 5 / 9:.1f} °C: expected °C"
    ) in proc.stderr


def test_every_subcommand_has_help_with_examples(capsys):
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert sorted(sub.choices) == ["check", "compensate", "import", "report", "run", "sweep"]
    for name, parser in sub.choices.items():
        assert parser.epilog.startswith("examples:\n  thermaxis "), name


def test_run_outside_a_checkout_says_where_to_run_it(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "data/raw/twin"]) == 1
    assert "no Snakefile; run it in a thermaxis checkout" in capsys.readouterr().err


def test_import_prints_the_run_summary_and_the_unit_warning(tmp_path, capsys):
    from test_importer_exports import _mapping

    mapping = _mapping(tmp_path, {"column": "minutes", "start": "2030-01-01T08:00:00"})
    assert main(["import", str(mapping), "--out", str(tmp_path / "raw")]) == 0
    out, err = capsys.readouterr()
    assert f"rig_X: 3 runs in {tmp_path / 'raw' / 'rig_X'}" in out
    assert re.search(r"^  A +6 min +181 samples +1 measurements$", out, re.MULTILINE)
    assert (
        "thermaxis warning: rig_X: run(s) A, B, C last 6 min" in err and "set time.unit: min" in err
    )
    assert "[1/1] table" not in err  # files: one progress line per table read
    assert "[3/3] tables read" in err


def test_progress_is_a_bar_on_a_terminal_and_lines_elsewhere(tmp_path):
    class Stream(list):
        def write(self, text):
            self.append(text)

        def flush(self):
            pass

    lines, bar = Stream(), Stream()
    ProgressBar(lines, tty=False)(2, 4, "batch")
    assert lines == ["[2/4] batch\n"]
    ProgressBar(bar, tty=True)(2, 4, "batch")
    assert bar[0].startswith("\r[" + "#" * 15 + "." * 15 + "] 2/4 batch")


WRAPPER = [
    sys.executable,
    "-m",
    "thermaxis.pipeline.resume",
    str(Path(sys.executable).with_name("snakemake")),
]


@pytest.fixture
def started(monkeypatch):
    """The commands the CLI would start, and the summary and answers it would write."""
    import thermaxis.cli as cli
    from thermaxis.reports import answer, crossdataset

    started = []
    monkeypatch.chdir(REPO)
    monkeypatch.setattr(cli, "_wrapped", lambda command: started.append(command) or 0)
    monkeypatch.setattr(crossdataset, "main", lambda argv: started.append(["summary", *argv]) or 0)
    monkeypatch.setattr(answer, "main", lambda argv: started.append(["answers", *argv]) or 0)
    return started


def test_run_goes_through_the_recovery_wrapper_quietly_then_summary_then_answers(started):
    assert main(["run", "data/raw/twin", "data/raw/fl_thermal", "--cores", "1", "--", "-F"]) == 0
    assert started == [
        [*WRAPPER, "--cores", "1", "--logger=rich", "-F", "--config", "dataset=data/raw/twin"],
        [*WRAPPER, "--cores", "1", "--logger=rich", "-F", "--config", "dataset=data/raw/fl_thermal"],
        # every dataset under results/, not only those just run; the answers last
        ["summary", "--results", "results"],
        ["answers", "results/twin", "results/fl_thermal"],
    ]  # fmt: skip


def test_verbose_gives_snakemakes_own_output_and_a_dry_run_writes_nothing(started):
    assert main(["run", "data/raw/twin", "--verbose", "--", "-n"]) == 0
    assert started == [
        [*WRAPPER, "--cores", "all", "--printshellcmds", "-n", "--config", "dataset=data/raw/twin"]
    ]


def test_sweep_and_report_put_their_targets_after_the_options(started):
    """A target right after ``--logger rich`` was read as a second logger (issue 62)."""
    assert main(["sweep", "data/raw/twin", "--cores", "2"]) == 0
    assert main(["report", "data/raw/twin", "--zip", "--cores", "2"]) == 0
    sweep = [*WRAPPER, "--cores", "2", "--logger=rich", "--config", "dataset=data/raw/twin"]
    report = [*sweep, "--report", "results/twin/report.zip"]
    assert started[0] == [*sweep, "--", "sweep"]
    assert started[-2:] == [report, ["answers", "results/twin"]]
    # As Snakemake's own parser reads them: one logger, the target a target.
    from snakemake.cli import get_argument_parser

    parsed = get_argument_parser().parse_args(started[0][len(WRAPPER) :])
    assert (parsed.logger, parsed.targets, parsed.config) == (
        ["rich"],
        ["sweep"],
        ["dataset=data/raw/twin"],
    )
    parsed = get_argument_parser().parse_args(report[len(WRAPPER) :])
    assert (parsed.logger, str(parsed.report), parsed.targets) == (
        ["rich"],
        "results/twin/report.zip",
        set(),
    )


def test_two_datasets_of_one_name_are_refused_before_either_runs(started, tmp_path, capsys):
    """Each writes results/<name>/: the second would silently replace the first's results."""
    copy = tmp_path / "twin_again"
    shutil.copytree(REPO / "data/raw/twin", copy)
    for command in ("run", "report"):
        assert main([command, "data/raw/twin", str(copy)]) == 1
        err = capsys.readouterr().err.splitlines()
        assert err == [
            f"thermaxis error: {copy}: dataset name 'twin' (its dataset.yaml) is "
            "data/raw/twin's too, and both would write results/twin; give one of them "
            "another name"
        ]
    assert main(["run", "data/raw/twin", "data/raw/twin/"]) == 1
    assert capsys.readouterr().err == "thermaxis error: data/raw/twin/: listed twice\n"
    assert started == []


def test_snakemake_arguments_are_refused_where_no_snakemake_runs():
    with pytest.raises(SystemExit) as info:
        main(["check", "data/raw/twin", "--", "-n"])
    assert info.value.code == 2


def test_a_semicolon_separated_controller_log_is_refused_naming_the_expected_separator(tmp_path):
    from thermaxis.cli.compensate import read_log
    from thermaxis.errors import DataError

    log = tmp_path / "log.csv"
    log.write_text("time_s;T1\n0;20,5\n60;20,7\n")
    with pytest.raises(DataError) as refused:
        read_log(log, ["T1"])
    # No import mapping here: the message names the log's own format, not a mapping's setting.
    assert str(refused.value) == (
        f"{log}: one column 'time_s;T1': looks ';'-separated; expected ',' between columns"
    )


def test_a_controller_log_without_a_sensor_of_the_model_names_it_as_the_models(tmp_path):
    from thermaxis.cli.compensate import read_log
    from thermaxis.errors import DataError

    log = tmp_path / "log.csv"
    log.write_text("time_s,T1\n0,20.5\n60,20.7\n")
    with pytest.raises(DataError) as refused:
        read_log(log, ["T1", "T2"])
    assert str(refused.value) == (
        f"{log}: missing column 'T2', a sensor the model reads; expected one column per sensor "
        "of the model (T1, T2)"
    )


@pytest.mark.parametrize("cores", ["0", "-3", "2.5", "many"])
def test_a_core_count_snakemake_cannot_run_with_is_refused_before_it_starts(cores, capsys):
    with pytest.raises(SystemExit) as info:
        main(["run", "data/raw/twin", "--cores", cores])
    assert info.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"thermaxis run: error: argument --cores: expected 'all' or a whole number of cores "
        f"from 1, got {cores!r}"
    )
