"""Wide logger tables (CSV or XLSX, one row per sample) into the raw-data layout.

``python -m thermaxis.dataset.importer MAPPING.yaml --out data/raw/<name>`` reads the table the
mapping names, splits it into runs (by an operating signal's rest-to-active steps, by
explicit time ranges, or one file per run), subsamples the error columns into
measurements every ``errors.every_s`` seconds, and writes ``dataset.yaml``,
``runs.tsv`` and one folder per run.  Every assumption the import makes (an invented
clock, re-referencing, subsampling, how runs were cut) is appended to the generated
``dataset.yaml`` description, so it travels with the data.

The output is validated by :func:`thermaxis.dataset.reader.load_dataset` before it is moved into
place; nothing half-written is left behind.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

import jsonschema
import numpy as np
import pandas as pd
import yaml

from thermaxis.dataset.reader import load_dataset
from thermaxis.errors import DataError
from thermaxis.schemas import load_schema

__all__ = ["load_mapping", "read_table", "split_runs", "measurements_of", "import_dataset", "main"]


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
        raise DataError(f"{path}: {where}: {errors[0].message}")
    for key, sub in schema["properties"].items():
        if "default" in sub and key not in mapping:
            mapping[key] = sub["default"]
    mapping["errors"].setdefault("rereference", "none")
    mapping["split"].setdefault("rest", 0)
    mapping["time"].setdefault("column", None)
    for sensor in mapping["sensors"]:
        sensor.setdefault("location", "not documented by the source")
    _check_ids(path, mapping)
    return mapping


def _check_ids(path: Path, mapping: dict) -> None:
    ids = [s["id"] for s in mapping["sensors"]] + [s["id"] for s in mapping["signals"]]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise DataError(f"{path}: sensors/signals: id {dup[0]!r} given more than once")
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


def read_table(path, sheet=0) -> pd.DataFrame:
    """A wide table, one row per sample; column names stripped of surrounding spaces."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: file not found (the mapping's source)")
    suffix = path.suffix.lower()
    try:
        if suffix in (".xlsx", ".xlsm"):
            frame = pd.read_excel(path, sheet_name=sheet)
        elif suffix in (".csv", ".txt"):
            frame = pd.read_csv(path)
        else:
            raise DataError(f"{path}: expected a .csv or .xlsx table, got {suffix or 'no suffix'}")
    except (ValueError, KeyError) as exc:
        raise DataError(f"{path}: cannot read the table ({str(exc).splitlines()[0]})") from None
    frame.columns = [str(c).strip() for c in frame.columns]
    if frame.empty:
        raise DataError(f"{path}: no data rows below the header")
    return frame


def _numeric(path: Path, frame: pd.DataFrame, column: str, allow_empty: bool) -> np.ndarray:
    if column not in frame.columns:
        raise DataError(
            f"{path}: missing column {column!r} (named in the mapping); the table has {', '.join(frame.columns)}"
        )
    values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values) & (frame[column].notna().to_numpy() if allow_empty else True)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"{path}: row {i + 2}, column {column!r}: expected a finite number, got {frame[column].iloc[i]!r}"
        )
    return values


def _seconds(path: Path, frame: pd.DataFrame, time: dict) -> np.ndarray:
    if time["column"]:
        t = _numeric(path, frame, time["column"], allow_empty=False)
        back = np.flatnonzero(np.diff(t) <= 0)
        if back.size:
            i = int(back[0]) + 1
            raise DataError(
                f"{path}: row {i + 2}, column {time['column']!r}: time does not increase ({t[i]:g} after {t[i - 1]:g})"
            )
        return t
    return np.arange(len(frame), dtype=float) * float(time["interval_s"])


def _tidy(path: Path, frame: pd.DataFrame, mapping: dict) -> pd.DataFrame:
    """Seconds since the record's start, then every mapped column under its new id."""
    out = {"_t": _seconds(path, frame, mapping["time"])}
    for item in (*mapping["sensors"], *mapping["signals"]):
        out[item["id"]] = _numeric(path, frame, item["column"], allow_empty=True)
    for j, item in enumerate(mapping["errors"]["columns"]):
        out[f"_e{j}"] = _numeric(path, frame, item["column"], allow_empty=True)
    return pd.DataFrame(out)


