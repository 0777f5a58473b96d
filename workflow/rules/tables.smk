rule ambient_ranges:
    input:
        code=code_of("ambient_ranges.py"),
        series=expand(f"{OUT}/clean/{{run}}/temperatures.parquet", run=RUNS),
        windows=expand(f"{OUT}/clean/{{run}}/windows.csv", run=RUNS),
    output:
        table=report(
            f"{OUT}/tables/ambient_ranges.csv",
            caption="../report/ambient_ranges.rst",
            category=CATEGORY["dataset"],
            labels={"table": "ambient ranges (Table 1)"},
        ),
        series=f"{OUT}/tables/ambient_series.parquet",
    log:
        f"{LOGS}/ambient_ranges.log",
    benchmark:
        f"{BENCH}/ambient_ranges.tsv"
    conda:
        ENV
    resources:
        **rule_resources("ambient_ranges"),
    params:
        runs=RUNS,
        statement=DATA_STATEMENT,
        sensor=AMBIENT,
    script:
        "../scripts/ambient_ranges.py"


rule paper_comparison:
    input:
        code=code_of("paper_comparison.py"),
        summary=f"{OUT}/tables/dataset_summary.csv",
        ambient=f"{OUT}/tables/ambient_ranges.csv",
        kb=[f"{OUT}/tables/table5_slope_intercept.csv"] if DECOUPLED else [],
        metrics=f"{OUT}/tables/metrics.csv",
        coefficients=f"{OUT}/tables/coefficients.csv",
        selection=f"{OUT}/tables/sensitive_points.csv",
        predictions=f"{OUT}/tables/error_predictions.csv",
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        paper=PAPER_FILES,
    output:
        csv=report(
            f"{OUT}/tables/paper_comparison.csv",
            caption="../report/paper_comparison.rst",
            category=CATEGORY["audit"],
            labels={"table": "paper comparison"},
        ),
        markdown=f"{OUT}/tables/paper_comparison.md",
        faithfulness=report(
            f"{OUT}/tables/faithfulness.csv",
            caption="../report/faithfulness.rst",
            category=CATEGORY["audit"],
            labels={"table": "faithfulness"},
        ),
        faithfulness_markdown=f"{OUT}/tables/faithfulness.md",
    log:
        f"{LOGS}/paper_comparison.log",
    benchmark:
        f"{BENCH}/paper_comparison.tsv"
    conda:
        ENV
    resources:
        **rule_resources("paper_comparison"),
    params:
        paper_fold=config["paper_fold"],
        statement=DATA_STATEMENT,
        dataset_name=DATASET.name,
        simulated=SIMULATED,
        paper_dir=lambda w, input: os.path.dirname(input.paper[0]),
    script:
        "../scripts/paper_comparison.py"
