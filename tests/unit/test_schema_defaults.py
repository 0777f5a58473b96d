"""Defaults live only in the schemas: every default the code uses equals the schema's.

The schemas are parsed here with plain ``yaml.safe_load``, apart from the library's
reader, so a second copy of a default in the code fails one of these.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from helpers.builders import write_dataset
from thermaxis.config import Settings, schema_default
from thermaxis.dataset.reader import load_dataset
from thermaxis.method.estimators import DecoupledAxisModel, PointwiseAxisModel

SCHEMAS = Path(__file__).resolve().parents[2] / "src" / "thermaxis" / "schemas"


def _schema(name: str) -> dict:
    return yaml.safe_load((SCHEMAS / f"{name}.schema.yaml").read_text(encoding="utf-8"))


CONFIG = _schema("config")["properties"]
MODELS = CONFIG["models"]["properties"]
INNER = MODELS["inner_search"]["properties"]
PAPER_SENSORS = CONFIG["sweep"]["properties"]["fixed"]["default"]

# Every keyword default of the estimators the schema has a default for.
COMMON = {
    "algorithm": CONFIG["compensation"]["properties"]["algorithm"]["default"],
    "random_state": MODELS["random_state"]["default"],
    "signals": tuple(MODELS["signals"]["default"]),
    "inner_search": (INNER["max_loco_runs"]["default"], INNER["group_folds"]["default"]),
    "gpr_max_samples": MODELS["gpr_max_samples"]["default"],
    "svr_max_samples": MODELS["svr_max_samples"]["default"],
    "svr_search_folds": INNER["svr_folds"]["default"],
    "svr_max_loco_runs": INNER["svr_max_loco_runs"]["default"],
}


@pytest.mark.parametrize(
    "estimator, own",
    [
        (
            DecoupledAxisModel,
            {
                "k_sensors": tuple(PAPER_SENSORS["k"]),
                "b_sensors": tuple(PAPER_SENSORS["b"]),
                "degree": CONFIG["decoupling"]["properties"]["degree"]["default"],
            },
        ),
        (PointwiseAxisModel, {"sensors": tuple(PAPER_SENSORS["pointwise"])}),
    ],
)
def test_estimator_defaults_are_the_schemas(estimator, own):
    params = estimator().get_params()
    expected = {**COMMON, **own}
    assert {name: params[name] for name in expected} == expected
    # No other default is a value: the rest are None (chosen from the settings when fitted).
    assert all(params[name] is None for name in set(params) - set(expected))


def test_temperature_cleaning_takes_the_schemas_clock_search():
    temperatures = CONFIG["temperatures"]["properties"]
    cleaning = Settings.from_config({}).cleaning.temperatures
    assert cleaning.max_offset_s == temperatures["max_offset_s"]["default"] == 120.0
    assert cleaning.offset_step_s == temperatures["offset_step_s"]["default"] == 1.0
    assert temperatures["reference_source"]["default"] == ""
    assert cleaning.reference_source is None  # empty: the source with most sensors


def test_schema_default_reads_nested_keys_and_returns_a_copy():
    assert schema_default("models", "inner_search", "group_folds") == 5
    grid = schema_default("models", "svr_grid")
    assert grid == {"C": [0.1, 1.0, 10.0, 100.0], "epsilon": [0.01, 0.1], "gamma": ["scale", 0.1]}
    grid["C"].append(1e6)
    assert schema_default("models", "svr_grid")["C"] == [0.1, 1.0, 10.0, 100.0]


def test_dataset_sheet_defaults_are_the_schemas(tmp_path):
    schema = _schema("dataset")["properties"]
    root = write_dataset(tmp_path / "d")
    sheet = root / "dataset.yaml"
    meta = yaml.safe_load(sheet.read_text(encoding="utf-8"))
    for source in meta["sources"]:
        source.pop("clock_offset_s")
    assert "signals" not in meta and "temperature_kind" not in meta
    sheet.write_text(yaml.safe_dump(meta, sort_keys=False), encoding="utf-8")

    dataset = load_dataset(root)
    assert dataset.temperature_kind == schema["temperature_kind"]["default"] == "absolute"
    assert list(dataset.signals) == schema["signals"]["default"] == []
    offset = schema["sources"]["items"]["properties"]["clock_offset_s"]["default"]
    assert dataset.clock_offsets_s() == {"box": offset} == {"box": 0.0}
