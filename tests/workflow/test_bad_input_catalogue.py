"""The bad-input catalogue: hostile and broken datasets and config values.

Each case copies a two-run cut of the twin and breaks one thing. Every refusal must be
ONE ``thermaxis error:`` line naming the offending file (and line or column where one
exists), without a traceback, without a hang, without a partial output and without a
file written outside ``results/<dataset>/``, ``logs/`` and ``benchmarks/``. Legitimate
oddities must pass, implausible values must warn.

``test_bad_input`` runs every case in-process, the way the workflow does: the parse-time
gate, :mod:`thermaxis.pipeline.preflight` (``check_before_jobs``, the first call of
common.smk; the workflow parsed in-process, which ends with ``check_rules``; for the
sweep ``sweep_plan``), then the scripts of the rules up to the first one that must
refuse (the case's target). Which script a rule runs and what it hands the script
(input, output, params, log, wildcards) come from the workflow Snakemake parsed with the
case's config. ``test_bad_input_end_to_end`` runs a representative set (``END_TO_END``)
through Snakemake itself, then in-process with every check of ``test_bad_input`` (which
leaves those cases to it), and checks that both print the very same line.

With ``THERMAXIS_CATALOGUE=<folder>`` each case also writes its message there;
``PYTHONPATH=tests python tests/workflow/test_bad_input_catalogue.py <folder> tests/workflow/CATALOGUE.md``
lists them (``THERMAXIS_CATALOGUE=<folder> pytest tests/workflow/test_bad_input_catalogue.py``
fills the folder).
"""

from __future__ import annotations

import json
import logging
import os
import re
import runpy
import shutil
import signal
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

from helpers import REPO
from helpers.workflow import run_snakemake, workflow_workdir
from thermaxis.config import merge
from thermaxis.pipeline import preflight

TWIN = REPO / "data" / "raw" / "twin"
NAME = "cut"
# A hang is a failure: far above the slowest case (a few seconds).
TIMEOUT_S = 120


@dataclass(frozen=True)
class Case:
    id: str
    break_it: Callable  # (dataset folder, work folder) -> config overrides (dict) or None
    expect: str  # substring of the message (regex when it starts with "re:")
    file: str | None = None  # offending file, relative to the dataset ("" = the dataset folder)
    line: int | None = None
    target: str = "parse"  # "parse", "summary", "clean:<run>", "assemble", "select:<fold>", "sweep"
    fails: bool = True
    config: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- #
# editing helpers
# --------------------------------------------------------------------------- #
def _remove_csv_files(folder: Path) -> None:
    for path in folder.glob("*.csv"):
        path.unlink()


def _text(path: Path, old: str, new: str, count: int = 1) -> None:
    text = path.read_text(encoding="utf-8")
    assert old in text, f"{old!r} not in {path}"
    path.write_text(text.replace(old, new, count), encoding="utf-8")


def _meta(ds: Path, edit) -> None:
    meta = yaml.safe_load((ds / "dataset.yaml").read_text(encoding="utf-8"))
    edit(meta)
    (ds / "dataset.yaml").write_text(yaml.safe_dump(meta, sort_keys=False), encoding="utf-8")


def _yaml_text(ds: Path, text: str) -> None:
    (ds / "dataset.yaml").write_text(text, encoding="utf-8")


def _lines(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()


def _write_lines(path: Path, lines: list[str]) -> None:
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _start_at(path: Path, time: str) -> None:
    """Drop a log's rows before ``time`` (ISO 8601, as the log writes it)."""
    lines = _lines(path)
    _write_lines(path, lines[:1] + [line for line in lines[1:] if line.split(",")[0] >= time])


def _cell(path: Path, line: int, column: str, value: str) -> None:
    """Set one cell (``line`` 1-based, header = 1) of a comma-separated file."""
    lines = _lines(path)
    header = lines[0].split(",")
    fields = lines[line - 1].split(",")
    fields[header.index(column)] = value
    lines[line - 1] = ",".join(fields)
    _write_lines(path, lines)


def _column(path: Path, column: str, value: Callable[[float], str]) -> None:
    lines = _lines(path)
    header = lines[0].split(",")
    i = header.index(column)
    out = [lines[0]]
    for line in lines[1:]:
        fields = line.split(",")
        if fields[i]:
            fields[i] = value(float(fields[i]))
        out.append(",".join(fields))
    _write_lines(path, out)


def _fifo(path: Path) -> None:
    path.unlink(missing_ok=True)
    os.mkfifo(path)


def _runs_row(ds: Path, run: str, column: str, value: str) -> None:
    lines = _lines(ds / "runs.tsv")
    header = lines[0].split("\t")
    for k, line in enumerate(lines):
        fields = line.split("\t")
        if fields[0] == run:
            fields[header.index(column)] = value
            lines[k] = "\t".join(fields)
    _write_lines(ds / "runs.tsv", lines)


def _link_outside(ds: Path, rel: str) -> None:
    """Replace a file or folder of the dataset by a symlink to the twin's (outside the dataset)."""
    shutil.rmtree(ds / rel) if (ds / rel).is_dir() else (ds / rel).unlink()
    os.symlink(TWIN / rel, ds / rel)


def _rename_run(ds: Path, old: str, new: str) -> None:
    _runs_row(ds, old, "run", new)


E1_M01 = "E1/errors/M01.csv"
E2_M03 = "E2/errors/M03.csv"
E2_BOX = "E2/temperatures/box.csv"
E2_HMI = "E2/temperatures/hmi.csv"


BILLION_LAUGHS = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(8)
)


def _dataset_with(extra: str) -> Callable:
    def edit(ds, work):
        _yaml_text(
            ds,
            (TWIN / "dataset.yaml")
            .read_text(encoding="utf-8")
            .replace("name: twin", f"name: {NAME}")
            + extra,
        )

    return edit


