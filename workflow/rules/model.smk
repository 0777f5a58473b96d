# Every fold's sensitive points (fuzzy clustering + grey relational grade on its training
# runs) and every approach x algorithm fitted and its held-out run predicted, in one job:
# each fold's numerics take well under a second, less than starting Python does. The
# folds' files stay, and the collected tables carry their intervals.


rule models:
    input:
        code=code_of("models.py"),
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
        signals=out(paths.ASSEMBLED_SIGNALS),
    output:
        **{
            f"fold_{name}": expand(out(paths.FOLD_TABLE), fold=FOLDS, table=name)
            for name in MODEL_TABLES
        },
        selections=expand(out(paths.SELECTION), fold=FOLDS),
        selection_tables=expand(out(paths.SELECTION_TABLE), fold=FOLDS),
        metrics=report(
            out(paths.METRICS),
            caption="../report/metrics.rst",
            category=CATEGORY["prediction"],
            labels={"table": "metrics"},
        ),
        coefficients=report(
            out(paths.COEFFICIENTS),
            caption="../report/coefficients.rst",
            category=CATEGORY["models"],
            labels={"table": "coefficients"},
        ),
        kb_predictions=report(
            out(paths.KB_PREDICTIONS),
            caption="../report/kb_predictions.rst",
            category=CATEGORY["prediction"],
            labels={"table": "k and b predictions"},
        ),
        error_predictions=report(
            out(paths.ERROR_PREDICTIONS),
            caption="../report/error_predictions.rst",
            category=CATEGORY["prediction"],
            labels={"table": "error predictions"},
        ),
        fitting=report(
            out(paths.FITTING),
            caption="../report/fitting.rst",
            category=CATEGORY["models"],
            labels={"table": "fitting"},
        ),
        selection=report(
            out(paths.SENSITIVE_POINTS),
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
