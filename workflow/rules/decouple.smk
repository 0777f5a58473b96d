rule decouple:
    input:
        code=code_of("decouple.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        paper=f"{PAPER_DIR}/table5_slope_intercept.csv",
    output:
        table=report(
            f"{OUT}/tables/table5_slope_intercept.csv",
            caption="../report/table5.rst",
            category=CATEGORY["decoupling"],
            labels={"table": "Table 5"},
        ),
        markdown=f"{OUT}/tables/table5_slope_intercept.md",
        coefficients=f"{OUT}/decoupled/polynomial_coefficients.csv",
    log:
        f"{LOGS}/decouple.log",
    benchmark:
        f"{BENCH}/decouple.tsv"
    conda:
        ENV
    resources:
        **rule_resources("decouple"),
    params:
        degree=config["decoupling"]["degree"],
        statement=DATA_STATEMENT,
        paper=PAPER,
        paper_dir=lambda w, input: os.path.dirname(input.paper),
    script:
        "../scripts/decouple.py"
