"""The figure table: one id per figure (stem, caption key, function), explicit conditions."""

from __future__ import annotations

import pytest

from thermaxis.figures import captions, registry

FACTS = registry.Facts(
    dataset_name="twin",
    simulated=True,
    decoupled=True,
    ambient=True,
    run="E1",
    other_runs=["E2", "E3", "E4"],
    folds=["E1", "E2", "E3", "E4"],
    approaches=["decoupled", "pointwise"],
    prediction_algorithms=["mlr", "svr"],
    units={},
    selection={},
    degree=1,
)
# The figures' file stems of the twin before the table was shared by every figure:
# they must not change (results, tests and reports name them).
TWIN_STEMS = [
    "fig2_positioning_error", "fig5_unzeroed", "fig6_error_vs_time", "fig7_error_surface",
    "fig8_rezeroed", "fig3_ambient", "fig9_other_runs", "fig10_temperature_rise",
    "fig12_slope_intercept", "fold_comparison", "recommendation", "selection_stability",
    "error_prediction_{fold}_decoupled_mlr", "error_prediction_{fold}_pointwise_mlr",
    "kb_prediction_{fold}_decoupled_mlr",
    "error_prediction_{fold}_decoupled_svr", "error_prediction_{fold}_pointwise_svr",
    "kb_prediction_{fold}_decoupled_svr",
    "compensation_drift_E1", "compensation_drift_E2", "compensation_drift_E3",
    "compensation_drift_E4",
]  # fmt: skip
# figures.sweep, a library module, names this one without its id's prefix.
NAMED_OTHERWISE = {"sweep_factor_effects": "fig_factor_effects"}


def test_ids_are_unique_and_name_each_drawing_function():
    ids = [e.id for e in registry.FIGURES]
    assert len(ids) == len(set(ids))
    for e in registry.FIGURES:
        name = e.draw.rsplit(".", 1)[1]
        assert name in (e.id, f"fig_{e.id}", NAMED_OTHERWISE.get(e.id)), e.id
        assert callable(registry.function(e.draw)), e.draw
        if e.reader:
            assert callable(registry.function(e.reader)), e.reader


def test_ids_are_the_caption_keys():
    with_captions = {e.id for e in registry.FIGURES if e.caption is not None}
    assert with_captions == set(captions._CAPTIONS)
    assert {figure_id for figure_id, _ in captions._VARIANTS} <= with_captions


def test_every_condition_is_a_fact_and_every_stem_starts_with_its_id():
    facts = {name for name in registry.Facts.__dataclass_fields__}
    for e in registry.FIGURES:
        assert e.when in facts, e.id
        assert e.target in ("all", "sweep", "datasets"), e.id
        assert e.stem.startswith("{id}"), e.id


def test_the_twins_figures_keep_their_stems_and_order():
    figures = registry.expand(FACTS, "all")
    assert [f.stem for f in figures] == TWIN_STEMS
    per_fold = {f.family for f in figures if f.per_fold}
    assert per_fold == {"fig_predictions"}
    assert [f.stem for f in registry.expand(FACTS, "sweep")] == [
        "sweep_heatmap",
        "sweep_factor_effects",
        "sweep_critical_difference",
    ]
    assert [f.stem for f in registry.expand(None, "datasets")] == ["heldout_error"]


@pytest.mark.parametrize(
    "change, gone",
    [
        ({"decoupled": False, "approaches": ["pointwise"]},
         {"fig2_positioning_error", "fig7_error_surface", "fig8_rezeroed", "fig12_slope_intercept",
          "kb_prediction"}),
        ({"ambient": False}, {"fig3_ambient"}),
        ({"other_runs": []}, {"fig9_other_runs"}),
    ],
)  # fmt: skip
def test_conditions_leave_out_exactly_their_figures(change, gone):
    facts = registry.Facts(**{**FACTS.__dict__, **change})
    every = {f.id for f in registry.expand(FACTS, "all")}
    assert {f.id for f in registry.expand(facts, "all")} == every - gone


def test_a_figure_gets_its_facts_and_its_caption():
    by_stem = {f.stem: f for f in registry.expand(FACTS, "all")}
    fig9 = by_stem["fig9_other_runs"]
    assert fig9.arguments == {"runs": ["E2", "E3", "E4"]}
    assert fig9.labels == {"figure": "Fig. 9", "run": "others"}
    fig10 = by_stem["fig10_temperature_rise"]
    assert fig10.tables == {
        "series": "clean/E1/temperatures.parquet",
        "signals": "clean/E1/signals.parquet",
    }
    pointwise = by_stem["error_prediction_{fold}_pointwise_mlr"]
    caption = registry.caption_of(pointwise, FACTS, {"fold": "E4"})
    details = dict(fold="E4", approach="pointwise", algorithm="mlr")
    assert caption == captions.figure_caption("error_prediction", "twin", True, **details)
    assert "paper's Fig. 11." in caption and "fold E4" in caption
    drift = by_stem["compensation_drift_E2"]
    assert drift.arguments == {"fold": "E2"} and drift.tables == {
        "summary": "compensation/folds/E2/summary.csv"
    }
    assert registry.stem_of(
        "kb_prediction", fold="E4", approach="decoupled", algorithm="svr", run="E1"
    ) == ("kb_prediction_E4_decoupled_svr")


def test_a_per_fold_figure_files_its_fold_in_the_report():
    """Snakemake fills report fields from a job's wildcards, and a family's job has none:
    `make report` stopped at `'Wildcards' object has no attribute 'fold'` (issue 62)."""
    by_stem = {f.stem: f for f in registry.expand(FACTS, "all")}
    fields = by_stem["kb_prediction_{fold}_decoupled_svr"].report_fields({"fold": "E3"})
    assert fields == {
        "subcategory": "E3",
        "labels": {"figure": "Figs. 14/16", "fold": "E3", "approach": "decoupled",
                   "algorithm": "svr"},
    }  # fmt: skip
    # A figure of no fold keeps its fields as they are.
    fig9 = by_stem["fig9_other_runs"]
    assert fig9.report_fields({}) == {"subcategory": fig9.subcategory, "labels": fig9.labels}