CASES = [
    # ---- names that could escape the results folder -------------------------------
    Case(
        "name_dotdot",
        lambda ds, w: _meta(ds, lambda m: m.update(name="..")),
        "name: '..'",
        "dataset.yaml",
    ),
    Case(
        "name_dot",
        lambda ds, w: _meta(ds, lambda m: m.update(name=".")),
        "name: '.'",
        "dataset.yaml",
    ),
    Case(
        "name_slash",
        lambda ds, w: _meta(ds, lambda m: m.update(name="a/../../b")),
        "name: 'a/../../b'",
        "dataset.yaml",
    ),
    Case(
        "name_leading_dash",
        lambda ds, w: _meta(ds, lambda m: m.update(name="-rf")),
        "name: '-rf'",
        "dataset.yaml",
    ),
    Case(
        "name_absolute",
        lambda ds, w: _meta(ds, lambda m: m.update(name="/tmp/x")),
        "name: '/tmp/x'",
        "dataset.yaml",
    ),
    Case(
        "name_trailing_newline",
        lambda ds, w: _meta(ds, lambda m: m.update(name="x\n")),
        "dataset name 'x\\n' is not a safe name",
        "dataset.yaml",
    ),
    Case(
        "first_error_non_utf8_late",
        lambda ds, w: (ds / E1_M01).write_bytes(
            (ds / E1_M01).read_bytes() + b"x" * 70000 + b"\xff\n"
        ),
        "byte 0xff is not UTF-8",
        E1_M01,
    ),
    Case(
        "name_empty",
        lambda ds, w: _meta(ds, lambda m: m.update(name="")),
        "name: ''",
        "dataset.yaml",
    ),
    Case("run_dotdot", lambda ds, w: _rename_run(ds, "E2", ".."), "column 'run'", "runs.tsv", 3),
    Case(
        "run_slash",
        lambda ds, w: _rename_run(ds, "E2", "E2/../../x"),
        "column 'run'",
        "runs.tsv",
        3,
    ),
    Case(
        "run_leading_dash",
        lambda ds, w: _rename_run(ds, "E2", "-E2"),
        "column 'run'",
        "runs.tsv",
        3,
    ),
    Case(
        "sensor_id_slash",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(id="T1/x")),
        "sensors/0/id",
        "dataset.yaml",
    ),
    Case(
        "sensor_id_dotdot",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(id="..")),
        "sensors/0/id",
        "dataset.yaml",
    ),
    Case(
        "source_name_dotdot",
        lambda ds, w: _meta(ds, lambda m: m["sources"][0].update(name="..")),
        "sources/0/name",
        "dataset.yaml",
    ),
    Case(
        "sensor_source_slash",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(source="../box")),
        "sensors/0/source",
        "dataset.yaml",
    ),
    Case(
        "measurement_leading_dash",
        lambda ds, w: (ds / "E2/errors/M03.csv").rename(ds / "E2/errors/-M03.csv"),
        "measurement '-M03' is not a safe name",
        "E2/errors/-M03.csv",
        target="clean:E2",
    ),
    Case(
        "measurement_hidden",
        lambda ds, w: shutil.copy(ds / E2_M03, ds / "E2/errors/.M09.csv"),
        "measurement '.M09' is not a safe name",
        "E2/errors/.M09.csv",
        target="clean:E2",
    ),
    Case(
        "measurement_symlink_outside",
        lambda ds, w: _link_outside(ds, E2_M03),
        "file resolves to",
        E2_M03,
        target="clean:E2",
    ),
    Case(
        "temperature_symlink_outside",
        lambda ds, w: _link_outside(ds, E2_HMI),
        "file resolves to",
        E2_HMI,
        target="clean:E2",
    ),
    Case(
        "run_folder_symlink_outside",
        lambda ds, w: _link_outside(ds, "E2"),
        "run folder resolves to",
        "E2",
        target="clean:E2",
    ),
    # ---- dataset.yaml ------------------------------------------------------------------
    Case(
        "yaml_duplicate_key",
        _dataset_with("name: elsewhere\n"),
        "duplicate key 'name' (first on line 2)",
        "dataset.yaml",
    ),
    Case(
        "yaml_alias_bomb",
        lambda ds, w: _yaml_text(ds, BILLION_LAUGHS),
        "aliases are not allowed",
        "dataset.yaml",
        2,
    ),
    Case(
        "yaml_merge_key",
        _dataset_with("defaults: &d {a: 1}\nother:\n  <<: *d\n"),
        "aliases are not allowed",
        "dataset.yaml",
    ),
    Case(
        "yaml_python_tag",
        _dataset_with("pwn: !!python/object/apply:os.system ['touch pwned']\n"),
        "could not determine a constructor",
        "dataset.yaml",
    ),
    Case(
        "yaml_not_mapping",
        lambda ds, w: _yaml_text(ds, "- a\n- b\n"),
        "expected a mapping",
        "dataset.yaml",
    ),
    Case(
        "yaml_syntax",
        lambda ds, w: _yaml_text(ds, "name: [unclosed\n"),
        "not valid YAML",
        "dataset.yaml",
    ),
    Case(
        "yaml_deep_nesting",
        lambda ds, w: _yaml_text(ds, "a: " + "[" * 50000 + "]" * 50000 + "\n"),
        "nested too deeply",
        "dataset.yaml",
    ),
    Case(
        "yaml_too_large",
        _dataset_with("pad: '" + "x" * (1 << 20) + "'\n"),
        "larger than the limit",
        "dataset.yaml",
    ),
    Case(
        "yaml_utf16",
        lambda ds, w: (ds / "dataset.yaml").write_bytes(
            (TWIN / "dataset.yaml").read_text(encoding="utf-8").encode("utf-16")
        ),
        "looks UTF-16-encoded",
        "dataset.yaml",
    ),
    Case(
        "yaml_not_utf8",
        lambda ds, w: (ds / "dataset.yaml").write_bytes(b"name: caf\xe9\n"),
        "line 1: byte 0xe9 is not UTF-8",
        "dataset.yaml",
    ),
    Case(
        "yaml_fifo",
        lambda ds, w: _fifo(ds / "dataset.yaml"),
        "not a regular file (a FIFO)",
        "dataset.yaml",
    ),
    Case(
        "yaml_directory",
        lambda ds, w: ((ds / "dataset.yaml").unlink(), (ds / "dataset.yaml").mkdir()),
        "not a regular file (a directory)",
        "dataset.yaml",
    ),
    Case(
        "yaml_missing",
        lambda ds, w: (ds / "dataset.yaml").unlink(),
        "file not found",
        "dataset.yaml",
    ),
    Case(
        "yaml_sensor_id_integer",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(id=1)),
        "sensors/0/id: 1 is not of type 'string'",
        "dataset.yaml",
    ),
    Case(
        "sensor_id_reserved_time",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(id="time")),
        "sensors/0/id",
        "dataset.yaml",
    ),
    Case(
        "sensor_id_reserved_run",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(id="run")),
        "sensors/0/id",
        "dataset.yaml",
    ),
    Case(
        "yaml_duplicate_sensor",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][1].update(id="T1")),
        "declared more than once",
        "dataset.yaml",
    ),
    Case(
        "yaml_undeclared_source",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(source="nowhere")),
        "is not one of the declared sources",
        "dataset.yaml",
    ),
    Case(
        "yaml_bad_kind",
        lambda ds, w: _meta(ds, lambda m: m["provenance"].update(kind="guessed")),
        "provenance/kind",
        "dataset.yaml",
    ),
    Case(
        "yaml_clock_offset_inf",
        lambda ds, w: _meta(ds, lambda m: m["sources"][0].update(clock_offset_s=float("inf"))),
        "sources/0/clock_offset_s: expected a finite number",
        "dataset.yaml",
    ),
    Case(
        "yaml_clock_offset_huge",
        lambda ds, w: _meta(ds, lambda m: m["sources"][0].update(clock_offset_s=1e12)),
        "sources/0/clock_offset_s: 1000000000000.0 is greater than the maximum",
        "dataset.yaml",
    ),
    Case(
        "yaml_clock_offset_text",
        lambda ds, w: _meta(ds, lambda m: m["sources"][0].update(clock_offset_s="ten")),
        "sources/0/clock_offset_s",
        "dataset.yaml",
    ),
    Case(
        "yaml_list_property",
        lambda ds, w: _meta(ds, lambda m: m["sensors"][0].update(tags=["a", "b"])),
        "",
        target="summary",
        fails=False,
    ),
    # ---- runs.tsv -----------------------------------------------------------------------
    Case(
        "runs_utf8_bom",
        lambda ds, w: (ds / "runs.tsv").write_bytes(
            b"\xef\xbb\xbf" + (ds / "runs.tsv").read_bytes()
        ),
        "",
        target="summary",
        fails=False,
    ),
    Case(
        "runs_utf16",
        lambda ds, w: (ds / "runs.tsv").write_bytes(
            (ds / "runs.tsv").read_text(encoding="utf-8").encode("utf-16")
        ),
        "looks UTF-16-encoded",
        "runs.tsv",
    ),
    Case(
        "runs_comma_separated",
        lambda ds, w: _text(
            ds / "runs.tsv",
            "run\tcondition\tfeed_mm_min\tdescription",
            "run,condition,feed_mm_min,description",
        ),
        "line 1: looks comma-separated; expected tab-separated",
        "runs.tsv",
        1,
    ),
    Case(
        "runs_semicolon_separated",
        lambda ds, w: _write_lines(
            ds / "runs.tsv", [line.replace("\t", ";") for line in _lines(ds / "runs.tsv")]
        ),
        "looks semicolon-separated",
        "runs.tsv",
        1,
    ),
    Case(
        "runs_feed_inf",
        lambda ds, w: _runs_row(ds, "E2", "feed_mm_min", "inf"),
        "column 'feed_mm_min': expected a finite number, got 'inf'",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_feed_text",
        lambda ds, w: _runs_row(ds, "E2", "feed_mm_min", "x"),
        "column 'feed_mm_min': expected a finite number, got 'x'",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_feed_nan",
        lambda ds, w: _runs_row(ds, "E2", "feed_mm_min", "nan"),
        "column 'feed_mm_min': expected a finite number",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_feed_huge",
        lambda ds, w: _runs_row(ds, "E2", "feed_mm_min", "1e999"),
        "column 'feed_mm_min': expected a finite number",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_feed_negative",
        lambda ds, w: _runs_row(ds, "E2", "feed_mm_min", "-5"),
        "column 'feed_mm_min'",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_condition_empty",
        lambda ds, w: _runs_row(ds, "E2", "condition", ""),
        "column 'condition'",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_condition_label",
        lambda ds, w: _runs_row(ds, "E2", "condition", "warm start, 4000 mm/min"),
        "",
        fails=False,
    ),
    Case(
        "runs_missing_column",
        lambda ds, w: _write_lines(
            ds / "runs.tsv",
            [
                "\t".join(line.split("\t")[:1] + line.split("\t")[2:])
                for line in _lines(ds / "runs.tsv")
            ],
        ),
        "missing column 'condition'",
        "runs.tsv",
    ),
    Case(
        "runs_duplicate_run",
        lambda ds, w: _write_lines(
            ds / "runs.tsv", _lines(ds / "runs.tsv") + [_lines(ds / "runs.tsv")[1]]
        ),
        "listed more than once",
        "runs.tsv",
    ),
    Case(
        "runs_description_too_long",
        lambda ds, w: _write_lines(
            ds / "runs.tsv",
            _lines(ds / "runs.tsv")[:2] + [_lines(ds / "runs.tsv")[2] + "x" * 200_000],
        ),
        "line 3: field larger than field limit (131072); expected short tab-separated fields",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_field_count",
        lambda ds, w: _write_lines(
            ds / "runs.tsv", _lines(ds / "runs.tsv")[:2] + [_lines(ds / "runs.tsv")[2] + "\textra"]
        ),
        "line 3: 5 tab-separated fields but the header has 4; expected 4 fields (run, condition, "
        "feed_mm_min, description): a tab inside a text (a description?) is the likely cause",
        "runs.tsv",
        3,
    ),
    Case(
        "runs_unlisted_folder",
        lambda ds, w: shutil.copytree(TWIN / "E3", ds / "E3"),
        "run folder is not listed",
        "E3",
    ),
    Case(
        "runs_missing_folder",
        lambda ds, w: shutil.rmtree(ds / "E2"),
        "run 'E2' has no folder",
        "runs.tsv",
    ),
    Case(
        "runs_empty",
        lambda ds, w: (ds / "runs.tsv").write_text(""),
        "line 1: empty header",
        "runs.tsv",
    ),
    Case(
        "runs_fifo", lambda ds, w: _fifo(ds / "runs.tsv"), "not a regular file (a FIFO)", "runs.tsv"
    ),
    Case(
        "runs_too_large",
        lambda ds, w: (ds / "runs.tsv").write_text((ds / "runs.tsv").read_text() + "#" * (1 << 20)),
        "larger than the limit",
        "runs.tsv",
    ),
    Case(
        "runs_not_utf8",
        lambda ds, w: (ds / "runs.tsv").write_bytes(
            (ds / "runs.tsv").read_bytes().replace(b"reciprocating", b"r\xe9ciprocating", 1)
        ),
        "line 2: byte 0xe9 is not UTF-8",
        "runs.tsv",
        2,
    ),
    Case(
        "runs_single_run",
        lambda ds, w: (
            _write_lines(ds / "runs.tsv", _lines(ds / "runs.tsv")[:2]),
            shutil.rmtree(ds / "E2"),
        ),
        "leave-one-condition-out needs at least 2 runs",
        "runs.tsv",
    ),
    # ---- the first error file, read when the workflow is parsed -------------------------
    Case(
        "first_error_no_position",
        lambda ds, w: _text(ds / E1_M01, "position_mm", "pos"),
        "missing column 'position_mm'",
        E1_M01,
    ),
    Case(
        "first_error_semicolon",
        lambda ds, w: _write_lines(
            ds / E1_M01, [line.replace(",", ";") for line in _lines(ds / E1_M01)]
        ),
        "line 1: looks semicolon-separated",
        E1_M01,
        1,
    ),
    Case("first_error_empty", lambda ds, w: (ds / E1_M01).write_text(""), "empty file", E1_M01),
    Case(
        "first_error_header_only",
        lambda ds, w: _write_lines(ds / E1_M01, _lines(ds / E1_M01)[:1]),
        "no data rows",
        E1_M01,
    ),
    Case(
        "first_error_fifo", lambda ds, w: _fifo(ds / E1_M01), "not a regular file (a FIFO)", E1_M01
    ),
    Case(
        "first_error_binary",
        lambda ds, w: (ds / E1_M01).write_bytes(bytes(range(256)) * 4),
        "not UTF-8",
        E1_M01,
    ),
    Case(
        "first_error_decimal_comma",
        lambda ds, w: _column(ds / E1_M01, "error_um", lambda v: f"{v:.3f}".replace(".", ",")),
        "looks like decimal commas",
        E1_M01,
        2,
    ),
    # ---- interferometer readings ------------------------------------------------------
    Case(
        "error_huge",
        lambda ds, w: _cell(ds / E2_M03, 5, "error_um", "1e30"),
        "beyond the plausible ±1000 um",
        E2_M03,
        5,
        "clean:E2",
    ),
    Case(
        "error_beyond_1mm",
        lambda ds, w: _cell(ds / E2_M03, 6, "error_um", "-1500"),
        "beyond the plausible ±1000 um",
        E2_M03,
        6,
        "clean:E2",
    ),
    Case(
        "error_bound_configurable",
        lambda ds, w: _cell(ds / E2_M03, 6, "error_um", "150"),
        "beyond the plausible ±100 um",
        E2_M03,
        6,
        "clean:E2",
        config={"errors": {"max_abs_error_um": 100}},
    ),
    Case(
        "error_inf",
        lambda ds, w: _cell(ds / E2_M03, 4, "error_um", "inf"),
        "column 'error_um': expected a number, got 'inf'",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_minus_inf",
        lambda ds, w: _cell(ds / E2_M03, 4, "error_um", "-Infinity"),
        "column 'error_um': expected a number",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_nan",
        lambda ds, w: _cell(ds / E2_M03, 4, "error_um", "NaN"),
        "column 'error_um': expected a number, got 'NaN'",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_empty_cell",
        lambda ds, w: _cell(ds / E2_M03, 4, "error_um", ""),
        "column 'error_um': expected a number",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_text",
        lambda ds, w: _cell(ds / E2_M03, 4, "error_um", "n/a"),
        "column 'error_um': expected a number, got 'n/a'",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_line_cut_short",
        lambda ds, w: _write_lines(
            ds / E2_M03,
            _lines(ds / E2_M03)[:3]
            + [_lines(ds / E2_M03)[3].rsplit(",", 2)[0]]
            + _lines(ds / E2_M03)[4:],
        ),
        "line 4: 2 comma-separated fields but the header has 4; expected 4 fields (time, "
        "position_mm, error_um, direction), an empty one for a missing value",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "position_text",
        lambda ds, w: _cell(ds / E2_M03, 3, "position_mm", "x"),
        "column 'position_mm': expected a number",
        E2_M03,
        3,
        "clean:E2",
    ),
    Case(
        "position_inf",
        lambda ds, w: _cell(ds / E2_M03, 3, "position_mm", "inf"),
        "column 'position_mm': expected a number",
        E2_M03,
        3,
        "clean:E2",
    ),
    Case(
        "position_huge",
        lambda ds, w: _cell(ds / E2_M03, 3, "position_mm", "1e308"),
        "expected a position within ±1e+06 mm, got 1e+308",
        E2_M03,
        3,
        "clean:E2",
    ),
    Case(
        "error_time_year_9999",
        lambda ds, w: _cell(ds / E2_M03, 5, "time", "9999-03-15T13:51:21"),
        "expected a time between 1678 and 2261",
        E2_M03,
        5,
        "clean:E2",
    ),
    Case(
        "first_error_time_year_1066",
        lambda ds, w: _cell(ds / E1_M01, 2, "time", "1066-10-14T09:00:00"),
        "line 2, column 'time': expected a time between 1678 and 2261",
        E1_M01,
        2,
    ),
    Case(
        "error_time_bad",
        lambda ds, w: _cell(ds / E2_M03, 4, "time", "yesterday"),
        "column 'time': expected an ISO 8601 time",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_time_backwards",
        lambda ds, w: _cell(ds / E2_M03, 4, "time", "2000-01-01T00:00:00"),
        "time goes backwards",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_mixed_time_zones",
        lambda ds, w: _cell(
            ds / E2_M03, 4, "time", _lines(ds / E2_M03)[3].split(",")[0] + "+02:00"
        ),
        "expected a time without a time zone",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_time_zone_z",
        lambda ds, w: _cell(ds / E2_M03, 2, "time", _lines(ds / E2_M03)[1].split(",")[0] + "Z"),
        "expected a time without a time zone",
        E2_M03,
        2,
        "clean:E2",
    ),
    Case(
        "error_direction_bad",
        lambda ds, w: _cell(ds / E2_M03, 4, "direction", "forward"),
        "column 'direction': expected '+' or '-'",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_conflicting_repeat",
        lambda ds, w: _write_lines(
            ds / E2_M03,
            _lines(ds / E2_M03)
            + [_lines(ds / E2_M03)[-1].replace(",+", ",-").rsplit(",", 2)[0] + ",9.9,+"],
        ),
        "appears twice",
        E2_M03,
        target="clean:E2",
    ),
    Case(
        "error_extra_field",
        lambda ds, w: _write_lines(
            ds / E2_M03,
            _lines(ds / E2_M03)[:3] + [_lines(ds / E2_M03)[3] + ",x"] + _lines(ds / E2_M03)[4:],
        ),
        "re:line 4: 5 comma-separated fields but the header has 4; expected 4 fields "
        "\\(time, position_mm, error_um, direction\\)$",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        # pandas reads a field of any length; Python's csv module, which looks for lines
        # cut short, stops at 131,072 characters.
        "error_field_too_long",
        lambda ds, w: _write_lines(
            ds / E2_M03, _lines(ds / E2_M03)[:3] + ["x" * 200_000] + _lines(ds / E2_M03)[3:]
        ),
        "line 4: field larger than field limit (131072); expected short comma-separated fields",
        E2_M03,
        4,
        "clean:E2",
    ),
    Case(
        "error_positions_differ",
        lambda ds, w: [
            _column(p, "position_mm", lambda v: f"{v + 1:g}")
            for p in (ds / "E2/errors").glob("*.csv")
        ],
        "expected the same targets in every run",
        "E2/errors",
        target="assemble",
    ),
    Case(
        "error_decimal_comma",
        lambda ds, w: _column(ds / E2_M03, "error_um", lambda v: f"{v:.3f}".replace(".", ",")),
        "looks like decimal commas",
        E2_M03,
        2,
        "clean:E2",
    ),
    Case(
        "error_semicolon",
        lambda ds, w: _write_lines(
            ds / E2_M03, [line.replace(",", ";") for line in _lines(ds / E2_M03)]
        ),
        "looks semicolon-separated",
        E2_M03,
        1,
        "clean:E2",
    ),
    Case(
        "error_utf16",
        lambda ds, w: (ds / E2_M03).write_bytes((ds / E2_M03).read_text().encode("utf-16")),
        "looks UTF-16-encoded",
        E2_M03,
        target="clean:E2",
    ),
    Case(
        "error_fifo",
        lambda ds, w: _fifo(ds / E2_M03),
        "not a regular file (a FIFO)",
        E2_M03,
        target="clean:E2",
    ),
    Case(
        "error_directory",
        lambda ds, w: (ds / "E2/errors/M09.csv").mkdir(),
        "not a regular file (a directory)",
        "E2/errors/M09.csv",
        target="clean:E2",
    ),
    Case(
        "error_copied_measurement",
        lambda ds, w: shutil.copy(ds / E2_M03, ds / "E2/errors/M09.csv"),
        "overlap measurement M03",
        "E2/errors/M09.csv",
        target="clean:E2",
    ),
    Case(
        "error_symlink_loop",
        lambda ds, w: os.symlink("M09.csv", ds / "E2/errors/M09.csv"),
        "cannot be read",
        "E2/errors/M09.csv",
    ),
    Case(
        "error_dangling_symlink",
        lambda ds, w: os.symlink("nowhere.csv", ds / "E2/errors/M09.csv"),
        "data file not found",
        "E2/errors/M09.csv",
    ),
    Case(
        "error_device",
        lambda ds, w: os.symlink("/dev/zero", ds / "E2/errors/M09.csv"),
        "outside",
        "E2/errors/M09.csv",
    ),
    Case(
        "error_no_files",
        lambda ds, w: _remove_csv_files(ds / "E2/errors"),
        "0 measurement(s)",
        "E2/errors",
        target="clean:E2",
    ),
    Case(
        "one_measurement_per_run",
        lambda ds, w: [
            p.unlink() for p in sorted(ds.glob("E*/errors/*.csv")) if p.name != "M01.csv"
        ],
        "one measurement per run",
        "",
    ),
    # ---- temperature logs -------------------------------------------------------------
    Case(
        "temp_semicolon",
        lambda ds, w: _write_lines(
            ds / E2_BOX, [line.replace(",", ";") for line in _lines(ds / E2_BOX)]
        ),
        "looks semicolon-separated",
        E2_BOX,
        1,
        "clean:E2",
    ),
    Case(
        "temp_decimal_comma",
        lambda ds, w: _column(ds / E2_BOX, "T3", lambda v: f"{v:.3f}".replace(".", ",")),
        "looks like decimal commas",
        E2_BOX,
        2,
        "clean:E2",
    ),
    Case(
        "temp_missing_time",
        lambda ds, w: _text(ds / E2_BOX, "time,", "stamp,"),
        "missing column 'time'",
        E2_BOX,
        target="clean:E2",
    ),
    Case(
        "temp_unknown_sensor",
        lambda ds, w: _text(ds / E2_BOX, ",T3,", ",T99,"),
        "column 'T99': unknown sensor id",
        E2_BOX,
        target="clean:E2",
    ),
    Case(
        "temp_value_text",
        lambda ds, w: _cell(ds / E2_BOX, 7, "T3", "hot"),
        "line 7, column 'T3': expected a number, got 'hot'",
        E2_BOX,
        7,
        "clean:E2",
    ),
    Case(
        # A logger stopped mid-write: its missing fields are missing samples, said so.
        "temp_line_cut_short",
        lambda ds, w: _write_lines(
            ds / E2_BOX,
            _lines(ds / E2_BOX)[:6] + [_lines(ds / E2_BOX)[6][:25]] + _lines(ds / E2_BOX)[7:],
        ),
        "line 7: 2 comma-separated fields but the header has 11; a line cut short? Its missing "
        "fields are read as missing samples",
        E2_BOX,
        target="clean:E2",
        fails=False,
    ),
    Case(
        "temp_value_inf",
        lambda ds, w: _cell(ds / E2_BOX, 7, "T3", "inf"),
        "line 7, column 'T3': expected a number, got 'inf'",
        E2_BOX,
        7,
        "clean:E2",
    ),
    Case(
        "temp_mixed_time_zones",
        lambda ds, w: _cell(ds / E2_BOX, 9, "time", _lines(ds / E2_BOX)[8].split(",")[0] + "Z"),
        "expected a time without a time zone",
        E2_BOX,
        9,
        "clean:E2",
    ),
    Case(
        "temp_sensor_all_empty",
        lambda ds, w: _column(ds / E2_BOX, "T3", lambda v: ""),
        "T3",
        "E2/temperatures",
        target="clean:E2",
        # One sensor is unusable in E2: it leaves the candidates, not the dataset.
        fails=False,
    ),
    Case(
        "temp_sensor_column_missing",
        lambda ds, w: _write_lines(
            ds / E2_BOX,
            [
                ",".join(f for j, f in enumerate(line.split(",")) if j != 3)
                for line in _lines(ds / E2_BOX)
            ],
        ),
        "sensor T3 has no valid reading at all (no column",
        "E2/temperatures",
        target="clean:E2",
        # A declared sensor without a column in one run: it leaves that run's folds, as an
        # empty column does, not the dataset.
        fails=False,
    ),
    Case(
        "temp_duplicate_column",
        lambda ds, w: _text(ds / E2_BOX, ",T3,", ",T2,"),
        "line 1: column 'T2' appears twice",
        E2_BOX,
        1,
        "clean:E2",
    ),
    Case(
        "temp_unnamed_column",
        lambda ds, w: _text(ds / E2_BOX, ",T3,", ",,"),
        "line 1: column 4 has no name",
        E2_BOX,
        1,
        "clean:E2",
    ),
    Case(
        "temp_folder_missing",
        lambda ds, w: shutil.rmtree(ds / "E2/temperatures"),
        "folder not found",
        "E2/temperatures",
        target="clean:E2",
    ),
    Case(
        "temp_date_only_times",
        lambda ds, w: _cell(ds / E2_HMI, 3, "time", "2022-03-15"),
        "line 3, column 'time': time goes backwards",
        E2_HMI,
        3,
        "clean:E2",
    ),
    Case(
        "temp_fifo",
        lambda ds, w: _fifo(ds / E2_HMI),
        "not a regular file (a FIFO)",
        E2_HMI,
        target="clean:E2",
    ),
    # One logger that recorded nothing in a run costs its sensors there (issue 33).
    Case(
        "temp_missing_source",
        lambda ds, w: (ds / E2_HMI).unlink(),
        "no log of source hmi in this run; its sensor(s) T12 have no reading here",
        E2_HMI,
        target="clean:E2",
        fails=False,
    ),
    Case(
        "temp_header_only",
        lambda ds, w: (ds / E2_HMI).write_text("time,T12\n", encoding="utf-8"),
        "no data rows below the header; its sensor(s) T12 have no reading here",
        E2_HMI,
        target="clean:E2",
        fails=False,
    ),
    Case(
        "temp_every_source_missing",
        lambda ds, w: _remove_csv_files(ds / "E2/temperatures"),
        "no temperature reading (every log absent or without data rows); expected one CSV per "
        "source that dataset.yaml declares sensors for",
        "E2/temperatures",
        target="clean:E2",
    ),
    Case(
        "temp_unknown_source",
        lambda ds, w: shutil.copy(ds / E2_HMI, ds / "E2/temperatures/cnc.csv"),
        "unknown temperature source 'cnc'",
        "E2/temperatures/cnc.csv",
        target="clean:E2",
    ),
    Case(
        "temp_utf8_bom",
        lambda ds, w: (ds / E2_BOX).write_bytes(b"\xef\xbb\xbf" + (ds / E2_BOX).read_bytes()),
        "",
        target="clean:E2",
        fails=False,
    ),
    Case(
        "temp_crlf",
        lambda ds, w: (ds / E2_BOX).write_bytes((ds / E2_BOX).read_bytes().replace(b"\n", b"\r\n")),
        "",
        target="clean:E2",
        fails=False,
    ),
    Case(
        "temp_fahrenheit",
        lambda ds, w: _column(ds / E2_BOX, "T3", lambda v: f"{v * 9 / 5 + 32:.3f}"),
        "sensor T3: median",
        E2_BOX,
        target="clean:E2",
        fails=False,
    ),
    Case(
        "temp_90c_everywhere",
        lambda ds, w: [
            _column(ds / E2_BOX, f"T{i}", lambda v: f"{v + 60:.3f}") for i in range(1, 11)
        ],
        "sensor T1: median",
        E2_BOX,
        target="clean:E2",
        fails=False,
    ),
    Case(
        "temp_kelvin",
        lambda ds, w: _column(ds / E2_BOX, "T4", lambda v: f"{v + 273.15:.3f}"),
        # Beyond temperatures.limits_c every reading is an open circuit; the warning explains why.
        "sensor T4 has no valid reading at all",
        "E2/temperatures",
        target="clean:E2",
        # One sensor is unusable in E2: it leaves the candidates, not the dataset.
        fails=False,
    ),
    Case(
        "temp_long_gap",
        lambda ds, w: _write_lines(
            ds / E2_BOX, _lines(ds / E2_BOX)[:200] + _lines(ds / E2_BOX)[500:]
        ),
        "longer than max_gap_s",
        "E2/temperatures",
        target="clean:E2",
        # One sensor is unusable in E2: it leaves the candidates, not the dataset.
        fails=False,
    ),
    Case(
        "temp_one_row",
        lambda ds, w: _write_lines(ds / E2_HMI, _lines(ds / E2_HMI)[:2]),
        "sensor T12 has",
        "E2/temperatures",
        target="clean:E2",
        # One sensor is unusable in E2: it leaves the candidates, not the dataset.
        fails=False,
    ),
    Case(
        "temp_one_time_repeated",
        lambda ds, w: _write_lines(
            ds / E2_HMI, [_lines(ds / E2_HMI)[0]] + [_lines(ds / E2_HMI)[1]] * 50
        ),
        "sensor T12 has",
        "E2/temperatures",
        target="clean:E2",
        # One sensor is unusable in E2: it leaves the candidates, not the dataset.
        fails=False,
    ),
    Case(
        "temp_huge_values",
        lambda ds, w: _column(ds / E2_HMI, "T12", lambda v: "1e308"),
        "sensor T12 has",
        "E2/temperatures",
        target="clean:E2",
        # One sensor is unusable in E2: it leaves the candidates, not the dataset.
        fails=False,
    ),
    Case(
        "temp_log_ends_early",
        lambda ds, w: _write_lines(ds / E2_BOX, _lines(ds / E2_BOX)[:30]),
        # Every box sensor (T1-T10) is unusable in E2 and leaves: two remain for three
        # clusters, each a cluster of its own.
        "fold E2: 3 clusters (selection.n_clusters) but only 2 sensors vary",
        target="select:E2",
        fails=False,
    ),
    Case(
        "temp_every_log_starts_late",
        # Every log of E2 starts 12 minutes after its first measurement ended: no sensor
        # has a reading there, so every one is unusable in E2 and none is left.
        lambda ds, w: [
            _start_at(path, "2022-03-15T13:20:00")
            for path in sorted((ds / "E2" / "temperatures").glob("*.csv"))
        ],
        "every sensor (T1, T2, T3, T4, T5, T6, T7, T8, T9, T10, T11, T12) misses a measurement",
        target="select:E2",
    ),
    Case(
        "error_one_row",
        lambda ds, w: _write_lines(ds / E2_M03, _lines(ds / E2_M03)[:2]),
        "13 of 14 targets have no reading",
        E2_M03,
        target="clean:E2",
    ),
    Case(
        "error_targets_shifted",
        lambda ds, w: _column(ds / E2_M03, "position_mm", lambda v: f"{v + 3:g}"),
        "reads 14 position(s) that are not the run's targets (188, 208, 228, 248, 268, 288, ... "
        "(14 in all) mm) and lacks 14 of the run's 14 targets (185, 205, 225, 245, 265, 285, ... "
        "(14 in all) mm); they look shifted by +3 mm",
        E2_M03,
        target="clean:E2",
    ),
    Case(
        "error_stray_position",
        # One reading at 195 mm, between two targets, that no other measurement reads.
        lambda ds, w: _write_lines(
            ds / E2_M03,
            [*_lines(ds / E2_M03)[:2], "2022-03-15T13:51:12,195,-1.5,+", *_lines(ds / E2_M03)[2:]],
        ),
        "195 mm read by 1 of the run's 8 measurements, not one of its targets; left out",
        E2_M03,
        target="clean:E2",
        fails=False,
    ),
    Case(
        "error_zero_duration",
        lambda ds, w: _write_lines(
            ds / E2_M03,
            [_lines(ds / E2_M03)[0]]
            + [
                _lines(ds / E2_M03)[1].split(",")[0] + "," + ",".join(line.split(",")[1:])
                for line in _lines(ds / E2_M03)[1:]
            ],
        ),
        "",
        target="clean:E2",
        fails=False,
    ),
    Case(
        "error_backward_pass_only",
        lambda ds, w: _write_lines(
            ds / E2_M03, [line for line in _lines(ds / E2_M03) if not line.endswith(",+")]
        ),
        "",
        target="clean:E2",
        fails=False,
    ),
    Case(
        "every_measurement_one_position",
        lambda ds, w: [_write_lines(p, _lines(p)[:2]) for p in sorted(ds.glob("E*/errors/*.csv"))],
        "",
        target="select:E2",
        fails=False,
    ),
    Case(
        "error_no_direction_two_passes",
        lambda ds, w: [
            _write_lines(p, [",".join(line.split(",")[:3]) for line in _lines(p)])
            for p in sorted(ds.glob("E2/errors/*.csv"))
        ],
        "position 185 mm appears twice in the + pass",
        "E2/errors/M01.csv",
        target="clean:E2",
    ),
    Case(
        "temp_all_out_of_limits",
        lambda ds, w: _column(ds / E2_BOX, "T5", lambda v: "500"),
        "sensor T5 has",
        "E2/temperatures",
        target="clean:E2",
        # One sensor is unusable in E2: it leaves the candidates, not the dataset.
        fails=False,
    ),
    Case(
        "two_runs_one_condition",
        lambda ds, w: _runs_row(ds, "E2", "condition", "1"),
        "",
        target="select:E2",
        fails=False,
    ),
    # ---- dataset-level and config -------------------------------------------------------
    Case(
        "config_n_clusters_too_many",
        lambda ds, w: None,
        "fold E2: 50 clusters (selection.n_clusters) but only 12 sensors vary",
        target="select:E2",
        fails=False,
        config={"selection": {"n_clusters": 50}},
    ),
    Case(
        "config_huge_interval",
        lambda ds, w: None,
        "config temperatures.interval_s",
        target="clean:E2",
        config={"temperatures": {"interval_s": 1e12}},
    ),
    Case(
        "config_degree_out_of_range",
        lambda ds, w: None,
        "config decoupling/degree: 7 is greater than the maximum of 3",
        config={"decoupling": {"degree": 7}},
    ),
    Case(
        "config_unknown_key",
        lambda ds, w: None,
        "config top level: Additional properties are not allowed ('bogus' was unexpected)",
        config={"bogus": 1},
    ),
    Case(
        "config_wrong_type",
        lambda ds, w: None,
        "config selection/n_clusters: 'three' is not of type 'integer'",
        config={"selection": {"n_clusters": "three"}},
    ),
    Case(
        "config_limits_reversed",
        lambda ds, w: None,
        "limits_c must be (low, high) with low < high",
        config={"temperatures": {"limits_c": [120, -20]}},
    ),
    Case(
        "config_median_reversed",
        lambda ds, w: None,
        "config temperatures.plausible_median_c: expected [low, high]",
        target="clean:E2",
        config={"temperatures": {"plausible_median_c": [60, 5]}},
    ),
    Case("config_dataset_missing", lambda ds, w: shutil.rmtree(ds), "dataset folder not found", ""),
    Case("config_unknown_fold", lambda ds, w: None, "config folds: 'E9'", config={"folds": ["E9"]}),
    Case(
        "config_compensation_algorithm_not_modelled",
        lambda ds, w: None,
        "config compensation.algorithm: 'svr' is not one of models.algorithms (mlr)",
        config={"models": {"algorithms": ["mlr"]}, "compensation": {"algorithm": "svr"}},
    ),
    Case(
        "config_sweep_unknown_fold",
        lambda ds, w: None,
        "config sweep.folds: 'E9' is not a run of",
        "runs.tsv",
        config={"sweep": {"folds": ["E9"]}},
    ),
    Case(
        "config_sweep_nothing_fits",
        lambda ds, w: None,
        "config sweep: no selection setting fits the dataset (fixed: sensor(s) X1, X2, X3 of sweep.fixed are not in the dataset)",
        target="sweep",
        config={
            "sweep": {
                "methods": ["fixed"],
                "fixed": {"k": ["X1"], "b": ["X2"], "pointwise": ["X3"]},
            }
        },
    ),
    Case(
        "constant_sensor",
        lambda ds, w: (
            _column(ds / E2_BOX, "T3", lambda v: "25.000")
            or _column(ds / "E1/temperatures/box.csv", "T3", lambda v: "25.000")
        ),
        "sensor T3 is constant over the training measurements; left out of the selection",
        target="select:E2",
        fails=False,
    ),
    Case(
        "constant_sensor_too_few_for_clusters",
        lambda ds, w: _column(ds / "E1/temperatures/box.csv", "T3", lambda v: "25.000"),
        "fold E2: 12 clusters (selection.n_clusters) but only 11 sensors vary over its training measurements",
        target="select:E2",
        fails=False,
        config={"selection": {"n_clusters": 12}},
    ),
    Case(
        "constant_every_sensor",
        lambda ds, w: [
            _column(path, sensor, lambda v: "25.000")
            for path in sorted((ds / "E1" / "temperatures").glob("*.csv"))
            for sensor in _lines(path)[0].split(",")[1:]
        ],
        "re:results/cut/assembled/temperatures\\.parquet: fold E2: every sensor is constant over "
        "the training measurements",
        target="select:E2",
    ),
    Case(
        "constant_fixed_sensor",
        lambda ds, w: _column(ds / "E1/temperatures/box.csv", "T1", lambda v: "25.000"),
        "config selection.fixed: sensor T1 is constant",
        target="select:E2",
        config={
            "selection": {
                "method": "fixed",
                "fixed": {"k": ["T1", "T6"], "b": ["T2", "T7"], "pointwise": ["T1", "T11"]},
            }
        },
    ),
]


