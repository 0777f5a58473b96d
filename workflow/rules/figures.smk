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
            tables=figure_tables(figures),
            code=figure_code(figures),
        output:
            *(
                figure_output(fig, wildcards)
                for fig, wildcards in figure_instances(figures)
            ),
        log:
            f"{LOGS}/figures/{family}.log",
        benchmark:
            f"{BENCH}/figures/{family}.tsv"
        priority: rule_priority(family)
        conda:
            ENV
        # Snakemake gives at most --cores; the job deals its figures to that many workers.
        threads: figure_threads(figures)
        resources:
            **rule_resources(family),
        params:
            figures=figure_specs(figures),
            stamp=STAMP,
            dpi=SETTINGS.figures.dpi,
        script:
            "../scripts/plot.py"
