"""Defences against hostile or broken datasets (issue 13).

Datasets are untrusted input; config files and the workflow are trusted code (README,
"Security and trust").  Everything here turns a dataset that could escape the results
folder, hang the workflow, exhaust memory or slip an implausible value into a model
into ONE line naming the file, the line or column and what was expected
(:class:`thermaxis.io.DataError`).  Checks run before a file is parsed: a FIFO is
never opened, a YAML alias is never expanded, a file's size is known before it is read.
"""

from __future__ import annotations

import math
import os
import re
import stat
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

__all__ = [
    "NAME_PATTERN",
    "MAX_SHEET_BYTES",
    "MAX_DATA_BYTES",
    "check_name",
    "check_regular_file",
    "check_inside",
    "check_within",
    "check_rule_outputs",
    "check_dataset_shape",
    "check_run_plausibility",
    "check_same_targets",
    "load_yaml",
    "sniff_delimited",
    "check_time_zones",
    "check_time_range",
    "check_error_readings",
    "sensor_median_warnings",
    "informative_sensors",
]

# Starts with a letter, digit or underscore: no dot-only names ("." or ".."), no hidden
# files, no leading dash that a tool could read as an option; no separators at all.
NAME_PATTERN = r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,127}$"
_NAME = re.compile(NAME_PATTERN)
# dataset.yaml and runs.tsv are small by nature; a 1 MiB sheet is already absurd.
MAX_SHEET_BYTES = 1 << 20
# The largest legitimate log seen (2 million rows at 1 Hz of 12 sensors) is ~150 MB.
MAX_DATA_BYTES = 2 << 30
_SNIFF_BYTES = 1 << 16
# No linear axis is a kilometre long: beyond this a position is a unit or logging fault.
MAX_ABS_POSITION_MM = 1e6
_BOMS = (
    (b"\xff\xfe\x00\x00", "UTF-32"),
    (b"\x00\x00\xfe\xff", "UTF-32"),
    (b"\xff\xfe", "UTF-16"),
    (b"\xfe\xff", "UTF-16"),
)
_DELIMITER_NAMES = {",": "comma", "\t": "tab", ";": "semicolon", "|": "pipe"}
_INTEGER_PART = re.compile(r"^\s*[-+]?\d+$")
_FRACTION_PART = re.compile(r"^\d+\s*$")
# A zone follows the clock time: "...T09:10:00Z", "... 09:10:00.5+02:00", "...T09:10-0500".
_TIME_ZONE = re.compile(r"[T\s]\d{1,2}:\d{2}(?::\d{2}(?:\.\d*)?)?\s*(?:Z|[+-]\d{2}(?::?\d{2})?)\s*$", re.IGNORECASE)


def _error(path, message: str) -> ValueError:
    # io imports this module at load time, so its error class is looked up on use.
    from .io import DataError

    return DataError(f"{path}: {message}")


def check_name(value, what: str, where) -> str:
    """A dataset, run, source, sensor or measurement name that is safe as a path part."""
    # fullmatch: "$" alone would let a trailing newline through.
    if not isinstance(value, str) or not _NAME.fullmatch(value):
        raise _error(
            where,
            f"{what} {value!r} is not a safe name (expected letters, digits, '_', '.', '-', "
            "starting with a letter, digit or '_', at most 128 characters)",
        )
    return value


def check_regular_file(path, max_bytes: int = MAX_DATA_BYTES, what: str = "file") -> int:
    """Size of ``path`` if it is a regular file within the limit; never opens it."""
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise _error(path, f"{what} not found") from None
    except OSError as exc:
        raise _error(path, f"cannot be read ({exc.strerror})") from None
    if not stat.S_ISREG(info.st_mode):
        raise _error(path, f"not a regular file ({_file_kind(info.st_mode)}); expected a {what}")
    if info.st_size > max_bytes:
        raise _error(path, f"{info.st_size} bytes, larger than the limit of {max_bytes} bytes for a {what}")
    return info.st_size