# Run end to end through Snakemake as well: at least one case of every stage that can
# refuse (the config, each kind of check of thermaxis.pipeline.preflight, a job of each
# rule that refuses or warns) and every case that could hang or write outside the
# dataset's folders. Each also checks that the in-process message is Snakemake's.
END_TO_END = {
    "config_degree_out_of_range",  # preflight's validate_config, before anything else
    "config_compensation_algorithm_not_modelled",  # preflight: a check that was the compensation rules' own
    "config_sweep_nothing_fits",  # preflight.sweep_plan, when the sweep's DAG is built
    "name_dotdot",  # preflight: a name that would escape results/
    "first_error_fifo",  # preflight: the one data file read at parse time; a FIFO must not hang
    "yaml_list_property",  # accepted: both runs cleaned and assembled, the summary with them
    "temp_fifo",  # clean refuses; a FIFO inside a job must not hang
    "measurement_symlink_outside",  # clean refuses a file outside the dataset
    "temp_fahrenheit",  # clean warns, and the warning reaches the terminal
    "error_positions_differ",  # assemble refuses
    "constant_every_sensor",  # the models rule refuses, naming the fold's temperatures file
}
# Cases the end-to-end tests elsewhere used to repeat are run in-process above and, for the
# config and the compensation algorithm, end to end here: a non-number in an error file
# (error_text), a text in runs.tsv's feed column (runs_feed_text), a degree out of range and a
# compensation algorithm that is not modelled. A second refusal of the models rule
# (constant_sensor_too_few_for_clusters) runs in-process only: one models case shows that
# its line passes through Snakemake.


