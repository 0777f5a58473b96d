# Every comparison with its uncertainty (thermaxis.statistics, docs/statistics.md), one
# job: the paired comparisons of the models and the paper's claims from the held-out
# predictions, the stability of the sensitive points and, for a dataset that reproduces
# the paper, the audit of every published value (thermaxis.paper). The metrics table's
# intervals are added where it is collected (model.smk), the sweep's where its ranking
# is (sweep.smk).


rule statistics:
    input:
        code=code_of("statistics.py"),
        kb_predictions=out(paths.KB_PREDICTIONS),
        error_predictions=out(paths.ERROR_PREDICTIONS),
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
        recommendation=out(paths.RECOMMENDATION),
        summary=out(paths.DATASET_SUMMARY),
        ambient=[out(paths.AMBIENT_RANGES)] if AMBIENT else [],
        kb=[out(paths.TABLE5)] if DECOUPLED else [],
        metrics=out(paths.METRICS),
        coefficients=out(paths.COEFFICIENTS),
        selection=out(paths.SENSITIVE_POINTS),
        paper=PAPER_FILES if PAPER else [],
    output:
        **filed(targets.audit_tables(PLAN, OUT)),
        comparisons=report(
            out(paths.COMPARISONS),
            caption="../report/comparisons.rst",
            category=CATEGORY["prediction"],
            labels={"table": "paired comparisons"},
        ),
        claims=report(
            out(paths.CLAIMS),
            caption="../report/claims.rst",
            category=CATEGORY["audit"],
            labels={"table": "the paper's claims"},
        ),
        markdown=out(paths.CLAIMS_MARKDOWN),
        stability=report(
            out(paths.SELECTION_STABILITY),
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
