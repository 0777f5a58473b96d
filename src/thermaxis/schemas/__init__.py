"""The schemas of the config, the dataset sheets, the import mapping and ``model.json``.

They are package data, so an installed wheel validates exactly as a checkout does.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

import yaml

__all__ = ["SCHEMA_DIR", "schema_path", "load_schema", "load_trusted_yaml"]

SCHEMA_DIR = Path(__file__).resolve().parent
# libyaml's safe loader where PyYAML was built with it: the same safe tags, 8x faster on
# the config schema, which every parse of the Snakefile reads.
_SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def load_trusted_yaml(stream):
    """Safe-load YAML of the project's own (schemas, config): datasets go through
    :func:`thermaxis.dataset.safety.load_yaml`, which also guards their size and aliases."""
    return yaml.load(stream, Loader=_SAFE_LOADER)  # noqa: S506 - a safe loader


def schema_path(name: str) -> Path:
    """The file of schema ``name`` (``config``, ``dataset``, ``runs``, ``import_mapping``, ``compensation_model``)."""
    for suffix in (".schema.yaml", ".schema.json"):
        path = SCHEMA_DIR / f"{name}{suffix}"
        if path.is_file():
            return path
    raise FileNotFoundError(f"no schema {name!r} in {SCHEMA_DIR}")


@cache
def load_schema(name: str) -> dict:
    path = schema_path(name)
    with open(path, encoding="utf-8") as fh:
        return json.load(fh) if path.suffix == ".json" else load_trusted_yaml(fh)
