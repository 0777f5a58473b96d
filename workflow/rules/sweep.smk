# The sweep (`make sweep`, i.e. `snakemake sweep`; common.smk, sweep block): batches of
# the grid, their tables, the two figures (the figure table's family fig_sweep) and the
# report. Not part of `rule all`: the default run stays fast.


rule sweep_batch:
    input:
        code=code_of("sweep_batch.py"),
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
    output:
        out(paths.SWEEP_BATCH),
    log:
        f"{LOGS}/sweep/batch_{{n_batches}}_{{batch}}.log",
    benchmark:
        f"{BENCH}/sweep/batch_{{n_batches}}_{{batch}}.tsv"
    conda:
        ENV
    threads: 1
    resources:
        **rule_resources("sweep_batch"),
    params:
        sweep=config["sweep"],
        selection=config["selection"],
        models=config["models"],
        folds=CHECKED.sweep_folds,
        sensors=list(DATASET.sensors),
        n_batches=lambda w: int(w.n_batches),
        decoupled=DECOUPLED,
    script:
        "../scripts/sweep_batch.py"


rule sweep_collect:
    input:
        code=code_of("sweep_collect.py"),
        batches=sweep_batch_files,
    output:
        summary=out(paths.SWEEP_SUMMARY),
        ranking=out(paths.SWEEP_RANKING),
        effects=out(paths.SWEEP_EFFECTS),
    log:
        f"{LOGS}/sweep/collect.log",
    benchmark:
        f"{BENCH}/sweep/collect.tsv"
    conda:
        ENV
    resources:
        **rule_resources("sweep_collect"),
    params:
        selection=config["selection"],
        decoupling=config["decoupling"],
        statistics=config["statistics"],
    script:
        "../scripts/sweep_collect.py"


rule sweep_report:
    input:
        library=code_of("notebooks/sweep_report.ipynb"),
        notebook="notebooks/sweep_report.ipynb",
        summary=out(paths.SWEEP_SUMMARY),
        ranking=out(paths.SWEEP_RANKING),
        effects=out(paths.SWEEP_EFFECTS),
        figures=targets.figure_files(PLAN, OUT, SWEEP_FIGURES),
        benchmarks=sweep_batch_benchmarks,
    output:
        notebook=out(paths.SWEEP_REPORT, ext="ipynb"),
        html=report(
            out(paths.SWEEP_REPORT, ext="html"),
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            subcategory="Sweep",
            labels={"report": "sweep"},
        ),
    log:
        f"{LOGS}/sweep/report.log",
    benchmark:
        f"{BENCH}/sweep/report.tsv"
    conda:
        ENV
    resources:
        **rule_resources("sweep_report"),
    params:
        title=f"Sweep report: {DATASET.name}",
        statement=DATA_STATEMENT,
        parameters=sweep_report_parameters,
    shell:
        pages.RUN_NOTEBOOK


rule sweep:
    input:
        out(paths.SWEEP_SUMMARY),
        out(paths.SWEEP_RANKING),
        out(paths.SWEEP_EFFECTS),
        targets.figure_files(PLAN, OUT, SWEEP_FIGURES),
        out(paths.SWEEP_REPORT, ext="html"),
