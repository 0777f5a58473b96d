rule assemble:
    input:
        errors=expand(f"{OUT}/clean/{{run}}/errors.parquet", run=RUNS),
        temperatures=expand(
            f"{OUT}/clean/{{run}}/measurement_temperatures.parquet", run=RUNS
        ),
        signals=expand(f"{OUT}/clean/{{run}}/measurement_signals.parquet", run=RUNS),
        qc=expand(f"{OUT}/clean/{{run}}/qc.csv", run=RUNS),
        inputs=expand(f"{OUT}/clean/{{run}}/measurement_inputs.parquet", run=RUNS),
        code=code_of("assemble.py"),
    output:
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
        dataset=str(DATASET.root),
    script:
        "../scripts/assemble.py"
