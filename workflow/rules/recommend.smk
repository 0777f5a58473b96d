# The recommendation (thermaxis.pipeline.plan.recommend_params), one job: per held-out
# run, every candidate's inner scores on the other runs and its error on the held-out run;
# then the choice per fold, the final one, and the tables.


rule recommend:
    input:
        code=code_of("recommend.py"),
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
        signals=out(paths.ASSEMBLED_SIGNALS),
        inputs=out(paths.ASSEMBLED_INPUTS),
    output:
        scores=expand(out(paths.FOLD_SCORES), fold=FOLDS),
        table=report(
            out(paths.RECOMMENDATION),
            caption="../report/recommendation.rst",
            category=CATEGORY["compensation"],
            labels={"table": "recommendation"},
        ),
        markdown=out(paths.RECOMMENDATION_MARKDOWN),
        candidates=out(paths.CANDIDATES),
        choice=out(paths.CHOICE),
    log:
        f"{LOGS}/recommend.log",
    benchmark:
        f"{BENCH}/recommend.tsv"
    priority: rule_priority("recommend")
    conda:
        ENV
    threads: FOLD_THREADS["recommend"]
    resources:
        **rule_resources("recommend"),
    params:
        **RECOMMEND_PARAMS,
        folds=FOLDS,
        statement=DATA_STATEMENT,
        statistics=config["statistics"],
    script:
        "../scripts/recommend.py"