def _file_kind(mode: int) -> str:
    kinds = (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
    )
    return next((name for test, name in kinds if test(mode)), "a special file")


def check_inside(path, root, what: str = "path") -> Path:
    """``path`` itself, after checking that it resolves inside ``root`` (symlinks followed)."""
    resolved, base = Path(os.path.realpath(path)), Path(os.path.realpath(root))
    if resolved != base and base not in resolved.parents:
        raise _error(path, f"{what} resolves to {resolved}, outside {base}")
    return Path(path)


def check_within(path: str, roots, what: str) -> str:
    """A path pattern (wildcards allowed) that stays below one of ``roots`` once normalised."""
    normal = os.path.normpath(path)
    if os.path.isabs(normal) or not any(normal.startswith(os.path.normpath(r) + os.sep) for r in roots):
        raise _error(what, f"output {path!r} is outside {', '.join(roots)}")
    return path


def check_rule_outputs(rules, roots) -> None:
    """Every output, log and benchmark pattern of every Snakemake rule stays below ``roots``."""
    for rule in rules:
        for path in [*rule.output, *rule.log, *([rule.benchmark] if rule.benchmark else [])]:
            check_within(str(path), roots, f"rule {rule.name}")


def check_dataset_shape(dataset, config) -> None:
    """Dataset-level needs of the workflow, named before any job starts.

    Lists and stats the run folders' data files (safe names, regular files of bounded
    size, inside the dataset) and counts the measurements; nothing is read.
    """
    # The schemas' patterns again, strictly (a JSON-schema "$" accepts a trailing newline).
    sheet = dataset.root / "dataset.yaml"
    check_name(dataset.name, "dataset name", sheet)
    for name in dataset.sensors:
        check_name(name, "sensor", sheet)
    for name in dataset.sources:
        check_name(name, "source", sheet)
    for run in dataset.run_ids:
        check_name(run, "run", dataset.root / "runs.tsv")
        check_inside(dataset.root / run, dataset.root, what="run folder")
        for path in sorted((dataset.root / run / "errors").glob("*.csv")):
            check_name(path.stem, "measurement", path)
        folder = dataset.root / run
        data_files = [*folder.glob("errors/*.csv"), *folder.glob("errors.csv"), *folder.glob("temperatures/*.csv"), *folder.glob("signals/*.csv")]
        for path in sorted(data_files):
            check_inside(path, dataset.root, what="data file")
            check_regular_file(path, what="data file")
    runs_sheet = dataset.root / "runs.tsv"
    if len(dataset.run_ids) < 2:
        raise _error(
            runs_sheet,
            f"{len(dataset.run_ids)} run listed; leave-one-condition-out needs at least 2 runs",
        )
    # A run's measurements in one errors.csv are counted when it is read, not here.
    counts = {run: len(list((dataset.root / run / "errors").glob("*.csv"))) for run in dataset.run_ids}
    if not any((dataset.root / run / "errors.csv").exists() for run in dataset.run_ids) and max(counts.values()) < 2:
        raise _error(
            dataset.root,
            "one measurement per run; the drift (intercept b) and every model need at least 2 measurements "
            "in a run (expected several measurements while the axis heats up)",
        )
    selection = config["selection"]
    n_sensors = len(dataset.sensors)
    if selection["method"] in ("fuzzy_grey", "correlation") and selection["n_clusters"] > n_sensors:
        raise _error(
            "config selection.n_clusters",
            f"{selection['n_clusters']} clusters but {dataset.root / 'dataset.yaml'} declares {n_sensors} "
            f"sensors (expected at most {n_sensors})",
        )