# --------------------------------------------------------------------------- #
# running a case
# --------------------------------------------------------------------------- #
@pytest.fixture(scope="module")
def two_runs(tmp_path_factory) -> Path:
    """E1 and E2 of the twin as a dataset of its own (SIMULATED, like the twin)."""
    root = tmp_path_factory.mktemp("cut") / "cut"
    root.mkdir()
    for run in ("E1", "E2"):
        shutil.copytree(TWIN / run, root / run)
    # Two of the paper's four runs no longer reproduce its experiment (no paper fold E4).
    sheet = (
        (TWIN / "dataset.yaml").read_text(encoding="utf-8").replace("name: twin", f"name: {NAME}")
    )
    _yaml_text(root, sheet.replace("reproduces: xu2023\n", ""))
    _write_lines(
        root / "runs.tsv",
        [line for line in _lines(TWIN / "runs.tsv") if line.split("\t")[0] in ("run", "E1", "E2")],
    )
    return root


def _broken(case: Case, two_runs: Path, tmp_path: Path) -> tuple[Path, Path, dict]:
    """The case's dataset and workflow folder in tmp, and its config overrides."""
    ds = tmp_path / "data" / NAME
    shutil.copytree(two_runs, ds, symlinks=True)
    work = workflow_workdir(tmp_path)
    case.break_it(ds, work)
    config = {
        "dataset": str(ds),
        "ambient_sensor": "T10",
        "selection": {"n_clusters": 3},
        # The cases of the models job check the selection's line; its fits after the
        # selection add nothing to them, and one algorithm's take a fraction of five's.
        **({"models": {"algorithms": ["mlr"]}} if case.target.startswith("select") else {}),
        **case.config,
    }
    (work / "case.yaml").write_text(yaml.safe_dump(config))
    return ds, work, config


