"""The parse-time gate: one validation of the config, every check, the sweep's plan on demand."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

from thermaxis.config import Settings, merge
from thermaxis.errors import DataError
from thermaxis.pipeline import preflight
from thermaxis.schemas import schema_path

REPO = Path(__file__).resolve().parents[2]
TWIN = REPO / "data" / "raw" / "twin"


def base_config(**overrides) -> dict:
    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text(encoding="utf-8"))
    return merge(config, {"dataset": str(TWIN), **overrides})


@pytest.mark.parametrize(
    "overrides",
    [
        {},
        {"dataset": str(REPO / "data" / "raw" / "fl_thermal")},
        {
            "models": {"algorithms": ["mlr"]},
            "sweep": {"svr_grid": "models"},
            "figures": {"dpi": 100},
        },
    ],
)
def test_the_one_validation_fills_what_snakemakes_validate_filled(overrides):
    """The rules read the config the gate validated; notebooks' parameters and
    provenance.json carry its sections, so it must equal (keys in the same order) what
    snakemake.utils.validate(set_default=True) made of the same config."""
    from snakemake.utils import validate

    config = base_config(**overrides)
    checked = preflight.check_before_jobs(copy.deepcopy(config))
    snakemake_filled = copy.deepcopy(config)
    validate(snakemake_filled, str(schema_path("config")), set_default=True)
    assert json.dumps(checked.config) == json.dumps(snakemake_filled)
    assert checked.settings == Settings.from_config(config)


def test_the_config_is_validated_once(monkeypatch):
    calls = []
    original = preflight.validate_config
    monkeypatch.setattr(preflight, "validate_config", lambda c: calls.append(1) or original(c))
    preflight.check_before_jobs(base_config())
    assert len(calls) == 1


@pytest.mark.parametrize(
    "overrides, message",
    [
        (
            {"models": {"algorithms": ["mlr"]}, "compensation": {"algorithm": "svr"}},
            "config compensation.algorithm: 'svr' is not one of models.algorithms (mlr); "
            "its held-out metrics go into model.json",
        ),
        (
            {"sweep": {"folds": ["E9"]}},
            f"config sweep.folds: 'E9' is not a run of {TWIN / 'runs.tsv'}",
        ),
        (
            {"temperatures": {"limits_c": [120, -20]}},
            "limits_c must be (low, high) with low < high",
        ),
    ],
)
def test_checks_that_were_the_rule_files_own_are_the_gates(overrides, message):
    with pytest.raises(ValueError) as refused:
        preflight.check_before_jobs(base_config(**overrides))
    assert str(refused.value).startswith(message), str(refused.value)


def test_the_sweep_plan_waits_for_the_sweep_and_refuses_a_grid_that_fits_nothing():
    fixed = {"k": ["X1"], "b": ["X2"], "pointwise": ["X3"]}
    # The default run does not plan the sweep: a grid that fits nothing passes the gate.
    checked = preflight.check_before_jobs(base_config(sweep={"methods": ["fixed"], "fixed": fixed}))
    with pytest.raises(
        DataError, match=r"^config sweep: no selection setting fits the dataset \(fixed: "
    ):
        preflight.sweep_plan(checked, cores=2, on_cluster=False)


def test_sweep_batches_per_core_locally_and_per_evaluations_on_a_cluster():
    checked = preflight.check_before_jobs(base_config())
    local = preflight.sweep_plan(checked, cores=3, on_cluster=False)
    assert local.batches == 3 and len(local.units) == len(local.unit_sizes)
    assert preflight.sweep_plan(checked, cores=None, on_cluster=False).batches == 1
    per_batch = checked.settings.sweep.cluster_batch_size
    cluster = preflight.sweep_plan(checked, cores=3, on_cluster=True)
    assert cluster.batches == min(-(-local.evaluations // per_batch), len(local.units))
    # A cluster job parses again and must find the same plan.
    assert preflight.sweep_plan(checked, cores=1, on_cluster=True) == cluster


def test_rules_that_write_outside_the_datasets_folders_are_refused():
    checked = preflight.check_before_jobs(base_config())

    def rule(name, output, log=(), benchmark=None):
        return SimpleNamespace(name=name, output=list(output), log=list(log), benchmark=benchmark)

    inside = rule("a", ["results/twin/x.csv"], ["logs/twin/a.log"], "benchmarks/twin/a.tsv")
    preflight.check_rules([inside], checked)
    with pytest.raises(DataError, match="rule b: output 'results/other/x.csv' is outside"):
        preflight.check_rules([inside, rule("b", ["results/other/x.csv"])], checked)


def test_one_line_turns_a_value_error_into_the_workflows_exit():
    with pytest.raises(SystemExit) as stopped, preflight.one_line():
        raise DataError("data/x.csv: line 2: expected a number")
    assert stopped.value.code == "thermaxis error: data/x.csv: line 2: expected a number"
