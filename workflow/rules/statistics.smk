# Every comparison with its uncertainty (thermaxis.statistics, docs/statistics.md), one
# job: the paired comparisons of the models and the paper's claims from the held-out
# predictions, the stability of the sensitive points and, for a dataset that reproduces
# the paper, the audit of every published value (thermaxis.paper). metrics.csv's
# intervals are added where it is collected (model.smk), the sweep's where its ranking
# is (sweep.smk).


rule statistics:
    input:
        code=code_of("statistics.py"),
        kb_predictions=f"{OUT}/tables/kb_predictions.csv",
        error_predictions=f"{OUT}/tables/error_predictions.csv",
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        recommendation=f"{OUT}/tables/recommendation.csv",
        summary=f"{OUT}/tables/dataset_summary.csv",
        ambient=[f"{OUT}/tables/ambient_ranges.csv"] if AMBIENT else [],
        kb=[f"{OUT}/tables/table5_slope_intercept.csv"] if DECOUPLED else [],
        metrics=f"{OUT}/tables/metrics.csv",
        coefficients=f"{OUT}/tables/coefficients.csv",
        selection=f"{OUT}/tables/sensitive_points.csv",
        paper=PAPER_FILES if PAPER else [],
    output:
        **audit_tables(),
        comparisons=report(
            f"{OUT}/tables/comparisons.csv",
            caption="../report/comparisons.rst",
            category=CATEGORY["prediction"],
            labels={"table": "paired comparisons"},
        ),
        claims=report(
            f"{OUT}/tables/claims.csv",
            caption="../report/claims.rst",
            category=CATEGORY["audit"],
            labels={"table": "the paper's claims"},
        ),
        markdown=f"{OUT}/tables/claims.md",
        stability=report(
            f"{OUT}/tables/selection_stability.csv",
            caption="../report/selection_stability.rst",
            category=CATEGORY["sensitive_points"],
            labels={"table": "stability of the sensitive points"},
        ),
    log:
        f"{LOGS}/statistics.log",
    benchmark:
        f"{BENCH}/statistics.tsv"
    priority: rule_priority("statistics")
    conda:
        ENV
    resources:
        **rule_resources("statistics"),
    params:
        statistics=config["statistics"],
        selection=config["selection"],
        decoupling=config["decoupling"],
        decoupled=DECOUPLED,
        folds=FOLDS,
        dataset_name=DATASET.name,
        statement=DATA_STATEMENT,
        paper=PAPER,
        paper_fold=config["paper_fold"],
        simulated=SIMULATED,
        paper_dir=lambda w, input: (
            os.path.dirname(input.paper[0]) if input.paper else ""
        ),
    script:
        "../scripts/statistics.py"
