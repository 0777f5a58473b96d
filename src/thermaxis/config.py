"""The workflow's configuration outside Snakemake: safe-loaded, validated, defaults filled.

The Snakefile validates with ``snakemake.utils.validate``; this module applies the same
schema (``workflow/schemas/config.schema.yaml``) so that the library, the sweep and the
tests see exactly the configuration the workflow sees.
"""

from __future__ import annotations

import copy
from pathlib import Path

import jsonschema
import yaml

__all__ = ["CONFIG_SCHEMA", "load_config", "validate_config", "merge", "dataset_of"]

REPO = Path(__file__).resolve().parents[2]
CONFIG_SCHEMA = REPO / "workflow" / "schemas" / "config.schema.yaml"


def merge(base: dict, update: dict) -> dict:
    """Recursive update, as Snakemake merges several --configfile files."""
    out = copy.deepcopy(base)
    for key, value in update.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _fill_defaults(instance: dict, schema: dict) -> None:
    for key, sub in schema.get("properties", {}).items():
        if "default" in sub and key not in instance:
            instance[key] = copy.deepcopy(sub["default"])
        if isinstance(instance.get(key), dict) and sub.get("type") == "object":
            _fill_defaults(instance[key], sub)


def validate_config(config: dict, schema_path=CONFIG_SCHEMA) -> dict:
    """Return a validated copy with defaults filled; raise ValueError with one line otherwise."""
    with open(schema_path, encoding="utf-8") as fh:
        schema = yaml.safe_load(fh)
    filled = copy.deepcopy(config)
    _fill_defaults(filled, schema)
    errors = sorted(jsonschema.Draft202012Validator(schema).iter_errors(filled), key=lambda e: list(e.absolute_path))
    if errors:
        where = "/".join(map(str, errors[0].absolute_path)) or "top level"
        raise ValueError(f"config {where}: {errors[0].message}")
    filled["dataset"] = dataset_of(filled)
    return filled


def dataset_of(config: dict) -> str:
    """The dataset folder of one run: ``dataset`` if given, else the first of ``datasets``."""
    return config.get("dataset") or config["datasets"][0]


def load_config(*paths, overrides: dict | None = None) -> dict:
    """Safe-load one or more YAML files (later ones win), apply overrides, validate."""
    config: dict = {}
    for path in paths or (REPO / "config" / "config.yaml",):
        with open(path, encoding="utf-8") as fh:
            doc = yaml.safe_load(fh) or {}
        if not isinstance(doc, dict):
            raise ValueError(f"{path}: expected a mapping at top level")
        config = merge(config, doc)
    if overrides:
        config = merge(config, overrides)
    return validate_config(config)
