rule dataset_summary:
    input:
        sheets=dataset_sheets(),
        windows=expand(f"{OUT}/clean/{{run}}/windows.csv", run=RUNS),
        code=code_of("dataset_summary.py"),
    output:
        table=report(
            f"{OUT}/tables/dataset_summary.csv",
            caption="../report/dataset_summary.rst",
            category="1. Dataset",
            labels={"table": "dataset summary"},
        ),
    log:
        f"{LOGS}/dataset_summary.log",
    benchmark:
        f"{BENCH}/dataset_summary.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        provenance=DATA_STATEMENT,
        runs=RUNS,
    script:
        "../scripts/dataset_summary.py"
