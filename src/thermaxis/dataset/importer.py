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

The mapping is :mod:`thermaxis.dataset.import_mapping`, the table's reading and cutting
into runs :mod:`thermaxis.dataset.import_parsing`, the datasets' files
:mod:`thermaxis.dataset.import_writing`; this module runs them into a temporary folder,
validates, moves it into place and warns about the runs.
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from thermaxis.dataset.import_mapping import _channel_mapping, _channels, load_mapping
from thermaxis.dataset.import_parsing import _UNIT_WORDS, TIME_UNITS_S, Progress, _runs_rows
from thermaxis.dataset.import_writing import Imported, RunSummary, _write_dataset
from thermaxis.dataset.reader import load_dataset

__all__ = ["ImportReport", "run_warnings", "summary_lines", "import_dataset"]

# A thermal test heats the axis for half an hour at least and no bench run lasts a week;
# outside these a run's length is almost always a time column read in the wrong unit.
PLAUSIBLE_RUN_S = (30 * 60.0, 7 * 86400.0)
# check_dataset_shape's floor: the intercept b and every model need two measurements in a run.
MIN_MEASUREMENTS = 2


@dataclass(frozen=True)
class ImportReport:
    """The import's result: the folder replaced, the datasets in it and the warnings about its runs."""

    out: Path
    datasets: tuple[Imported, ...]
    warnings: tuple[str, ...]


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
