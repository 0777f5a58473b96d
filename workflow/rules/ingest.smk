rule dataset_summary:
    input:
        sheets=dataset_sheets(),
    output:
        table=f"{OUT}/tables/dataset_summary.csv",
    params:
        dataset=str(DATASET.root),
    log:
        f"{LOGS}/dataset_summary.log",
    benchmark:
        f"{BENCH}/dataset_summary.tsv"
    conda:
        ENV
    script:
        "../scripts/dataset_summary.py"
