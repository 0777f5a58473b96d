"""Config: the default preset validates, defaults fill, bad values give one line."""

import pytest

from helpers import REPO
from thermaxis.config import load_config, validate_config


def test_default_config_is_valid_and_is_the_papers_protocol():
    config = load_config()
    assert config["datasets"] == ["data/raw/twin", "data/raw/fl_thermal"]
    assert config["dataset"] == "data/raw/twin"  # the first listed, when none is named
    assert config["selection"]["n_clusters"] == 3
    assert config["selection"]["rho"] == 0.5
    assert config["decoupling"]["degree"] == 1
    assert config["paper_fold"] == "E4"
    assert {"mlr", "svr"} <= set(config["models"]["algorithms"])


def test_paper_sensors_preset_merges():
    config = load_config(REPO / "config" / "config.yaml", REPO / "config" / "paper_sensors.yaml")
    assert config["selection"]["method"] == "fixed"
    assert config["selection"]["fixed"] == {
        "k": ["T1", "T6", "T12"],
        "b": ["T2", "T7", "T11"],
        "pointwise": ["T1", "T11", "T12"],
    }
    assert config["selection"]["n_clusters"] == 3  # untouched keys survive the merge


def test_defaults_fill_missing_sections():
    config = validate_config({"dataset": "x"})
    assert config["temperatures"]["interval_s"] == 10
    assert config["errors"]["direction"] == "mean"


@pytest.mark.parametrize(
    "override, message",
    [
        ({"decoupling": {"degree": 4}}, "decoupling/degree: 4 is greater than the maximum of 3"),
        ({"selection": {"method": "magic"}}, "selection/method: 'magic' is not one of"),
        ({"temperatures": {"spike_threshold": 0}}, "temperatures/spike_threshold"),
        ({"models": {"algorithms": ["mlr", "xgb"]}}, "models/algorithms/1: 'xgb' is not one of"),
        ({"unknown_key": 1}, "Additional properties are not allowed"),
    ],
)
def test_bad_values_are_rejected(override, message):
    with pytest.raises(ValueError) as exc:
        load_config(overrides=override)
    assert message in str(exc.value)
    assert "\n" not in str(exc.value)