def _targets(case: Case, name: str) -> list[str]:
    kind, _, arg = case.target.partition(":")
    out = f"results/{name}"
    return {
        "parse": [f"{out}/tables/dataset_summary.csv"],
        "summary": [f"{out}/tables/dataset_summary.csv"],
        "clean": [f"{out}/clean/{arg}/qc.csv"],
        "select": [f"{out}/selection/{arg}.json"],
        "assemble": [f"{out}/assembled/errors.parquet"],
        "sweep": [f"{out}/sweep/summary.csv"],
    }[kind]


def _tree(root: Path, skip: tuple[str, ...]) -> set[str]:
    found = set()
    for dirpath, dirnames, filenames in os.walk(root):
        rel = Path(dirpath).relative_to(root)
        dirnames[:] = [d for d in dirnames if str(rel / d) not in skip]
        found.update(
            str(rel / f)
            for f in filenames + [d for d in dirnames if os.path.islink(Path(dirpath) / d)]
        )
    return found


def _message(stderr: str) -> str:
    lines = [line for line in stderr.splitlines() if line.startswith("thermaxis error:")]
    return lines[0] if lines else ""


def _record(case: Case, message: str, status: str) -> None:
    folder = os.environ.get("THERMAXIS_CATALOGUE")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        (Path(folder) / f"{case.id}.json").write_text(
            json.dumps({"id": case.id, "status": status, "message": message})
        )


