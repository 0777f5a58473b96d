"""One vocabulary: the schemas, the models and the display names agree with thermaxis.vocabulary."""

from __future__ import annotations

import copy

import pytest

from thermaxis import vocabulary
from thermaxis.config import validate_config
from thermaxis.schemas import load_schema, schema_path
from thermaxis.vocabulary import ALGORITHMS, APPROACHES

SCHEMAS = ("config", "compensation_model")


def _nodes(node, path=()):
    """Every mapping of a schema with its path of keys."""
    if isinstance(node, dict):
        yield path, node
        for key, value in node.items():
            yield from _nodes(value, (*path, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _nodes(value, (*path, i))


def _inlined(node, defs):
    """The schema with every local ``$ref`` replaced by its target: the schema as it was
    before ``$defs``."""
    if isinstance(node, dict):
        ref = node.get("$ref")
        own = {k: _inlined(v, defs) for k, v in node.items() if k not in ("$ref", "$defs")}
        return {**copy.deepcopy(defs[ref.rsplit("/", 1)[1]]), **own} if ref else own
    if isinstance(node, list):
        return [_inlined(v, defs) for v in node]
    return node


@pytest.mark.parametrize("schema", SCHEMAS)
def test_the_schemas_define_the_vocabulary_once_as_the_code_does(schema):
    doc = load_schema(schema)
    assert tuple(doc["$defs"]["algorithm"]["enum"]) == ALGORITHMS
    assert tuple(doc["$defs"]["approach"]["enum"]) == APPROACHES
    # Every other site refers to $defs: no second list of algorithms or approaches.
    repeated = [
        path
        for path, node in _nodes(doc)
        if path[:1] != ("$defs",) and set(node.get("enum", ())) & {*ALGORITHMS, *APPROACHES}
    ]
    assert repeated == []


def test_every_algorithm_and_approach_setting_of_the_config_refers_to_the_vocabulary():
    refs = {path: node["$ref"] for path, node in _nodes(load_schema("config")) if "$ref" in node}
    assert sorted(
        "/".join(p for p in path if p not in ("properties", "items")) for path in refs
    ) == [
        "compensation/algorithm",
        "compensation/approach",
        "figures/algorithms",
        "models/algorithms",
        "models/searched",
        "recommend/extra_candidates/algorithm",
        "recommend/extra_candidates/approach",
        "reports/model_algorithms",
        "sweep/algorithms",
        "sweep/approaches",
    ]
    config = load_schema("config")["properties"]
    # Every algorithm but lasso and the evidence ridge (candidates of the recommendation,
    # not of the paper's comparison) and both approaches are the defaults, in the
    # vocabulary's order.
    paper_set = tuple(a for a in ALGORITHMS if a not in ("lasso", "bayesridge"))
    assert tuple(config["models"]["properties"]["algorithms"]["default"]) == paper_set
    assert tuple(config["sweep"]["properties"]["algorithms"]["default"]) == paper_set
    assert tuple(config["sweep"]["properties"]["approaches"]["default"]) == APPROACHES


@pytest.mark.parametrize(
    "override",
    [
        {
            "models": {"algorithms": ["svr"]},
            "compensation": {"algorithm": "svr", "approach": "pointwise"},
        },
        {},
    ],
)
def test_refs_fill_defaults_exactly_as_the_inlined_schema_did(tmp_path, override):
    import yaml

    doc = load_schema("config")
    inlined = tmp_path / "inlined.schema.yaml"
    inlined.write_text(yaml.safe_dump(_inlined(doc, doc["$defs"])), encoding="utf-8")
    config = {"dataset": "x", **override}
    assert validate_config(config) == validate_config(config, schema_path=inlined)


@pytest.mark.parametrize(
    "override, where",
    [
        ({"models": {"algorithms": ["elasticnet"]}}, "models/algorithms/0"),
        ({"figures": {"algorithms": ["MLR"]}}, "figures/algorithms/0"),
        ({"reports": {"model_algorithms": ["q"]}}, "reports/model_algorithms/0"),
        ({"sweep": {"algorithms": ["z"]}}, "sweep/algorithms/0"),
        ({"sweep": {"approaches": ["w"]}}, "sweep/approaches/0"),
        ({"compensation": {"algorithm": "x"}}, "compensation/algorithm"),
        ({"compensation": {"approach": "y"}}, "compensation/approach"),
    ],
)
def test_both_validators_resolve_the_refs(override, where):
    from snakemake.exceptions import WorkflowError
    from snakemake.utils import validate

    with pytest.raises(ValueError, match=f"config {where}: .* is not one of"):
        validate_config({"dataset": "x", **override})
    with pytest.raises(WorkflowError):
        validate({"dataset": "x", **override}, str(schema_path("config")), set_default=True)
    filled = {"dataset": "x"}
    validate(filled, str(schema_path("config")), set_default=True)
    assert filled["models"]["algorithms"] == [
        a for a in ALGORITHMS if a not in ("lasso", "bayesridge")
    ]


def test_the_model_schema_refuses_an_unknown_algorithm():
    import jsonschema

    validator = jsonschema.Draft202012Validator(load_schema("compensation_model"))
    # A model's algorithm is one of the vocabulary's, or the recommendation's super learner.
    errors = [
        message
        for e in validator.iter_errors({"approach": "pointwise", "algorithm": "elasticnet"})
        for message in (e.message, *(c.message for c in e.context))
    ]
    assert (
        "'elasticnet' is not one of ['mlr', 'svr', 'ridge', 'lasso', 'pls', 'gpr', 'bayesridge']"
        in errors
    )
    assert "'super learner' was expected" in errors
    assert not any("'pointwise'" in message for message in errors)


def test_the_code_knows_every_algorithm_and_approach():
    from thermaxis.figures.captions import DISPLAY_NAMES
    from thermaxis.method import regressors
    from thermaxis.sweep_grid import LEVEL_ORDER

    assert set(regressors._ALLOWED_PARAMS) == set(ALGORITHMS)
    assert set(ALGORITHMS) | set(APPROACHES) <= set(DISPLAY_NAMES)
    assert LEVEL_ORDER["algorithm"] == ALGORITHMS and LEVEL_ORDER["approach"] == APPROACHES
    assert vocabulary.__all__ == ["APPROACHES", "ALGORITHMS", "SEARCHABLE"]
    assert set(vocabulary.SEARCHABLE) <= set(ALGORITHMS)
