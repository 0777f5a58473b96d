# The figures, from a table (showyourwork): an entry names its figure's stem, the
# function that draws it ("package.module.function" in thermaxis), the tables passed to it by
# argument name, its fixed arguments and how the report files it. Entries are drawn in
# families, one job per family (per fold for a fold's predictions), because starting
# Python and importing matplotlib costs more than drawing a figure. A family reads only
# tables the computing rules wrote, so a cosmetic change reruns only plots.

ERRORS = f"{OUT}/assembled/errors.parquet"
DATA_CATEGORY = "2. Errors and temperatures"
PREDICTION_CATEGORY = "5. Prediction"
# Figures along the stroke (2, 7, 8) need several positions; the others are drawn
# against time when there is one.
RUN_FIGURES = {
    "fig2_positioning_error": ("fig2", "Fig. 2", DECOUPLED),
    "fig5_unzeroed": ("fig5", "Fig. 5", True),
    "fig6_error_vs_time": ("fig6", "Fig. 6", True),
    "fig7_error_surface": ("fig7", "Fig. 7", DECOUPLED),
    "fig8_rezeroed": ("fig8", "Fig. 8", DECOUPLED),
}


def prediction_entry(kind, approach, algorithm, draw, tables, label):
    stem = f"{kind}_{{fold}}_{approach}_{algorithm}"
    return dict(
        family="fig_predictions",
        stem=stem,
        draw=draw,
        inputs=tables,
        arguments={"approach": approach, "algorithm": algorithm},
        category=PREDICTION_CATEGORY,
        subcategory="{fold}",
        labels={
            "figure": label,
            "fold": "{fold}",
            "approach": approach,
            "algorithm": algorithm,
        },
        caption=lambda w: prediction_caption(kind, w["fold"], approach, algorithm),
    )


FIGURES = [
    *(
        dict(
            family="fig_data",
            stem=stem,
            draw=f"figures.paper.{stem}",
            inputs={"errors": ERRORS},
            arguments={"run": FIG_RUN},
            category=DATA_CATEGORY,
            labels={"figure": label, "run": FIG_RUN},
            caption=figure_caption(figure_id, DATASET.name, SIMULATED, run=FIG_RUN),
        )
        for stem, (figure_id, label, drawn) in RUN_FIGURES.items()
        if drawn
    ),
    *[
        dict(
            family="fig_data",
            stem="fig3_ambient",
            draw="figures.paper.fig3_ambient",
            inputs={"ambient": f"{OUT}/tables/ambient_series.parquet"},
            category=DATA_CATEGORY,
            labels={"figure": "Fig. 3", "run": "all"},
            caption=figure_caption("fig3", DATASET.name, SIMULATED),
        )
    ]
    * bool(AMBIENT),
    *[
        dict(
            family="fig_data",
            stem="fig9_other_runs",
            draw="figures.paper.fig9_other_runs",
            inputs={"errors": ERRORS},
            arguments={"runs": OTHER_RUNS},
            category=DATA_CATEGORY,
            labels={"figure": "Fig. 9", "run": "others"},
            caption=figure_caption("fig9", DATASET.name, SIMULATED, runs=OTHER_RUNS),
        )
    ]
    * bool(OTHER_RUNS),
    dict(
        family="fig_data",
        stem="fig10_temperature_rise",
        draw="figures.paper.fig10_temperature_rise",
        inputs={
            "series": f"{OUT}/clean/{FIG_RUN}/temperatures.parquet",
            "signals": f"{OUT}/clean/{FIG_RUN}/signals.parquet",
        },
        arguments={"units": DATASET.signal_units()},
        category=DATA_CATEGORY,
        labels={"figure": "Fig. 10", "run": FIG_RUN},
        caption=figure_caption("fig10", DATASET.name, SIMULATED, run=FIG_RUN),
    ),
    *[
        dict(
            family="fig_slope_intercept",
            stem="fig12_slope_intercept",
            draw="figures.paper.fig12_slope_intercept",
            inputs={"kb": f"{OUT}/tables/table5_slope_intercept.csv"},
            category="3. Decoupling",
            labels={"figure": "Fig. 12", "run": "all"},
            caption=figure_caption("fig12", DATASET.name, SIMULATED),
        )
    ]
    * DECOUPLED,
    dict(
        family="fig_fold_comparison",
        stem="fold_comparison",
        draw="figures.predictions.fig_fold_comparison",
        inputs={"metrics": f"{OUT}/tables/metrics.csv"},
        category=PREDICTION_CATEGORY,
        labels={"figure": "fold comparison", "fold": "all"},
        caption=figure_caption(
            "fold_comparison", DATASET.name, SIMULATED, target="error"
        ),
    ),
    *(
        entry
        for algorithm in PREDICTION_ALGORITHMS
        for entry in [
            *(
                prediction_entry(
                    "error_prediction",
                    approach,
                    algorithm,
                    "figures.predictions.fig_error_prediction",
                    {"err_pred": f"{OUT}/tables/error_predictions.csv"},
                    "Figs. 11/15/17",
                )
                for approach in APPROACHES
            ),
            *[
                prediction_entry(
                    "kb_prediction",
                    "decoupled",
                    algorithm,
                    "figures.predictions.fig_kb_prediction",
                    {"kb_pred": f"{OUT}/tables/kb_predictions.csv"},
                    "Figs. 14/16",
                )
            ]
            * DECOUPLED,
        ]
    ),
    # The drift of each compensated held-out run (compensation.smk), all in one job.
    *(
        dict(
            family="fig_compensation_drift",
            stem=f"compensation_drift_{fold}",
            draw="figures.compensation.fig_compensation_drift",
            inputs={"summary": f"{COMP}/folds/{fold}/summary.csv"},
            arguments={"fold": fold},
            category="6. Compensation",
            labels={"figure": "thermal drift", "fold": fold},
            caption=figure_caption(
                "compensation_drift", DATASET.name, SIMULATED, fold=fold
            ),
        )
        for fold in FOLDS
    ),
]
FIGURE_FAMILIES = {}
for fig in FIGURES:
    FIGURE_FAMILIES.setdefault(fig["family"], []).append(fig)