def check_run_plausibility(dataset, raw, cleaning) -> list[str]:
    """Refuse implausible readings or a grid step longer than the run; warn of implausible medians."""
    folder = dataset.root / raw.run

    def file_of(name):
        # One file per measurement, or the run's one errors.csv.
        return raw.error_source if raw.error_source is not None and raw.error_source.is_file() else folder / "errors" / f"{name}.csv"

    for name, measurement in raw.measurements.items():
        path, positions = file_of(name), measurement["position_mm"].to_numpy()
        check_error_readings(path, measurement["error_um"].to_numpy(), cleaning.max_abs_error_um)
        _refuse_first_row(
            path,
            np.abs(positions) > MAX_ABS_POSITION_MM,
            "position_mm",
            lambda i: f"expected a position within ±{MAX_ABS_POSITION_MM:g} mm, got {positions[i]:g}",
        )
    windows = raw.windows()
    overlapping = np.flatnonzero(windows["start"].to_numpy()[1:] < windows["end"].to_numpy()[:-1])
    if overlapping.size:
        earlier, later = windows.iloc[overlapping[0]], windows.iloc[overlapping[0] + 1]
        raise _error(
            file_of(later["name"]),
            f"readings from {later['start']} overlap measurement {earlier['name']} ({earlier['start']} to "
            f"{earlier['end']}); expected one measurement at a time (a copied file?)",
        )
    span_s = (windows["end"].max() - windows["start"].min()).total_seconds()
    interval_s = cleaning.temperatures.interval_s
    if 0 < span_s < interval_s:
        raise _error(
            "config temperatures.interval_s",
            f"{interval_s:g} s is longer than run {raw.run} lasts ({span_s:g} s from its first to its last reading); "
            "expected a grid step well below the time between measurements",
        )
    median_c = cleaning.plausible_median_c
    if not median_c[0] < median_c[1]:
        raise _error("config temperatures.plausible_median_c", f"expected [low, high] with low < high, got [{median_c[0]:g}, {median_c[1]:g}]")
    if dataset.meta.get("temperature_kind", "absolute") == "rise":
        return []  # rises since the start sit near 0 °C by design: no structure-temperature median to judge
    notes = []
    for source, frame in raw.sources.items():
        with np.errstate(over="ignore"):  # the median of two readings near 1e308 is inf: still implausible
            medians = frame.drop(columns="time").median().to_dict()
        notes += sensor_median_warnings(medians, *median_c, where=str(folder / "temperatures" / f"{source}.csv"))
    return notes


def check_same_targets(errors: pd.DataFrame, dataset_root) -> None:
    """Every run reads the same target positions, or the runs cannot share one model."""
    targets = errors.groupby("run", sort=True)["position_mm"].unique()
    first_run = targets.index[0]
    reference = np.sort(targets.iloc[0])
    for run, positions in targets.items():
        positions = np.sort(positions)
        if positions.shape != reference.shape or not np.allclose(positions, reference, rtol=0, atol=1e-6):
            extra = np.setdiff1d(positions, reference)
            lacking = np.setdiff1d(reference, positions)
            detail = f"{extra[0]:g} mm is not a target of run {first_run}" if extra.size else f"{lacking[0]:g} mm is never read"
            raise _error(
                Path(dataset_root) / run / "errors",
                f"run {run} reads {positions.size} target positions, run {first_run} {reference.size} "
                f"({detail}); expected the same targets in every run",
            )


class _GuardedLoader(yaml.SafeLoader):
    """Safe loading without aliases (no alias bombs) and without duplicate keys.

    A repeated key would silently replace the first (a second ``name:`` sends the
    results elsewhere), so it is refused with both line numbers.
    """

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(
                None, None, f"found alias *{event.anchor}; anchors and aliases are not allowed", event.start_mark
            )
        return super().compose_node(parent, index)

    def construct_mapping(self, node, deep=False):
        seen: dict = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                first = seen.setdefault(key, key_node.start_mark.line + 1)
            except TypeError:
                continue  # unhashable: the base class names it
            if first != key_node.start_mark.line + 1:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (first on line {first})", key_node.start_mark
                )
        return super().construct_mapping(node, deep)


