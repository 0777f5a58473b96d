# One rule per figure (showyourwork): every figure reads tables the computing rules
# wrote, so a cosmetic change reruns only the plots.


rule fig2_positioning_error:
    input:
        code=lib("plotting", "captions"),
        errors=f"{OUT}/assembled/errors.parquet",
    output:
        figures=report(
            figure_paths("fig2_positioning_error"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 2", "run": FIG_RUN},
        ),
    log:
        f"{LOGS}/figures/fig2.log",
    benchmark:
        f"{BENCH}/figures/fig2.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        run=FIG_RUN,
        caption=figure_caption("fig2", DATASET.name, SIMULATED, run=FIG_RUN),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig3_ambient:
    input:
        code=lib("plotting", "captions"),
        series=expand(f"{OUT}/clean/{{run}}/temperatures.parquet", run=RUNS),
    output:
        figures=report(
            figure_paths("fig3_ambient"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 3", "run": "all"},
        ),
    log:
        f"{LOGS}/figures/fig3.log",
    benchmark:
        f"{BENCH}/figures/fig3.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        runs=RUNS,
        sensor=config["ambient_sensor"],
        caption=figure_caption("fig3", DATASET.name, SIMULATED),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig5_unzeroed:
    input:
        code=lib("plotting", "captions"),
        errors=f"{OUT}/assembled/errors.parquet",
    output:
        figures=report(
            figure_paths("fig5_unzeroed"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 5", "run": FIG_RUN},
        ),
    log:
        f"{LOGS}/figures/fig5.log",
    benchmark:
        f"{BENCH}/figures/fig5.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        run=FIG_RUN,
        caption=figure_caption("fig5", DATASET.name, SIMULATED, run=FIG_RUN),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig6_error_vs_time:
    input:
        code=lib("plotting", "captions"),
        errors=f"{OUT}/assembled/errors.parquet",
    output:
        figures=report(
            figure_paths("fig6_error_vs_time"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 6", "run": FIG_RUN},
        ),
    log:
        f"{LOGS}/figures/fig6.log",
    benchmark:
        f"{BENCH}/figures/fig6.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        run=FIG_RUN,
        caption=figure_caption("fig6", DATASET.name, SIMULATED, run=FIG_RUN),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig7_error_surface:
    input:
        code=lib("plotting", "captions"),
        errors=f"{OUT}/assembled/errors.parquet",
    output:
        figures=report(
            figure_paths("fig7_error_surface"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 7", "run": FIG_RUN},
        ),
    log:
        f"{LOGS}/figures/fig7.log",
    benchmark:
        f"{BENCH}/figures/fig7.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        run=FIG_RUN,
        caption=figure_caption("fig7", DATASET.name, SIMULATED, run=FIG_RUN),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig8_rezeroed:
    input:
        code=lib("plotting", "captions"),
        errors=f"{OUT}/assembled/errors.parquet",
    output:
        figures=report(
            figure_paths("fig8_rezeroed"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 8", "run": FIG_RUN},
        ),
    log:
        f"{LOGS}/figures/fig8.log",
    benchmark:
        f"{BENCH}/figures/fig8.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        run=FIG_RUN,
        caption=figure_caption("fig8", DATASET.name, SIMULATED, run=FIG_RUN),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig9_other_runs:
    input:
        code=lib("plotting", "captions"),
        errors=f"{OUT}/assembled/errors.parquet",
    output:
        figures=report(
            figure_paths("fig9_other_runs"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 9", "run": "others"},
        ),
    log:
        f"{LOGS}/figures/fig9.log",
    benchmark:
        f"{BENCH}/figures/fig9.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        runs=OTHER_RUNS,
        caption=figure_caption("fig9", DATASET.name, SIMULATED, runs=OTHER_RUNS),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig10_temperature_rise:
    input:
        code=lib("plotting", "captions"),
        series=f"{OUT}/clean/{FIG_RUN}/temperatures.parquet",
    output:
        figures=report(
            figure_paths("fig10_temperature_rise"),
            caption="../report/figure.rst",
            category="2. Errors and temperatures",
            labels={"figure": "Fig. 10", "run": FIG_RUN},
        ),
    log:
        f"{LOGS}/figures/fig10.log",
    benchmark:
        f"{BENCH}/figures/fig10.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        run=FIG_RUN,
        caption=figure_caption("fig10", DATASET.name, SIMULATED, run=FIG_RUN),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig12_slope_intercept:
    input:
        code=lib("plotting", "captions"),
        kb=f"{OUT}/tables/table5_slope_intercept.csv",
    output:
        figures=report(
            figure_paths("fig12_slope_intercept"),
            caption="../report/figure.rst",
            category="3. Decoupling",
            labels={"figure": "Fig. 12", "run": "all"},
        ),
    log:
        f"{LOGS}/figures/fig12.log",
    benchmark:
        f"{BENCH}/figures/fig12.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        caption=figure_caption("fig12", DATASET.name, SIMULATED),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig_kb_prediction:
    input:
        code=lib("plotting", "captions"),
        kb=f"{OUT}/tables/kb_predictions.csv",
    output:
        figures=report(
            figure_paths("kb_prediction_{fold}_{approach}_{algorithm}"),
            caption="../report/figure.rst",
            category="5. Prediction",
            subcategory="{fold}",
            labels={
                "figure": "Figs. 14/16",
                "fold": "{fold}",
                "approach": "{approach}",
                "algorithm": "{algorithm}",
            },
        ),
    log:
        f"{LOGS}/figures/kb_prediction_{{fold}}_{{approach}}_{{algorithm}}.log",
    benchmark:
        f"{BENCH}/figures/kb_prediction_{{fold}}_{{approach}}_{{algorithm}}.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        caption=lambda w: prediction_caption("kb_prediction", w),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig_error_prediction:
    input:
        code=lib("plotting", "captions"),
        errors=f"{OUT}/tables/error_predictions.csv",
    output:
        figures=report(
            figure_paths("error_prediction_{fold}_{approach}_{algorithm}"),
            caption="../report/figure.rst",
            category="5. Prediction",
            subcategory="{fold}",
            labels={
                "figure": "Figs. 11/15/17",
                "fold": "{fold}",
                "approach": "{approach}",
                "algorithm": "{algorithm}",
            },
        ),
    log:
        f"{LOGS}/figures/error_prediction_{{fold}}_{{approach}}_{{algorithm}}.log",
    benchmark:
        f"{BENCH}/figures/error_prediction_{{fold}}_{{approach}}_{{algorithm}}.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        caption=lambda w: prediction_caption("error_prediction", w),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"


rule fig_fold_comparison:
    input:
        code=lib("plotting", "captions"),
        metrics=f"{OUT}/tables/metrics.csv",
    output:
        figures=report(
            figure_paths("fold_comparison"),
            caption="../report/figure.rst",
            category="5. Prediction",
            labels={"figure": "fold comparison", "fold": "all"},
        ),
    log:
        f"{LOGS}/figures/fold_comparison.log",
    benchmark:
        f"{BENCH}/figures/fold_comparison.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        caption=figure_caption(
            "fold_comparison", DATASET.name, SIMULATED, target="error"
        ),
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        dpi=config["figures"]["dpi"],
    script:
        "../scripts/plot.py"
