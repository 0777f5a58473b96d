"""The settings model: one parse of the validated config, defaults from the schema only."""

from __future__ import annotations

import dataclasses

import pytest
import yaml

from thermaxis import config as config_module
from thermaxis.config import (
    CleaningSettings,
    DecouplingSettings,
    DisplacementQC,
    FallbackSettings,
    ModelSettings,
    SelectionSettings,
    Settings,
    TemperatureCleaning,
    load_config,
)
from thermaxis.schemas import schema_path

SCHEMA = yaml.safe_load(schema_path("config").read_text(encoding="utf-8"))


def schema_default(*path):
    node = SCHEMA
    for key in path:
        node = node["properties"][key]
    return node["default"]


def test_values_missing_from_the_config_get_the_schema_defaults():
    settings = Settings.from_config({"selection": {"n_clusters": 5}})
    assert settings.selection.n_clusters == 5
    assert settings.selection.rho == schema_default("selection", "rho")
    assert settings.decoupling.degree == schema_default("decoupling", "degree")
    for name in ("C", "epsilon", "gamma"):
        assert list(dict(settings.models.svr_grid)[name]) == schema_default(
            "models", "svr_grid", name
        )
    assert settings.cleaning.temperatures.spike_max_rate_c_per_min == schema_default(
        "temperatures", "spike_max_rate_c_per_min"
    )
    assert list(settings.cleaning.plausible_median_c) == schema_default(
        "temperatures", "plausible_median_c"
    )
    assert settings.compensation.fallback.policy == schema_default("compensation", "fallback")
    assert list(settings.figures.formats) == schema_default("figures", "formats")
    assert list(settings.reports.model_algorithms) == schema_default("reports", "model_algorithms")
    sweep_grid = schema_default("sweep", "svr_grid")
    assert {name: list(values) for name, values in settings.sweep.svr_grid} == sweep_grid
    assert list(settings.sweep.grid.n_clusters) == schema_default("sweep", "n_clusters")


def test_the_dataclasses_have_no_defaults_of_their_own():
    settings_classes = [
        cls
        for name in config_module.__all__
        if dataclasses.is_dataclass(cls := getattr(config_module, name))
    ]
    assert TemperatureCleaning in settings_classes and FallbackSettings in settings_classes
    for cls in settings_classes:
        fields = dataclasses.fields(cls)
        assert all(
            f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            for f in fields
        ), cls
    with pytest.raises(TypeError):
        SelectionSettings()


def test_settings_are_frozen():
    settings = Settings.from_config({})
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.decoupling.degree = 2
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.models = None
    hash(settings)  # frozen all the way down: tuples, not lists


def test_each_section_builds_from_its_config_section():
    assert DecouplingSettings.from_section({"degree": 3}).degree == 3
    selection = SelectionSettings.from_section(
        {
            "method": "fixed",
            "scope": "all",
            "n_clusters": 2,
            "similarity": "printed",
            "grade": "absolute",
            "rho": 0.25,
            "normalisation": "mean",
            "pointwise_common": 2,
            "fixed": {"k": ["T2"], "b": ["T1", "T3"]},
        }
    )
    assert selection.fixed == (("b", ("T1", "T3")), ("k", ("T2",)))
    assert selection.fixed_for("k") == ("T2",)
    models = ModelSettings.from_section(
        {
            "algorithms": ["mlr"],
            "ridge_alpha": 2,
            "lasso_alpha": 0.5,
            "pls_components": 1,
            "svr_kernel": "linear",
            "svr_grid": {"gamma": ["scale"], "C": [3], "epsilon": [0.5]},
            "searched": ["lasso"],
            "search_grids": {"lasso": {"alpha": [0.1, 1]}, "ridge": {"alpha": [2]}},
            "inner_search": {
                "max_loco_runs": 4,
                "group_folds": 3,
                "svr_folds": 2,
                "svr_max_loco_runs": 3,
            },
            "gpr_max_samples": 50,
            "svr_max_samples": 70,
            "interval_level": 0.9,
            "random_state": 7,
            "signals": ["spindle_rpm"],
        }
    )
    assert models.grid() == {"C": [3], "epsilon": [0.5], "gamma": ["scale"]}
    assert models.params_for("ridge") == {"alpha": 2.0} and models.params_for("mlr") is None
    assert models.params_for("lasso") == {"alpha": 0.5}
    # Only the searched algorithms search; the others keep their fixed strength.
    assert (
        models.search_grid_for("lasso") == {"alpha": [0.1, 1]}
        and models.search_grid_for("ridge") is None
    )
    assert (models.inner_search, models.gpr_max_samples) == ((4, 3), 50)
    assert (models.svr_max_samples, models.svr_search_folds) == (70, 2)
    assert models.svr_max_loco_runs == 3
    assert models.signals == ("spindle_rpm",)
    cleaning = CleaningSettings.from_sections(
        {
            "interval_s": 30,
            "spike_threshold": 3,
            "spike_min_deviation_c": 0.1,
            "spike_max_rate_c_per_min": 2.0,
            "spike_window_s": 90,
            "excursions": "fault",
            "limits_c": [-10, 90],
            "max_gap_s": 120,
            "plausible_median_c": [0, 50],
            "allow_long_gaps": True,
            "estimate_clock_offsets": True,
            "reference_source": "",
            "max_offset_s": 60,
            "offset_step_s": 0.5,
            "window": "start",
        },
        {
            "direction": "+",
            "max_missing_fraction": 0.5,
            "max_abs_error_um": 200,
            "outliers": "drop",
            "steps": "refuse",
            "qc_threshold": 8,
            "qc_min_deviation_um": 3,
        },
    )
    assert (cleaning.temperatures.interval_s, cleaning.temperatures.limits_c) == (
        30.0,
        (-10.0, 90.0),
    )
    assert (cleaning.temperatures.spike_window_s, cleaning.temperatures.excursions) == (
        90.0,
        "fault",
    )
    clock = cleaning.temperatures
    assert (clock.reference_source, clock.max_offset_s, clock.offset_step_s) == (None, 60.0, 0.5)
    assert (cleaning.errors.direction, cleaning.max_abs_error_um, cleaning.window) == (
        "+",
        200.0,
        "start",
    )
    assert cleaning.displacement == DisplacementQC(
        outliers="drop", steps="refuse", threshold=8.0, min_deviation_um=3.0
    )


def test_the_sweep_takes_the_models_grid_when_asked():
    settings = Settings.from_config(
        {"sweep": {"svr_grid": "models"}, "models": {"svr_grid": {"C": [2.0]}}}
    )
    # C from the config, epsilon and gamma from the schema's models.svr_grid.
    expected = {"C": [2.0], "epsilon": schema_default("models", "svr_grid", "epsilon"),
                "gamma": schema_default("models", "svr_grid", "gamma")}  # fmt: skip
    assert settings.sweep.models(settings.models).grid() == expected


def test_the_papers_preset_parses_once():
    settings = Settings.from_config(load_config())
    assert (
        settings.selection.method,
        settings.selection.n_clusters,
        settings.decoupling.degree,
    ) == ("fuzzy_grey", 3, 1)


def test_a_bad_value_is_one_line():
    with pytest.raises(ValueError, match="decoupling/degree"):
        Settings.from_config({"decoupling": {"degree": 4}})