def load_yaml(path, max_bytes: int = MAX_SHEET_BYTES):
    """The one loader for dataset sheets: bounded, regular file, UTF-8, guarded YAML."""
    path = Path(path)
    check_regular_file(path, max_bytes, what="YAML file")
    text = _decode(path, path.read_bytes())
    try:
        doc = yaml.load(text, Loader=_GuardedLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        raise _error(path, f"{line}not valid YAML ({getattr(exc, 'problem', None) or exc})") from None
    except RecursionError:
        raise _error(path, "YAML nested too deeply (expected a flat mapping of metadata)") from None
    _check_finite(path, doc, [])
    return doc


def _check_finite(path: Path, node, where: list) -> None:
    """A .inf or .nan anywhere in the sheet (an offset, a target) would poison every number after it."""
    if isinstance(node, float) and not math.isfinite(node):
        raise _error(path, f"{'/'.join(map(str, where)) or 'top level'}: expected a finite number, got {node}")
    children = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, child in children:
        _check_finite(path, child, [*where, key])


def _decode(path: Path, data: bytes) -> str:
    for bom, encoding in _BOMS:
        if data.startswith(bom):
            raise _error(path, f"looks {encoding}-encoded (byte-order mark); expected UTF-8")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise _error(path, f"line {line}: byte 0x{data[exc.start]:02x} is not UTF-8; expected UTF-8 text") from None


def sniff_delimited(path, delimiter: str, max_bytes: int = MAX_DATA_BYTES) -> None:
    """Refuse a delimited file that is not what the layout documents, and say what it looks like.

    Checks the head of the file only (the parser checks the rest): encoding, the
    delimiter of the header, and whether data rows split into more fields than the
    header because of decimal commas.
    """
    path = Path(path)
    check_regular_file(path, max_bytes, what="data file")
    with open(path, "rb") as fh:
        head = fh.read(_SNIFF_BYTES)
    # A multi-byte character may be cut at the end of the sniffed head.
    text = _decode(path, head if len(head) < _SNIFF_BYTES else head[: head.rfind(b"\n") + 1] or head)
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise _error(path, "line 1: empty header; expected a header row")
    expected = _DELIMITER_NAMES[delimiter]
    header = lines[0]
    if delimiter not in header:
        for other, name in _DELIMITER_NAMES.items():
            if other != delimiter and other in header:
                raise _error(path, f"line 1: looks {name}-separated; expected {expected}-separated columns")
    names = [name.strip().strip('"') for name in header.split(delimiter)]
    for k, name in enumerate(names):
        if not name:
            raise _error(path, f"line 1: column {k + 1} has no name; expected a name for every column")
        if name in names[:k]:
            raise _error(path, f"line 1: column {name!r} appears twice; expected each column once")
    _check_field_counts(path, lines[1:20], delimiter, len(names))


def _check_field_counts(path: Path, rows: list[str], delimiter: str, n_fields: int) -> None:
    """Surplus fields would quietly become the parser's index; name them instead.

    Decimal commas add fields to EVERY row of numbers, a stray field to one row only.
    """
    counted = [(lineno, row.split(delimiter)) for lineno, row in enumerate(rows, start=2) if row.strip()]
    surplus = [(lineno, fields) for lineno, fields in counted if len(fields) > n_fields and '"' not in "".join(fields)]
    if not surplus:
        return
    lineno, fields = surplus[0]
    decimal = delimiter == "," and len(surplus) == len(counted) and all(
        _decimal_splits(row) >= len(row) - n_fields for _, row in surplus
    )
    hint = "; looks like decimal commas (expected '.' as the decimal mark)" if decimal else ""
    raise _error(
        path, f"line {lineno}: {len(fields)} {_DELIMITER_NAMES[delimiter]}-separated fields but the header has {n_fields}{hint}"
    )


def _decimal_splits(fields: list[str]) -> int:
    """Adjacent fields that read as one number split at a decimal comma ("-0", "2751")."""
    count, k = 0, 0
    while k + 1 < len(fields):
        if _INTEGER_PART.match(fields[k]) and _FRACTION_PART.match(fields[k + 1]):
            count, k = count + 1, k + 2
        else:
            k += 1
    return count


def check_time_zones(path, values: pd.Series, column: str = "time") -> None:
    """Times carry no zone (one zone per dataset); name the first that does."""
    zoned = values.astype(str).str.contains(_TIME_ZONE).to_numpy()
    _refuse_first_row(
        path, zoned, column, lambda i: f"expected a time without a time zone (one zone per dataset), got {values.iloc[i]!r}"
    )


def check_time_range(path, parsed: pd.Series, values: pd.Series, column: str = "time") -> None:
    """Times the nanosecond clock of the tables can hold (pandas: 1677-09-21 to 2262-04-11)."""
    years = parsed.dt.year.to_numpy()
    _refuse_first_row(
        path, (years < 1678) | (years > 2261), column, lambda i: f"expected a time between 1678 and 2261, got {values.iloc[i]!r}"
    )


def check_error_readings(path, errors_um: np.ndarray, max_abs_um: float) -> None:
    """Interferometer errors are finite and within ``max_abs_um`` (row i is file line i + 2)."""
    errors_um = np.asarray(errors_um, dtype=float)
    bad = ~np.isfinite(errors_um) | (np.abs(errors_um) > max_abs_um)
    _refuse_first_row(
        path,
        bad,
        "error_um",
        lambda i: f"{errors_um[i]:g} um is beyond the plausible ±{max_abs_um:g} um (config errors.max_abs_error_um)",
    )


def _refuse_first_row(path, bad: np.ndarray, column: str, what) -> None:
    """The first flagged row as a file line (row i is line i + 2: the header is line 1)."""
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise _error(path, f"line {i + 2}, column {column!r}: {what(i)}")


def sensor_median_warnings(medians: dict, low_c: float, high_c: float, where: str) -> list[str]:
    """One warning per sensor whose median temperature is implausible for a machine structure."""
    notes = []
    for sensor, median in sorted(medians.items()):
        if not math.isnan(median) and not (low_c <= median <= high_c):
            # Above 200 a kelvin reading is likelier than a Fahrenheit one.
            unit, celsius = ("kelvin", median - 273.15) if median > 200 else ("°F", (median - 32.0) * 5.0 / 9.0)
            notes.append(
                f"{where}: sensor {sensor}: median {median:.1f} °C is outside the plausible {low_c:g}-{high_c:g} °C "
                f"of a machine structure (config temperatures.plausible_median_c); if it is in {unit}, "
                f"that is {celsius:.1f} °C: expected °C"
            )
    return notes


def informative_sensors(temperatures: pd.DataFrame, fixed: tuple[str, ...], where: str, n_clusters: int = 0) -> list[str]:
    """Sensors that vary over the samples; a constant one is named and left out.

    A constant series has no correlation with anything (the fuzzy relation would hold
    NaN), so it cannot be selected; a fixed sensitive point that is constant is an error.
    """
    if len(temperatures) < 2:
        raise _error(where, f"{len(temperatures)} training measurement; selection and models need at least 2")
    spread = temperatures.max() - temperatures.min()
    constant = [str(s) for s in temperatures.columns if not spread[s] > 0]
    fixed_constant = [s for s in constant if s in fixed]
    if fixed_constant:
        raise _error(
            "config selection.fixed",
            f"sensor {fixed_constant[0]} is constant over the training measurements; "
            "expected a sensor whose temperature varies",
        )
    if len(constant) == len(temperatures.columns):
        raise _error(where, "every sensor is constant over the training measurements; expected temperatures that vary")
    for sensor in constant:
        warnings.warn(
            f"{where}: sensor {sensor} is constant over the training measurements; left out of the selection",
            stacklevel=2,
        )
    varying = len(temperatures.columns) - len(constant)
    if n_clusters > varying:
        raise _error(
            "config selection.n_clusters",
            f"{n_clusters} clusters but only {varying} sensors vary over the training measurements of {where} "
            f"(expected at most {varying})",
        )
    return [str(s) for s in temperatures.columns if str(s) not in constant]
