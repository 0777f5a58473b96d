"""Defences against hostile or broken datasets.

Datasets are untrusted input; config files and the workflow are trusted code (the trust
model of docs/security.md).  Everything here turns a dataset that could escape the results
folder, hang the workflow, exhaust memory or slip an implausible value into a model
into ONE line naming the file, the line or column and what was expected
(:class:`thermaxis.errors.DataError`).  Checks run before a file is parsed: a FIFO is
never opened, a YAML alias is never expanded, a file's size is known before it is read.
"""

from __future__ import annotations

import math
import os
import re
import stat
from pathlib import Path

import yaml

from thermaxis.errors import DataError

__all__ = [
    "NAME_PATTERN",
    "MAX_SHEET_BYTES",
    "MAX_DATA_BYTES",
    "check_name",
    "check_regular_file",
    "check_inside",
    "check_within",
    "check_rule_outputs",
    "field_count_hint",
    "load_yaml",
    "sniff_delimited",
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
_BOMS = (
    (b"\xff\xfe\x00\x00", "UTF-32"),
    (b"\x00\x00\xfe\xff", "UTF-32"),
    (b"\xff\xfe", "UTF-16"),
    (b"\xfe\xff", "UTF-16"),
)
_DELIMITER_NAMES = {",": "comma", "\t": "tab", ";": "semicolon", "|": "pipe"}
_INTEGER_PART = re.compile(r"^\s*[-+]?\d+$")
_FRACTION_PART = re.compile(r"^\d+\s*$")


def _error(path, message: str) -> DataError:
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
        raise _error(
            path, f"{info.st_size} bytes, larger than the limit of {max_bytes} bytes for a {what}"
        )
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
    if os.path.isabs(normal) or not any(
        normal.startswith(os.path.normpath(r) + os.sep) for r in roots
    ):
        raise _error(what, f"output {path!r} is outside {', '.join(roots)}")
    return path


def check_rule_outputs(rules, roots) -> None:
    """Every output, log and benchmark pattern of every Snakemake rule stays below ``roots``."""
    for rule in rules:
        for path in [*rule.output, *rule.log, *([rule.benchmark] if rule.benchmark else [])]:
            check_within(str(path), roots, f"rule {rule.name}")


class _GuardedLoader(yaml.SafeLoader):
    """Safe loading without aliases (no alias bombs) and without duplicate keys.

    A repeated key would silently replace the first (a second ``name:`` sends the
    results elsewhere), so it is refused with both line numbers.
    """

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(
                None,
                None,
                f"found alias *{event.anchor}; anchors and aliases are not allowed",
                event.start_mark,
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
                    None,
                    None,
                    f"duplicate key {key!r} (first on line {first})",
                    key_node.start_mark,
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
        raise _error(
            path, f"{line}not valid YAML ({getattr(exc, 'problem', None) or exc})"
        ) from None
    except RecursionError:
        raise _error(path, "YAML nested too deeply (expected a flat mapping of metadata)") from None
    check_finite(path, doc)
    return doc


def check_finite(path, node, where: list | None = None) -> None:
    """A .inf or .nan anywhere in a document (a sheet's offset, a model's coefficient)
    would poison every number after it; ``where`` is the path to ``node``."""
    where = where or []
    if isinstance(node, float) and not math.isfinite(node):
        raise _error(
            path,
            f"{'/'.join(map(str, where)) or 'top level'}: expected a finite number, got {node}",
        )
    children = (
        node.items()
        if isinstance(node, dict)
        else enumerate(node)
        if isinstance(node, list)
        else ()
    )
    for key, child in children:
        check_finite(path, child, [*where, key])


def _decode(path: Path, data: bytes) -> str:
    for bom, encoding in _BOMS:
        if data.startswith(bom):
            raise _error(path, f"looks {encoding}-encoded (byte-order mark); expected UTF-8")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise _error(
            path, f"line {line}: byte 0x{data[exc.start]:02x} is not UTF-8; expected UTF-8 text"
        ) from None


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
    text = _decode(
        path, head if len(head) < _SNIFF_BYTES else head[: head.rfind(b"\n") + 1] or head
    )
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise _error(path, "line 1: empty header; expected a header row")
    expected = _DELIMITER_NAMES[delimiter]
    header = lines[0]
    if delimiter not in header:
        for other, name in _DELIMITER_NAMES.items():
            if other != delimiter and other in header:
                raise _error(
                    path, f"line 1: looks {name}-separated; expected {expected}-separated columns"
                )
    names = [name.strip().strip('"') for name in header.split(delimiter)]
    for k, name in enumerate(names):
        if not name:
            raise _error(
                path, f"line 1: column {k + 1} has no name; expected a name for every column"
            )
        if name in names[:k]:
            raise _error(path, f"line 1: column {name!r} appears twice; expected each column once")
    _check_field_counts(path, lines[1:20], delimiter, names)


def field_count_hint(delimiter: str, names) -> str:
    """What a row with too many fields should have, and the likely cause of a tab-separated one."""
    expected = f"; expected {len(names)} fields ({', '.join(names)})"
    if delimiter == "\t":
        return f"{expected}: a tab inside a text (a description?) is the likely cause; replace it with a space"
    return expected


def _check_field_counts(path: Path, rows: list[str], delimiter: str, names: list[str]) -> None:
    """Surplus fields would quietly become the parser's index; name them instead.

    Decimal commas add fields to EVERY row of numbers, a stray field to one row only.
    """
    n_fields = len(names)
    counted = [
        (lineno, row.split(delimiter)) for lineno, row in enumerate(rows, start=2) if row.strip()
    ]
    surplus = [
        (lineno, fields)
        for lineno, fields in counted
        if len(fields) > n_fields and '"' not in "".join(fields)
    ]
    if not surplus:
        return
    lineno, fields = surplus[0]
    decimal = (
        delimiter == ","
        and len(surplus) == len(counted)
        and all(_decimal_splits(row) >= len(row) - n_fields for _, row in surplus)
    )
    hint = (
        "; looks like decimal commas (expected '.' as the decimal mark)"
        if decimal
        else field_count_hint(delimiter, names)
    )
    raise _error(
        path,
        f"line {lineno}: {len(fields)} {_DELIMITER_NAMES[delimiter]}-separated fields but the header has {n_fields}{hint}",
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
