# Every fold's sensitive points (fuzzy clustering + grey relational grade on its training
# runs) and every approach x algorithm fitted and its held-out run predicted, in one job:
# each fold's numerics take well under a second, less than starting Python does. The
# folds' files stay, and the collected tables carry their intervals.


rule models:
    input:
        code=code_of("models.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
    output:
        **{
            f"fold_{name}": expand(f"{OUT}/models/{{fold}}/{name}.csv", fold=FOLDS)
            for name in MODEL_TABLES
        },
        selections=expand(f"{OUT}/selection/{{fold}}.json", fold=FOLDS),
        selection_tables=expand(f"{OUT}/selection/{{fold}}.csv", fold=FOLDS),
        metrics=report(
            f"{OUT}/tables/metrics.csv",
            caption="../report/metrics.rst",
            category=CATEGORY["prediction"],
            labels={"table": "metrics"},
        ),
        coefficients=report(
            f"{OUT}/tables/coefficients.csv",
            caption="../report/coefficients.rst",
            category=CATEGORY["models"],
            labels={"table": "coefficients"},
        ),
        kb_predictions=report(
            f"{OUT}/tables/kb_predictions.csv",
            caption="../report/kb_predictions.rst",
            category=CATEGORY["prediction"],
            labels={"table": "k and b predictions"},
        ),
        error_predictions=report(
            f"{OUT}/tables/error_predictions.csv",
            caption="../report/error_predictions.rst",
            category=CATEGORY["prediction"],
            labels={"table": "error predictions"},
        ),
        fitting=report(
            f"{OUT}/tables/fitting.csv",
            caption="../report/fitting.rst",
            category=CATEGORY["models"],
            labels={"table": "fitting"},
        ),
        selection=report(
            f"{OUT}/tables/sensitive_points.csv",
            caption="../report/sensitive_points.rst",
            category=CATEGORY["sensitive_points"],
            labels={"table": "sensitive points"},
        ),
    log:
        f"{LOGS}/models.log",
    benchmark:
        f"{BENCH}/models.tsv"
    priority: rule_priority("models")
    conda:
        ENV
    threads: FOLD_THREADS["models"]
    resources:
        **rule_resources("models"),
    params:
        folds=FOLDS,
        tables=MODEL_TABLES,
        selection=config["selection"],
        decoupling=config["decoupling"],
        decoupled=DECOUPLED,
        approaches=APPROACHES,
        algorithms=ALGORITHMS,
        models=config["models"],
        statistics=config["statistics"],
    script:
        "../scripts/models.py"