# ---- in process: the parse-time gate and the rules' own scripts ----------------------------
class _Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise _Timeout(f"no answer within {TIMEOUT_S} s")


def _target_jobs(case: Case) -> list[tuple[str, dict]]:
    """The (rule, wildcards) of the jobs Snakemake runs for the case's target, in order."""
    kind = case.target.partition(":")[0]
    # The dataset's manifest, then one clean job for every run: a "clean:<run>" target is
    # made by it too.
    cleans = [("data_manifest", {}), ("clean", {})]
    return {
        "parse": cleans + [("assemble", {})],
        "summary": cleans + [("assemble", {})],
        "clean": cleans,
        "assemble": cleans + [("assemble", {})],
        "select": cleans + [("assemble", {}), ("models", {})],
        "sweep": [],
    }[kind]


def _parsed(
    work: Path, jobs: list[tuple[str, dict]]
) -> tuple[dict, list[tuple[Path, SimpleNamespace]]]:
    """Parse the workflow in ``work`` as Snakemake does (config/config.yaml, then case.yaml)
    and take each job's wiring from its rule: the script it runs and the input, output,
    params, log and wildcards Snakemake hands that script as ``snakemake``.

    Returns the workflow's globals too; a refusal while parsing raises SystemExit.
    """
    from snakemake.api import SnakemakeApi
    from snakemake.iocontainers import Wildcards
    from snakemake.settings.enums import Quietness
    from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings

    with SnakemakeApi(OutputSettings(quiet={Quietness.ALL}, enable_file_logging=False)) as api:
        parsed = api.workflow(
            resource_settings=ResourceSettings(cores=1),
            config_settings=ConfigSettings(
                configfiles=[work / "config" / "config.yaml", work / "case.yaml"]
            ),
            snakefile=work / "Snakefile",
            workdir=work,
        )._workflow
        rules = {rule.name: rule for rule in parsed.rules}
        wired = []
        for name, values in jobs:
            rule = rules[name]
            wildcards = Wildcards(fromdict=values)
            input, *_ = rule.expand_input(wildcards)
            output, _ = rule.expand_output(wildcards)
            params, _ = rule.expand_params(wildcards, input, output, None)
            job = SimpleNamespace(
                rule=name,
                input=input,
                output=output,
                params=params,
                wildcards=wildcards,
                log=rule.expand_log(wildcards),
            )
            wired.append((Path(rule.basedir) / rule.script, job))
        return dict(parsed.globals), wired


