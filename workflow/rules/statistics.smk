# Every comparison with its uncertainty (thermaxis.statistics, docs/statistics.md): the
# paired comparisons of the models and the paper's claims from the held-out predictions,
# and the stability of the sensitive points. metrics.csv's intervals are added where it is
# collected (tables.smk), the sweep's where its ranking is (sweep.smk).


rule statistics_claims:
    input:
        code=code_of("statistics_claims.py"),
        kb_predictions=f"{OUT}/tables/kb_predictions.csv",
        error_predictions=f"{OUT}/tables/error_predictions.csv",
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        recommendation=f"{OUT}/tables/recommendation.csv",
    output:
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
    log:
        f"{LOGS}/statistics/claims.log",
    benchmark:
        f"{BENCH}/statistics/claims.tsv"
    conda:
        ENV
    resources:
        **rule_resources("statistics_claims"),
    params:
        statistics=config["statistics"],
        selection=config["selection"],
        folds=FOLDS,
        dataset_name=DATASET.name,
        statement=DATA_STATEMENT,
    script:
        "../scripts/statistics_claims.py"


rule selection_stability:
    input:
        code=code_of("selection_stability.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
    output:
        table=report(
            f"{OUT}/tables/selection_stability.csv",
            caption="../report/selection_stability.rst",
            category=CATEGORY["sensitive_points"],
            labels={"table": "stability of the sensitive points"},
        ),
    log:
        f"{LOGS}/statistics/selection_stability.log",
    benchmark:
        f"{BENCH}/statistics/selection_stability.tsv"
    conda:
        ENV
    resources:
        **rule_resources("selection_stability"),
    params:
        selection=config["selection"],
        decoupling=config["decoupling"],
        decoupled=DECOUPLED,
        folds=FOLDS,
    script:
        "../scripts/selection_stability.py"
