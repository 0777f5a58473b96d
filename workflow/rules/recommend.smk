# The recommendation (common.smk, recommendation block): per held-out run, every
# candidate's inner scores on the other runs and its error on the held-out run; then
# the choice per fold, the final one, and the tables.


rule recommend_fold:
    input:
        code=code_of("recommend_fold.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
        inputs=f"{OUT}/assembled/inputs.parquet",
    output:
        scores=f"{OUT}/recommend/folds/{{fold}}.csv",
    log:
        f"{LOGS}/recommend/{{fold}}.log",
    benchmark:
        f"{BENCH}/recommend/{{fold}}.tsv"
    conda:
        ENV
    resources:
        **rule_resources("recommend_fold"),
    params:
        **RECOMMEND_PARAMS,
    script:
        "../scripts/recommend_fold.py"


rule recommend_collect:
    input:
        code=code_of("recommend_collect.py"),
        scores=expand(f"{OUT}/recommend/folds/{{fold}}.csv", fold=FOLDS),
    output:
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
        f"{LOGS}/recommend/collect.log",
    benchmark:
        f"{BENCH}/recommend/collect.tsv"
    conda:
        ENV
    resources:
        **rule_resources("recommend_collect"),
    params:
        **RECOMMEND_PARAMS,
        statement=DATA_STATEMENT,
        statistics=config["statistics"],
    script:
        "../scripts/recommend_collect.py"
