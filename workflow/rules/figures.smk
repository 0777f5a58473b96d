# The figures, one rule per family of the figure table (thermaxis.figures.registry; the
# table is read in common.smk, figures block): each family is one job, every fold's
# figures included, because starting Python and importing matplotlib costs more than
# drawing a figure. A family reads only tables the computing rules wrote, so a cosmetic
# change reruns only plots.


for family, figures in FIGURE_FAMILIES.items():

    rule:
        name:
            family
        input:
            tables=targets.figure_tables(PLAN, OUT, figures),
            code=figure_code(figures),
        output:
            *(
                figure_output(fig, wildcards)
                for fig, wildcards in targets.figure_instances(PLAN, figures)
            ),
        log:
            f"{LOGS}/figures/{family}.log",
        benchmark:
            f"{BENCH}/figures/{family}.tsv"
        priority: rule_priority(family)
        conda:
            ENV
        # Snakemake gives at most --cores; the job deals its figures to that many workers.
        threads: PAGES.figure_threads(figures)
        resources:
            **rule_resources(family),
        params:
            figures=PAGES.figure_specs(figures),
            stamp=PAGES.stamp,
            dpi=SETTINGS.figures.dpi,
        script:
            "../scripts/plot.py"
