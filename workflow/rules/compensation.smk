# The deployable compensation (common.smk, compensation block): model.json and its
# Structured Text block from all runs, and per held-out run its fold's exports and the
# error left after compensating.


rule compensation_model:
    input:
        code=code_of("compensation_model.py"),
        schema=MODEL_SCHEMA,
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
        inputs=f"{OUT}/assembled/inputs.parquet",
        metrics=f"{OUT}/tables/metrics.csv",
        choice=f"{OUT}/recommend/choice.json",
        scores=expand(f"{OUT}/recommend/folds/{{fold}}.csv", fold=FOLDS),
    output:
        model=f"{OUT}/compensation/fitted_model.json",
    log:
        f"{LOGS}/compensation/model.log",
    benchmark:
        f"{BENCH}/compensation/model.tsv"
    conda:
        ENV
    resources:
        **rule_resources("compensation_model"),
    params:
        **COMP_PARAMS,
        citation=DATASET.meta["provenance"].get("citation", ""),
    script:
        "../scripts/compensation_model.py"


rule compensation_plc:
    input:
        code=code_of("compensation_plc.py"),
        model=f"{OUT}/compensation/model.json",
    output:
        st=f"{OUT}/compensation/ThermalCompensation.st",
    log:
        f"{LOGS}/compensation/plc.log",
    benchmark:
        f"{BENCH}/compensation/plc.tsv"
    conda:
        ENV
    resources:
        **rule_resources("compensation_plc"),
    params:
        statement=DATA_STATEMENT,
    script:
        "../scripts/compensation_plc.py"


rule compensation_fold:
    input:
        code=code_of("compensation_fold.py"),
        schema=MODEL_SCHEMA,
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
        inputs=f"{OUT}/assembled/inputs.parquet",
        series=f"{OUT}/clean/{{fold}}/temperatures.parquet",
        signal_series=f"{OUT}/clean/{{fold}}/signals.parquet",
        windows=f"{OUT}/clean/{{fold}}/windows.csv",
        selection=f"{OUT}/selection/{{fold}}.json",
        choice=f"{OUT}/recommend/choice.json",
        final=f"{OUT}/compensation/fitted_model.json",
        sheets=dataset_sheets(),
        raw=lambda w: raw_files(w.fold),
    output:
        **{
            name: f"{OUT}/compensation/folds/{{fold}}/{name}.csv"
            for name in COMP_TABLES
        },
        model=f"{OUT}/compensation/folds/{{fold}}/model.json",
    log:
        f"{LOGS}/compensation/{{fold}}.log",
    benchmark:
        f"{BENCH}/compensation/{{fold}}.tsv"
    conda:
        ENV
    resources:
        **rule_resources("compensation_fold"),
    params:
        **COMP_PARAMS,
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        max_missing_fraction=config["errors"]["max_missing_fraction"],
    script:
        "../scripts/compensation_fold.py"


rule compensation_verdict:
    input:
        code=code_of("compensation_verdict.py"),
        schema=MODEL_SCHEMA,
        fitted=f"{OUT}/compensation/fitted_model.json",
        summaries=expand(f"{OUT}/compensation/folds/{{fold}}/summary.csv", fold=FOLDS),
        choice=f"{OUT}/recommend/choice.json",
    output:
        model=f"{OUT}/compensation/model.json",
    log:
        f"{LOGS}/compensation/verdict.log",
    benchmark:
        f"{BENCH}/compensation/verdict.tsv"
    conda:
        ENV
    resources:
        **rule_resources("compensation_verdict"),
    params:
        compensation=config["compensation"],
    script:
        "../scripts/compensation_verdict.py"


rule compensation_collect:
    input:
        **{
            name: expand(f"{OUT}/compensation/folds/{{fold}}/{name}.csv", fold=FOLDS)
            for name in COMP_TABLES
        },
        model=f"{OUT}/compensation/model.json",
        code=code_of("compensation_collect.py"),
    output:
        **{
            name: report(
                f"{OUT}/compensation/{name}.csv",
                caption="../report/compensation_tables.rst",
                category=CATEGORY["compensation"],
                labels={"table": name},
            )
            for name in COMP_TABLES
        },
    log:
        f"{LOGS}/compensation/collect.log",
    benchmark:
        f"{BENCH}/compensation/collect.tsv"
    conda:
        ENV
    resources:
        **rule_resources("compensation_collect"),
    params:
        statement=DATA_STATEMENT,
        tables=COMP_TABLES,
    script:
        "../scripts/compensation_collect.py"
