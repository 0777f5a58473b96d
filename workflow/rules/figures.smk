# The figures, one rule per family of the figure table (thermaxis.figures.registry; the
# table is read in common.smk, figures block): each family is one job, per fold when its
# stems hold the fold, because starting Python and importing matplotlib costs more than
# drawing a figure. A family reads only tables the computing rules wrote, so a cosmetic
# change reruns only plots.


for family, figures in FIGURE_FAMILIES.items():
    per_fold = any(fig.per_fold for fig in figures)
    where = f"{family}_{{fold}}" if per_fold else family

    rule:
        name:
            family
        input:
            tables=sorted(
                {f"{OUT}/{path}" for fig in figures for path in fig.tables.values()}
            ),
            code=figure_code(figures),
        output:
            *(figure_output(fig) for fig in figures),
        log:
            f"{LOGS}/figures/{where}.log",
        benchmark:
            f"{BENCH}/figures/{where}.tsv"
        conda:
            ENV
        resources:
            **rule_resources(family),
        params:
            figures=lambda w, figures=figures: figure_specs(figures, dict(w.items())),
            simulated=SIMULATED,
            dpi=SETTINGS.figures.dpi,
        script:
            "../scripts/plot.py"
