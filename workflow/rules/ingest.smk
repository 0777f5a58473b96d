rule dataset_summary:
    input:
        sheets=dataset_sheets(),
    output:
        table=f"{OUT}/tables/dataset_summary.csv",
    log:
        f"{LOGS}/dataset_summary.log",
    benchmark:
        f"{BENCH}/dataset_summary.tsv"
    conda:
        ENV
    params:
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
    script:
        "../scripts/dataset_summary.py"
