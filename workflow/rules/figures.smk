# The figures, from a table (showyourwork): one rule per entry, each reading tables the
# computing rules wrote, so a cosmetic change reruns only the plots. An entry names its
# plotting function, the tables passed to it (by argument name) and its fixed arguments;
# wildcards (fold, approach, algorithm) are passed too. The rule is named after the
# figure's stem unless the entry names it.
from functools import partial

ERRORS = f"{OUT}/assembled/errors.parquet"
DATA_CATEGORY = "2. Errors and temperatures"
RUN_FIGURES = {
    "fig2_positioning_error": ("fig2", "Fig. 2"),
    "fig5_unzeroed": ("fig5", "Fig. 5"),
    "fig6_error_vs_time": ("fig6", "Fig. 6"),
    "fig7_error_surface": ("fig7", "Fig. 7"),
    "fig8_rezeroed": ("fig8", "Fig. 8"),
}
FIGURES = [
    *(
        dict(
            stem=stem,
            draw=stem,
            inputs={"errors": ERRORS},
            arguments={"run": FIG_RUN},
            category=DATA_CATEGORY,
            labels={"figure": label, "run": FIG_RUN},
            caption=figure_caption(figure_id, DATASET.name, SIMULATED, run=FIG_RUN),
        )
        for stem, (figure_id, label) in RUN_FIGURES.items()
    ),
    dict(
        stem="fig3_ambient",
        draw="fig3_ambient",
        inputs={"ambient": f"{OUT}/tables/ambient_series.parquet"},
        category=DATA_CATEGORY,
        labels={"figure": "Fig. 3", "run": "all"},
        caption=figure_caption("fig3", DATASET.name, SIMULATED),
    ),
    dict(
        stem="fig9_other_runs",
        draw="fig9_other_runs",
        inputs={"errors": ERRORS},
        arguments={"runs": OTHER_RUNS},
        category=DATA_CATEGORY,
        labels={"figure": "Fig. 9", "run": "others"},
        caption=figure_caption("fig9", DATASET.name, SIMULATED, runs=OTHER_RUNS),
    ),
    dict(
        stem="fig10_temperature_rise",
        draw="fig10_temperature_rise",
        inputs={
            "series": f"{OUT}/clean/{FIG_RUN}/temperatures.parquet",
            "signals": f"{OUT}/clean/{FIG_RUN}/signals.parquet",
        },
        arguments={"units": DATASET.signal_units()},
        category=DATA_CATEGORY,
        labels={"figure": "Fig. 10", "run": FIG_RUN},
        caption=figure_caption("fig10", DATASET.name, SIMULATED, run=FIG_RUN),
    ),
    dict(
        stem="fig12_slope_intercept",
        draw="fig12_slope_intercept",
        inputs={"kb": f"{OUT}/tables/table5_slope_intercept.csv"},
        category="3. Decoupling",
        labels={"figure": "Fig. 12", "run": "all"},
        caption=figure_caption("fig12", DATASET.name, SIMULATED),
    ),
    dict(
        name="fig_kb_prediction",
        stem="kb_prediction_{fold}_{approach}_{algorithm}",
        draw="fig_kb_prediction",
        inputs={"kb_pred": f"{OUT}/tables/kb_predictions.csv"},
        category="5. Prediction",
        subcategory="{fold}",
        labels={
            "figure": "Figs. 14/16",
            "fold": "{fold}",
            "approach": "{approach}",
            "algorithm": "{algorithm}",
        },
        caption=partial(prediction_caption, "kb_prediction"),
    ),
    dict(
        name="fig_error_prediction",
        stem="error_prediction_{fold}_{approach}_{algorithm}",
        draw="fig_error_prediction",
        inputs={"err_pred": f"{OUT}/tables/error_predictions.csv"},
        category="5. Prediction",
        subcategory="{fold}",
        labels={
            "figure": "Figs. 11/15/17",
            "fold": "{fold}",
            "approach": "{approach}",
            "algorithm": "{algorithm}",
        },
        caption=partial(prediction_caption, "error_prediction"),
    ),
    dict(
        name="fig_fold_comparison",
        stem="fold_comparison",
        draw="fig_fold_comparison",
        inputs={"metrics": f"{OUT}/tables/metrics.csv"},
        category="5. Prediction",
        labels={"figure": "fold comparison", "fold": "all"},
        caption=figure_caption(
            "fold_comparison", DATASET.name, SIMULATED, target="error"
        ),
    ),
]


for fig in FIGURES:

    rule:
        name:
            fig.get("name", fig["stem"])
        input:
            **fig["inputs"],
            code=code_of("plot.py"),
        output:
            figures=report(
                figure_paths(fig["stem"]),
                caption="../report/figure.rst",
                category=fig["category"],
                subcategory=fig.get("subcategory"),
                labels=fig["labels"],
            ),
        log:
            f"{LOGS}/figures/{fig['stem']}.log",
        benchmark:
            f"{BENCH}/figures/{fig['stem']}.tsv"
        conda:
            ENV
        resources:
            mem_mb=lambda w, attempt: 500 * attempt,
            runtime=lambda w, attempt: 5 * attempt,
        params:
            draw=fig["draw"],
            arguments=fig.get("arguments", {}),
            caption=fig["caption"],
            simulated=SIMULATED,
            dpi=config["figures"]["dpi"],
        script:
            "../scripts/plot.py"
