rule dataset_summary:
    input:
        sheets=dataset_sheets(),
        windows=expand(f"{OUT}/clean/{{run}}/windows.csv", run=RUNS),
        code=code_of("dataset_summary.py"),
    output:
        table=report(
            f"{OUT}/tables/dataset_summary.csv",
            caption="../report/dataset_summary.rst",
            category=CATEGORY["dataset"],
            labels={"table": "dataset summary"},
        ),
    log:
        f"{LOGS}/dataset_summary.log",
    benchmark:
        f"{BENCH}/dataset_summary.tsv"
    conda:
        ENV
    resources:
        **rule_resources("dataset_summary"),
    params:
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        statement=DATA_STATEMENT,
        runs=RUNS,
    script:
        "../scripts/dataset_summary.py"
