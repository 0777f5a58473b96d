"""The import mapping (``thermaxis import MAPPING``): loaded safely, validated, checked.

Everything about the mapping itself, before any table is read: its schema and defaults,
the checks a schema cannot say (ids and columns given once, time ranges that do not
overlap, a licence file that exists), its error channels, and how a column name it
gives is compared with a table's header.
"""

from __future__ import annotations

import codecs
import copy
import functools
from pathlib import Path

import pandas as pd
import yaml

from thermaxis.config import fill_defaults
from thermaxis.errors import DataError, first_schema_error, schema_message, schema_where, shown
from thermaxis.schemas import load_schema

__all__ = ["load_mapping", "header_name", "table_layout"]


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
    error = first_schema_error(schema, mapping)
    if error is not None:
        raise DataError(f"{path}: {schema_where(error)}: {schema_message(error)}")
    fill_defaults(mapping, schema)
    mapping["time"].setdefault("column", None)
    try:
        codecs.lookup(mapping["csv"]["encoding"])
    except LookupError:
        raise DataError(
            f"{path}: csv/encoding: unknown encoding {mapping['csv']['encoding']!r} "
            "(expected a Python codec name, e.g. utf-8 or cp1252)"
        ) from None
    _check_ids(path, mapping)
    _check_columns(path, mapping)
    _check_ranges(path, mapping)
    _check_start_and_licence(path, mapping)
    return mapping


def _check_columns(path: Path, mapping: dict) -> None:
    """One id per table column: a column mapped twice would be one sensor under two names
    (two perfectly collinear inputs) or a temperature read as an error."""
    seen: dict[str, str] = {}
    named = [(s["column"], s["id"]) for s in (*mapping["sensors"], *mapping["signals"])]
    named += [
        (
            c["column"],
            f"an error column of channel {channel['id']}" if channel["id"] else "an error column",
        )
        for channel in _channels(mapping)
        for c in channel["columns"]
    ]
    for column, what in named:
        key = header_name(column)
        if key in seen:
            raise DataError(
                f"{path}: column {key!r} is mapped twice ({seen[key]} and {what}); expected "
                "each column of the table under one id"
            )
        seen[key] = what


def _check_ranges(path: Path, mapping: dict) -> None:
    """Runs cut by time ranges hold distinct samples: a sample in two runs would sit in a
    training run and in the run held out from it."""
    if mapping["split"]["by"] != "ranges":
        return
    for run in mapping["runs"]:
        if not run["start_s"] < run["end_s"]:
            raise DataError(
                f"{path}: run {run['name']!r}: start_s {run['start_s']:g} is not before end_s "
                f"{run['end_s']:g}; expected [start_s, end_s) in seconds since the record's start"
            )
    ordered = sorted(mapping["runs"], key=lambda r: (r["start_s"], r["end_s"]))
    for earlier, later in zip(ordered, ordered[1:], strict=False):
        if later["start_s"] < earlier["end_s"]:
            raise DataError(
                f"{path}: run {later['name']!r} [{later['start_s']:g}, {later['end_s']:g}) s "
                f"overlaps run {earlier['name']!r} [{earlier['start_s']:g}, {earlier['end_s']:g}) s; "
                "expected ranges that do not overlap (a sample belongs to one run)"
            )


def _check_start_and_licence(path: Path, mapping: dict) -> None:
    start = mapping["time"].get("start")
    if start is not None:
        try:
            parsed = pd.Timestamp(start)
        except (ValueError, TypeError):
            parsed = pd.NaT
        if pd.isna(parsed):  # pandas reads "" and "NaT" as no time at all
            raise DataError(f"{path}: time/start: expected an ISO 8601 time, got {shown(start)}")
    licence = mapping.get("licence_file")
    if licence and not (path.parent / licence).is_file():
        raise DataError(
            f"{path}: licence_file: {path.parent / licence} not found; expected the source's "
            "licence text (it travels with the data)"
        )


def _check_ids(path: Path, mapping: dict) -> None:
    ids = [s["id"] for s in mapping["sensors"]] + [s["id"] for s in mapping["signals"]]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise DataError(f"{path}: sensors/signals: id {dup[0]!r} given more than once")
    channels = [c["id"] for c in mapping["errors"].get("channels", [])]
    dup = sorted({c for c in channels if channels.count(c) > 1})
    if dup:
        raise DataError(
            f"{path}: errors/channels: id {dup[0]!r} given more than once (each channel is a dataset of its own)"
        )
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


@functools.cache
def _plain_csv() -> dict:
    """The ``csv`` section of a mapping that gives none: the schema's defaults."""
    section: dict = {}
    fill_defaults(section, load_schema("import_mapping")["properties"]["csv"])
    return section


def header_name(name) -> str:
    """A column name as compared: white space around it and runs of it inside (a line
    break in a spreadsheet's header cell) read as one space."""
    return " ".join(str(name).split())


def table_layout(mapping: dict) -> tuple:
    """:func:`read_wide_table`'s arguments after the path, from the mapping."""
    return mapping["sheet"], mapping["csv"], mapping["header_row"], mapping["units_rows"]


def _error_key(channel: int, column: int) -> str:
    return f"_e{channel}.{column}"


def _channels(mapping: dict) -> list[dict]:
    """The error channels: ``errors.channels``, or ``errors.columns`` as the one unnamed channel."""
    errors = mapping["errors"]
    return errors.get("channels") or [{"id": None, "columns": errors["columns"]}]


def _channel_mapping(mapping: dict, channel: dict) -> dict:
    """The mapping of one channel's dataset: its own name, error columns and direction."""
    if channel["id"] is None:
        return mapping
    out = copy.deepcopy(mapping)
    out["name"] = f"{mapping['name']}_{channel['id']}"
    out["errors"]["columns"] = channel["columns"]
    if channel.get("direction"):
        out["axis"]["direction"] = channel["direction"]
    out["description"] = (
        mapping["description"].strip()
        + f"\n\nThis dataset holds error channel {channel['id']!r} of the record"
        + (f" ({channel['direction']})." if channel.get("direction") else ".")
    )
    return out