def figure_stems():
    """Every figure's stem, a fold's figures once per fold, in table order."""
    return [
        fig["stem"].format(fold=fold)
        for fig in FIGURES
        for fold in (FOLDS if "{fold}" in fig["stem"] else [None])
    ]


def figure_specs(entries, wildcards):
    """What plot.py draws: per figure its function, tables, arguments, files and caption."""
    specs = []
    for fig in entries:
        stem = fig["stem"].format(**wildcards)
        caption = fig["caption"]
        specs.append(
            dict(
                stem=stem,
                draw=fig["draw"],
                tables={k: v.format(**wildcards) for k, v in fig["inputs"].items()},
                arguments={**fig.get("arguments", {}), **wildcards},
                paths=figure_paths(stem),
                caption=caption(wildcards) if callable(caption) else caption,
            )
        )
    return specs


for family, entries in FIGURE_FAMILIES.items():
    # A family whose stems hold the fold is one job per fold.
    per_fold = any("{fold}" in fig["stem"] for fig in entries)
    where = f"{family}_{{fold}}" if per_fold else family

    rule:
        name:
            family
        input:
            tables=sorted({path for fig in entries for path in fig["inputs"].values()}),
            code=code_of("plot.py"),
        output:
            *(
                report(
                    figure_paths(fig["stem"]),
                    caption="../report/figure.rst",
                    category=fig["category"],
                    subcategory=fig.get("subcategory"),
                    labels=fig["labels"],
                )
                for fig in entries
            ),
        log:
            f"{LOGS}/figures/{where}.log",
        benchmark:
            f"{BENCH}/figures/{where}.tsv"
        conda:
            ENV
        resources:
            mem_mb=lambda w, attempt: 500 * attempt,
            runtime=lambda w, attempt: 5 * attempt,
        params:
            figures=lambda w, entries=entries: figure_specs(entries, dict(w.items())),
            simulated=SIMULATED,
            dpi=SETTINGS.figures.dpi,
        script:
            "../scripts/plot.py"
