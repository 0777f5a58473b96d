"""The template files: package data, valid string.Template text, every placeholder filled by
its code."""

from __future__ import annotations

import ast
import string
from pathlib import Path

import pytest

from thermaxis import templates

SRC = Path(__file__).resolve().parents[2] / "src" / "thermaxis"
TEMPLATES = sorted(SRC.glob("*/templates/*.tmpl"))


def test_the_templates_are_where_the_package_data_globs_look():
    pyproject = (SRC.parents[1] / "pyproject.toml").read_text(encoding="utf-8")
    assert {p.parent.parent.name for p in TEMPLATES} == {"compensation", "twin"}
    for package in ("compensation", "twin"):
        assert f'"{package}/templates/*.tmpl"' in pyproject


@pytest.mark.parametrize("path", TEMPLATES, ids=lambda p: p.name)
def test_each_template_is_valid_and_names_only_placeholders_its_code_passes(path):
    template = string.Template(path.read_text(encoding="utf-8"))
    assert template.is_valid(), path
    # The modules that fill it pass each placeholder by keyword (dict(...) or
    # fill(..., name=...)).
    fillers = {
        "compensation": ["compensation/plc.py"],
        "twin": ["twin/documents.py", "twin/report.py"],
    }[path.parent.parent.name]
    passed = {
        k.arg
        for filler in fillers
        for node in ast.walk(ast.parse((SRC / filler).read_text()))
        if isinstance(node, ast.Call)
        for k in node.keywords
    }
    assert set(template.get_identifiers()) <= passed, set(template.get_identifiers()) - passed


def test_fill_refuses_a_missing_value():
    with pytest.raises(KeyError, match="n_inputs"):
        templates.fill(
            "thermaxis.compensation",
            "affine_constants.st.tmpl",
            n_regressions=1,
            coefficients="[1.0]",
        )


def test_generated_texts_keep_no_placeholder():
    from thermaxis.compensation.plc import structured_text
    from thermaxis.twin.documents import _readme

    readme = _readme()
    assert "${" not in readme and readme == (
        SRC.parents[1] / "data" / "raw" / "twin" / "README.md"
    ).read_text(encoding="utf-8")
    affine = {
        "sensors": ["T1", "T2"],
        "inputs": [
            {
                "sensor": "T1",
                "temperature": "absolute",
                "training_min_c": 20.0,
                "training_max_c": 30.0,
            },
            {
                "sensor": "T2",
                "temperature": "relative",
                "training_min_c": 0.0,
                "training_max_c": 5.0,
            },
        ],
        "regressions": [
            {"target": "k", "form": "affine", "inputs": [0], "coefficients": [13.0]},
            {"target": "b", "form": "affine", "inputs": [1], "coefficients": [-11.0]},
        ],
        "line_weights": [[0.0, 1.0], [1.0, 0.0]],
        "positions_mm": [185.0, 205.0],
        "reference": {"reference_position_mm": 185.0},
        "fallback": {
            "range_margin_c": 2.0,
            "plausible_c": [-20.0, 120.0],
            "max_rate_c_per_min": 0.5,
            "max_sensor_age_s": 60.0,
            "policy": "hold",
            "ramp_to_zero_min": 30.0,
        },
        "approach": "decoupled",
        "algorithm": "mlr",
        "schema_version": 1,
    }
    text = structured_text(affine, "SIMULATED")
    assert (
        "${" not in text
        and "COEFF : ARRAY[1..2, 1..2] OF LREAL := [13.0, 0.0, 0.0, -11.0];" in text
    )