def _in_process(case: Case, work: Path, config: dict, capsys) -> tuple[bool, str, str, list[Path]]:
    """Refused?, the 'thermaxis error:' line, stderr, and the refusing job's outputs.

    Parse time is thermaxis.pipeline.preflight, the one parse-time gate: check_before_jobs
    (what common.smk calls first) on the config files merged as Snakemake merges them,
    then the workflow parsed in-process (its last check, preflight.check_rules) and, for
    the sweep, preflight.sweep_plan. The jobs run the rules' scripts with the wiring of
    the parsed workflow, as Snakemake does.
    """
    base = yaml.safe_load((REPO / "config" / "config.yaml").read_text(encoding="utf-8"))
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(TIMEOUT_S)
    cwd = os.getcwd()
    os.chdir(work)
    try:
        try:
            checked = preflight.check_before_jobs(merge(base, config))
        except ValueError as exc:
            assert "\n" not in str(exc), repr(str(exc))
            return True, f"thermaxis error: {exc}", capsys.readouterr().err, []
        try:
            _, jobs = _parsed(work, _target_jobs(case))
            if case.target == "sweep":
                preflight.sweep_plan(checked, cores=1, on_cluster=False)
        except SystemExit as exc:
            return True, str(exc.code), capsys.readouterr().err, []
        except ValueError as exc:
            assert "\n" not in str(exc), repr(str(exc))
            return True, f"thermaxis error: {exc}", capsys.readouterr().err, []
        finally:
            os.chdir(work)  # the parse changes back to where it started
        for script, job in jobs:
            for path in job.output:  # Snakemake makes the output folders
                Path(path).parent.mkdir(parents=True, exist_ok=True)
            try:
                runpy.run_path(str(script), init_globals={"snakemake": job}, run_name="__main__")
            except SystemExit as exc:
                assert exc.code == 1, exc.code
                err = capsys.readouterr().err
                return True, _message(err), err, [work / p for p in job.output]
        return False, "", capsys.readouterr().err, []
    finally:
        os.chdir(cwd)
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
        # run_script's logging set-up, undone: later tests must not write to this test's log.
        logging.captureWarnings(False)
        for name in ("thermaxis", "py.warnings"):
            for handler in logging.getLogger(name).handlers[:]:
                handler.close()
                logging.getLogger(name).removeHandler(handler)