def split_runs(rows: pd.DataFrame, mapping: dict, where: str = "mapping") -> list[pd.DataFrame]:
    """Cut one record into runs, in time order.

    ``by: signal``: a run starts where the signal leaves its rest value after being at
    rest (the first run starts with the record, so it keeps the standstill before the
    first step); ``by: ranges``: each run's ``[start_s, end_s)``.
    """
    split = mapping["split"]
    if split["by"] == "signal":
        active = rows[split["signal"]].to_numpy(dtype=float) != float(split["rest"])
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
        raise DataError(
            f"{where}: split by signal {split['signal']!r} found {len(pieces)} run(s) but the mapping lists "
            f"{len(mapping['runs'])}; expected one entry in runs per rest-to-active step"
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


def _write_run(folder: Path, rows: pd.DataFrame, mapping: dict, start: pd.Timestamp) -> int:
    """A run's temperatures, signals and measurements; returns the number of measurements."""
    times = _iso(start, rows["_t"])
    source = mapping["source_name"]
    (folder / "temperatures").mkdir(parents=True)
    temps = pd.DataFrame({"time": times, **{s["id"]: rows[s["id"]] for s in mapping["sensors"]}})
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
    reference = rows[[f"_e{j}" for j in range(len(columns))]].iloc[0].to_numpy(dtype=float)
    if mapping["errors"]["rereference"] == "run_start" and not np.isfinite(reference).all():
        raise DataError(
            f"{folder.name}: the run's first error reading is missing; cannot re-reference to it"
        )
    records = []
    for i, (_, sample) in enumerate(picked.iterrows(), start=1):
        for j, item in enumerate(columns):
            value = float(sample[f"_e{j}"])
            if mapping["errors"]["rereference"] == "run_start":
                value -= reference[j]
            if np.isfinite(value):
                records.append(
                    (f"M{i:03d}", _iso(start, [sample["_t"]])[0], item["position_mm"], value)
                )
    errors = pd.DataFrame(records, columns=["measurement", "time", "position_mm", "error_um"])
    errors.to_csv(folder / "errors.csv", index=False, float_format="%.6g", lineterminator="\n")
    return len(picked)


def _assumptions(mapping: dict, counts: dict[str, int]) -> list[str]:
    """What the import assumed, in sentences for the dataset's description."""
    time = mapping["time"]
    notes = []
    if time["column"]:
        notes.append(
            f"Times are seconds since the record's start (column {time['column']!r}); the clock time "
            f"{time['start']} given to the first row is invented by the import, not measured."
        )
    else:
        notes.append(
            f"The source has no time column: row i is taken at i x {time['interval_s']:g} s after {time['start']}, "
            "an invented clock."
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


def _runs_rows(mapping_path: Path, mapping: dict) -> list[pd.DataFrame]:
    source = (mapping_path.parent / mapping["source"]).resolve()
    if mapping["split"]["by"] == "files":
        pieces = []
        for run in mapping["runs"]:
            table_path = source / run["file"]
            pieces.append(_tidy(table_path, read_table(table_path, mapping["sheet"]), mapping))
        return pieces
    return split_runs(
        _tidy(source, read_table(source, mapping["sheet"]), mapping), mapping, str(mapping_path)
    )


def import_dataset(mapping_path, out) -> Path:
    """Write the dataset the mapping describes into ``out`` (replaced only when complete and valid)."""
    mapping_path = Path(mapping_path)
    mapping = load_mapping(mapping_path)
    pieces = _runs_rows(mapping_path, mapping)
    out = Path(out)
    start = pd.Timestamp(mapping["time"]["start"])
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        counts = {}
        for run, rows in zip(mapping["runs"], pieces, strict=False):
            # Each run keeps its place on the record's clock, so runs follow each other in time.
            counts[run["name"]] = _write_run(tmp / run["name"], rows, mapping, start)
        meta = _dataset_yaml(mapping, _assumptions(mapping, counts))
        header = f"# Written by `python -m thermaxis.dataset.importer {mapping_path.name}` -- do not edit by hand.\n"
        (tmp / "dataset.yaml").write_text(
            header + yaml.safe_dump(meta, sort_keys=False, allow_unicode=True, width=100),
            encoding="utf-8",
        )
        (tmp / "runs.tsv").write_text(_runs_tsv(mapping), encoding="utf-8")
        if mapping.get("licence_file"):
            shutil.copyfile(mapping_path.parent / mapping["licence_file"], tmp / "LICENSE")
        load_dataset(tmp)  # the layout's own validation, before anything replaces `out`
        if out.exists():
            shutil.rmtree(out)
        tmp.rename(out)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m thermaxis.dataset.importer", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "mapping",
        help="the import mapping (YAML; schema src/thermaxis/schemas/import_mapping.schema.yaml)",
    )
    parser.add_argument(
        "--out", required=True, help="the dataset folder to write, e.g. data/raw/<name>"
    )
    args = parser.parse_args(argv)
    try:
        out = import_dataset(args.mapping, args.out)
    except DataError as exc:
        print(f"thermaxis error: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
