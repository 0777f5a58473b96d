# The deployable compensation (thermaxis.pipeline.plan.compensation_params), one job:
# model.json and its Structured Text block from all runs, and per held-out run its fold's
# model, its controller exports and the error left after compensating, collected per table.


rule compensation:
    input:
        code=code_of("compensation.py"),
        schema=MODEL_SCHEMA,
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
        signals=out(paths.ASSEMBLED_SIGNALS),
        inputs=out(paths.ASSEMBLED_INPUTS),
        metrics=out(paths.METRICS),
        choice=out(paths.CHOICE),
        scores=expand(out(paths.FOLD_SCORES), fold=FOLDS),
        # Every run's log: the sensors' noise in the training runs (model.json noise_c),
        # and a held-out run's cycles for a model with time-aware inputs.
        logs=expand(out(paths.CLEAN_SERIES), run=RUNS),
        signal_series=expand(out(paths.CLEAN_SIGNAL_SERIES), run=FOLDS),
        windows=expand(out(paths.CLEAN_WINDOWS), run=FOLDS),
        selections=expand(out(paths.SELECTION), fold=FOLDS),
        sheets=dataset_sheets(),
        manifest=DATA_MANIFEST,
    output:
        **{
            f"fold_{name}": expand(
                out(paths.FOLD_COMPENSATION), fold=FOLDS, table=name
            )
            for name in COMP_TABLES
        },
        **{
            name: report(
                out(paths.COMPENSATION_TABLE, table=name),
                caption="../report/compensation_tables.rst",
                category=CATEGORY["compensation"],
                labels={"table": name},
            )
            for name in COMP_TABLES
        },
        fitted=out(paths.FITTED_MODEL),
        model=out(paths.DEPLOYED_MODEL),
        st=out(paths.STRUCTURED_TEXT),
        fold_models=expand(out(paths.FOLD_MODEL), fold=FOLDS),
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
        citation=DATASET.meta["provenance"]["citation"],
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        max_missing_fraction=config["errors"]["max_missing_fraction"],
        statement=DATA_STATEMENT,
        tables=COMP_TABLES,
        folds=FOLDS,
    script:
        "../scripts/compensation.py"