def _check_in_process(case: Case, two_runs: Path, tmp_path: Path, capsys) -> tuple[bool, str]:
    """The case run in-process and every check of its outcome; returns (refused, message)."""
    ds, work, config = _broken(case, two_runs, tmp_path)
    before = _tree(tmp_path, ())
    refused, message, stderr, outputs = _in_process(case, work, config, capsys)
    new = _tree(tmp_path, ()) - before
    assert "Traceback" not in stderr and not message.startswith("thermaxis error: unexpected "), (
        stderr[-4000:]
    )
    _assert_confined(new)
    if case.fails:
        _record(case, message, "refused")
        assert refused, f"accepted:\n{stderr[-4000:]}"
        assert message, f"no 'thermaxis error:' line:\n{stderr[-4000:]}"
        _assert_names(case, message, ds)
        # Stricter than end to end, where Snakemake deletes a failed job's outputs: the
        # refusing script itself leaves none of them, not even half-written.
        assert not [p for p in outputs if p.exists()], "outputs written despite the error"
        if case.target == "parse" or not outputs:
            assert not [p for p in new if p.startswith("work/results/")], (
                "parse-time refusal wrote results"
            )
    else:
        assert not refused, stderr[-4000:]
        _assert_warned(case, stderr, ds)
    return refused, message


# The END_TO_END cases are checked in-process by test_bad_input_end_to_end, after their
# Snakemake run, and not a second time here.
@pytest.mark.parametrize("case", [c for c in CASES if c.id not in END_TO_END], ids=lambda c: c.id)
def test_bad_input(case: Case, two_runs: Path, tmp_path: Path, capsys) -> None:
    _check_in_process(case, two_runs, tmp_path, capsys)


@pytest.mark.parametrize("case", [c for c in CASES if c.id in END_TO_END], ids=lambda c: c.id)
def test_bad_input_end_to_end(case: Case, two_runs: Path, tmp_path: Path, capsys) -> None:
    ds, work, config = _broken(case, two_runs, tmp_path)
    before = _tree(tmp_path, ("work/.snakemake",))
    proc = run_snakemake(
        work,
        "--configfile",
        "config/config.yaml",
        "case.yaml",
        "--",
        *_targets(case, NAME),
        check=False,
        timeout=TIMEOUT_S,
    )
    output = proc.stdout + proc.stderr
    message = _message(proc.stderr)
    assert "Traceback" not in output, output[-4000:]
    new = _tree(tmp_path, ("work/.snakemake",)) - before
    _assert_confined(new)
    if case.fails:
        assert proc.returncode != 0
        assert message, f"no 'thermaxis error:' line:\n{output[-4000:]}"
        _assert_names(case, message, ds)
        for target in _targets(case, NAME):
            assert not (work / target).exists(), f"{target} written despite the error"
        assert not [
            p for p in new if p.startswith(f"work/results/{NAME}/") and case.target == "parse"
        ]
    else:
        assert proc.returncode == 0, output[-4000:]
        _assert_warned(case, proc.stderr, ds)
    # The in-process path the catalogue runs, with all its checks, gives the very same line
    # (in the same folders: the line names the dataset's files).
    shutil.rmtree(tmp_path / "data")
    shutil.rmtree(tmp_path / "work")
    assert _check_in_process(case, two_runs, tmp_path, capsys) == (
        case.fails,
        message,
    )


def _assert_confined(new: set[str]) -> None:
    allowed = (f"work/results/{NAME}/", f"work/logs/{NAME}/", f"work/benchmarks/{NAME}/")
    escaped = sorted(p for p in new if not p.startswith(allowed))
    assert not escaped, f"written outside results/{NAME}/, logs/, benchmarks/: {escaped}"
    partial = sorted(p for p in new if Path(p).name.startswith("."))
    assert not partial, f"partial (temporary) outputs left: {partial}"


def _assert_warned(case: Case, stderr: str, ds: Path) -> None:
    warnings = [line for line in stderr.splitlines() if line.startswith("thermaxis warning:")]
    warning = next((line for line in warnings if case.expect and case.expect in line), "")
    _record(case, warning, "warned" if case.expect else "accepted")
    if case.expect:
        assert warning, f"no warning containing {case.expect!r} on the terminal:\n{stderr[-3000:]}"
        if case.file:
            assert str(ds / case.file) in warning


def _assert_names(case: Case, message: str, ds: Path) -> None:
    if case.expect.startswith("re:"):
        assert re.search(case.expect[3:], message), message
    else:
        assert case.expect in message, message
    if case.file is not None:
        assert f"{ds / case.file}".rstrip("/") in message, message
    if case.line is not None:
        assert f"line {case.line}" in message, message


def write_catalogue(folder: Path, out: Path) -> None:
    """Markdown list of every kind and its message, from the records of a test run."""
    records = {
        r["id"]: r for r in (json.loads(p.read_text()) for p in sorted(folder.glob("*.json")))
    }
    lines = [
        "# Bad-input catalogue",
        "",
        "Generated by running `tests/workflow/test_bad_input_catalogue.py` with `THERMAXIS_CATALOGUE` set.",
        "Paths are those of the test's scratch copy (`<tmp>` stands for it) and of the repository (`<repo>`).",
        "",
        "| kind | outcome | message |",
        "|---|---|---|",
    ]
    tmp = re.compile(r"/\S*?/data/" + NAME)
    for case in CASES:
        record = records.get(case.id, {"status": "not run", "message": ""})
        text = (
            tmp.sub("<tmp>/" + NAME, record["message"])
            .replace(str(REPO), "<repo>")
            .replace("|", "\\|")
        )
        lines.append(f"| `{case.id}` | {record['status']} | {text} |")
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    write_catalogue(Path(sys.argv[1]), Path(sys.argv[2]))
