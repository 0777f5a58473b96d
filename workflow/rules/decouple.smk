rule decouple:
    input:
        errors=f"{OUT}/assembled/errors.parquet",
        paper="data/paper/table5_slope_intercept.csv",
    output:
        table=f"{OUT}/tables/table5_slope_intercept.csv",
        markdown=f"{OUT}/tables/table5_slope_intercept.md",
        coefficients=f"{OUT}/decoupled/polynomial_coefficients.csv",
    log:
        f"{LOGS}/decouple.log",
    benchmark:
        f"{BENCH}/decouple.tsv"
    conda:
        ENV
    params:
        degree=config["decoupling"]["degree"],
        simulated=SIMULATED,
        dataset_name=DATASET.name,
        paper_dir=lambda w, input: os.path.dirname(input.paper),
    script:
        "../scripts/decouple.py"
