# The recommendation (common.smk, recommendation block), one job: per held-out run, every
# candidate's inner scores on the other runs and its error on the held-out run; then the
# choice per fold, the final one, and the tables.


rule recommend:
    input:
        code=code_of("recommend.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
        inputs=f"{OUT}/assembled/inputs.parquet",
    output:
        scores=expand(f"{OUT}/recommend/folds/{{fold}}.csv", fold=FOLDS),
        table=report(
            f"{OUT}/tables/recommendation.csv",
            caption="../report/recommendation.rst",
            category=CATEGORY["compensation"],
            labels={"table": "recommendation"},
        ),
        markdown=f"{OUT}/tables/recommendation.md",
        candidates=f"{OUT}/recommend/candidates.csv",
        choice=f"{OUT}/recommend/choice.json",
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
