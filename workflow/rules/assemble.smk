# The runs assembled: the unzeroed errors and the temperatures of every measurement, the
# cleaning's QC and events, what describes the dataset as a whole (its summary and, with
# an ambient sensor, Table 1's ambient ranges) and, with more than one target position,
# the slope/intercept decoupling of every measurement (Table 5, Eq. 2), in one job.


rule assemble:
    input:
        errors=expand(out(paths.CLEAN_ERRORS), run=RUNS),
        temperatures=expand(out(paths.CLEAN_TEMPERATURES), run=RUNS),
        signals=expand(out(paths.CLEAN_SIGNALS), run=RUNS),
        qc=expand(out(paths.CLEAN_QC), run=RUNS),
        inputs=expand(out(paths.CLEAN_INPUTS), run=RUNS),
        windows=expand(out(paths.CLEAN_WINDOWS), run=RUNS),
        series=(expand(out(paths.CLEAN_SERIES), run=RUNS) if AMBIENT else []),
        sheets=dataset_sheets(),
        paper=f"{PAPER_DIR}/table5_slope_intercept.csv",
        code=code_of("assemble.py"),
    output:
        **filed(targets.dataset_tables(PLAN, OUT)),
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
        signals=out(paths.ASSEMBLED_SIGNALS),
        inputs=out(paths.ASSEMBLED_INPUTS),
        qc=report(
            out(paths.CLEANING_QC),
            caption="../report/cleaning_qc.rst",
            category=CATEGORY["dataset"],
            labels={"table": "cleaning QC"},
        ),
        events=out(paths.CLEANING_EVENTS),
        summary=report(
            out(paths.DATASET_SUMMARY),
            caption="../report/dataset_summary.rst",
            category=CATEGORY["dataset"],
            labels={"table": "dataset summary"},
        ),
    log:
        f"{LOGS}/assemble.log",
    benchmark:
        f"{BENCH}/assemble.tsv"
    conda:
        ENV
    resources:
        **rule_resources("assemble"),
    params:
        statement=DATA_STATEMENT,
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        runs=RUNS,
        ambient=AMBIENT or "",
        decoupled=DECOUPLED,
        degree=config["decoupling"]["degree"],
        paper=PAPER,
        paper_dir=lambda w, input: os.path.dirname(input.paper),
    script:
        "../scripts/assemble.py"
