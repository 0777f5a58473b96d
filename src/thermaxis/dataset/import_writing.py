"""Writing one imported dataset in the raw layout: runs, ``dataset.yaml`` and ``runs.tsv``.

Temperatures and signals as logged (converted to degrees C), the error columns
subsampled into measurements (re-referenced and converted to um where the mapping says
so), and every assumption the import made, in sentences, appended to the dataset's
description so that it travels with the data.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from thermaxis.dataset.import_mapping import _error_key, _plain_csv
from thermaxis.dataset.import_parsing import (
    _UNIT_WORDS,
    Progress,
    _words,
    measurements_of,
    time_columns,
)
from thermaxis.errors import DataError

__all__ = ["ERROR_UNITS_UM", "RunSummary", "Imported"]

# A temperature unit (temperature_unit) as degrees C = (value - offset) x scale; a rise
# takes the scale alone.
TEMPERATURE_UNITS = {"degC": (0.0, 1.0), "K": (273.15, 1.0), "degF": (32.0, 5.0 / 9.0)}
# The error columns' unit (errors.unit) in um, the raw layout's.
ERROR_UNITS_UM = {"um": 1.0, "mm": 1000.0, "nm": 0.001}


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
    notes = [_time_note(mapping["time"])]
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
    notes.append(_split_note(mapping["split"], counts))
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


def _time_note(time: dict) -> str:
    """Where the times come from: the logged clock, a relative time or the row number."""
    if time.get("format"):
        return (
            f"Times are the logged clock times of {_words(time_columns(time))} (format {time['format']}); "
            "a time zone, where given, was converted to UTC."
        )
    if time["column"]:
        return (
            f"Times are {_UNIT_WORDS[time['unit']]} since the record's start (column {time['column']!r}); "
            f"the clock time {time['start']} given to the first row is invented by the import, not measured."
        )
    return (
        f"The source has no time column: row i is taken at i x {time['interval_s']:g} s after {time['start']}, "
        "an invented clock."
    )


def _split_note(split: dict, counts: dict[str, int]) -> str:
    """How the record was cut into runs."""
    if split["by"] == "signal":
        return (
            f"The record was cut into {len(counts)} runs where signal {split['signal']!r} leaves its rest value "
            f"{split['rest']:g} (the first run keeps the record's start)."
        )
    if split["by"] == "ranges":
        return "The record was cut into runs at the time ranges listed in the import mapping."
    return "Each run comes from its own file."


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
