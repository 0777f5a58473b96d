# The runs assembled: the unzeroed errors and the temperatures of every measurement, the
# cleaning's QC and events, what describes the dataset as a whole (its summary and, with
# an ambient sensor, Table 1's ambient ranges) and, with more than one target position,
# the slope/intercept decoupling of every measurement (Table 5, Eq. 2), in one job.


rule assemble:
    input:
        errors=expand(f"{OUT}/clean/{{run}}/errors.parquet", run=RUNS),
        temperatures=expand(
            f"{OUT}/clean/{{run}}/measurement_temperatures.parquet", run=RUNS
        ),
        signals=expand(f"{OUT}/clean/{{run}}/measurement_signals.parquet", run=RUNS),
        qc=expand(f"{OUT}/clean/{{run}}/qc.csv", run=RUNS),
        inputs=expand(f"{OUT}/clean/{{run}}/measurement_inputs.parquet", run=RUNS),
        windows=expand(f"{OUT}/clean/{{run}}/windows.csv", run=RUNS),
        series=(
            expand(f"{OUT}/clean/{{run}}/temperatures.parquet", run=RUNS)
            if AMBIENT
            else []
        ),
        sheets=dataset_sheets(),
        paper=f"{PAPER_DIR}/table5_slope_intercept.csv",
        code=code_of("assemble.py"),
    output:
        **dataset_tables(),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
        inputs=f"{OUT}/assembled/inputs.parquet",
        qc=report(
            f"{OUT}/tables/cleaning_qc.csv",
            caption="../report/cleaning_qc.rst",
            category=CATEGORY["dataset"],
            labels={"table": "cleaning QC"},
        ),
        events=f"{OUT}/tables/cleaning_events.csv",
        summary=report(
            f"{OUT}/tables/dataset_summary.csv",
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
