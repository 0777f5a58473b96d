# The deployable compensation (common.smk, compensation block), one job: model.json and
# its Structured Text block from all runs, and per held-out run its fold's model, its
# controller exports and the error left after compensating, collected per table.


rule compensation:
    input:
        code=code_of("compensation.py"),
        schema=MODEL_SCHEMA,
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
        inputs=f"{OUT}/assembled/inputs.parquet",
        metrics=f"{OUT}/tables/metrics.csv",
        choice=f"{OUT}/recommend/choice.json",
        scores=expand(f"{OUT}/recommend/folds/{{fold}}.csv", fold=FOLDS),
        # Every run's log: the sensors' noise in the training runs (model.json noise_c),
        # and a held-out run's cycles for a model with time-aware inputs.
        logs=expand(f"{OUT}/clean/{{run}}/temperatures.parquet", run=RUNS),
        signal_series=expand(f"{OUT}/clean/{{fold}}/signals.parquet", fold=FOLDS),
        windows=expand(f"{OUT}/clean/{{fold}}/windows.csv", fold=FOLDS),
        selections=expand(f"{OUT}/selection/{{fold}}.json", fold=FOLDS),
        sheets=dataset_sheets(),
        manifest=DATA_MANIFEST,
    output:
        **{
            f"fold_{name}": expand(
                f"{OUT}/compensation/folds/{{fold}}/{name}.csv", fold=FOLDS
            )
            for name in COMP_TABLES
        },
        **{
            name: report(
                f"{OUT}/compensation/{name}.csv",
                caption="../report/compensation_tables.rst",
                category=CATEGORY["compensation"],
                labels={"table": name},
            )
            for name in COMP_TABLES
        },
        fitted=f"{OUT}/compensation/fitted_model.json",
        model=f"{OUT}/compensation/model.json",
        st=f"{OUT}/compensation/ThermalCompensation.st",
        fold_models=expand(f"{OUT}/compensation/folds/{{fold}}/model.json", fold=FOLDS),
    log:
        f"{LOGS}/compensation/compensation.log",
    benchmark:
        f"{BENCH}/compensation/compensation.tsv"
    priority: rule_priority("compensation")
    conda:
        ENV
    resources:
        **rule_resources("compensation"),
    params:
        **COMP_PARAMS,
        citation=DATASET.meta["provenance"].get("citation", ""),
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        max_missing_fraction=config["errors"]["max_missing_fraction"],
        statement=DATA_STATEMENT,
        tables=COMP_TABLES,
        folds=FOLDS,
    script:
        "../scripts/compensation.py"
