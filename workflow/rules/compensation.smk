# The deployable compensation: the configured model fitted on all runs (model.json and a
# Structured Text block), and per held-out run the controller exports of that fold's
# model and the error left after compensating. Folds stay for evaluation only.

COMPENSATION = config["compensation"]
# A single target has no slope: the point-by-point model gives an offset (SD43900 alone).
COMP_APPROACH = COMPENSATION["approach"] if DECOUPLED else "pointwise"
COMP_ALGORITHM = COMPENSATION["algorithm"]
COMP_TABLES = ["siemens_840d", "twincat", "residuals", "iso230_2", "summary"]
COMP = f"{OUT}/compensation"
if COMP_ALGORITHM not in ALGORITHMS:
    sys.exit(
        f"thermaxis error: config compensation.algorithm: {COMP_ALGORITHM!r} is not one of models.algorithms "
        f"({', '.join(ALGORITHMS)}); its held-out metrics go into model.json"
    )
COMP_PARAMS = dict(
    approach=COMP_APPROACH,
    sections={
        name: config[name]
        for name in ("selection", "decoupling", "models", "compensation")
    },
    about=dict(dataset=DATASET.name, simulated=SIMULATED, statement=DATA_STATEMENT),
)


rule compensation_model:
    input:
        code=code_of("compensation_model.py"),
        schema=MODEL_SCHEMA,
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        metrics=f"{OUT}/tables/metrics.csv",
    output:
        model=f"{COMP}/model.json",
    log:
        f"{LOGS}/compensation/model.log",
    benchmark:
        f"{BENCH}/compensation/model.tsv"
    conda:
        ENV
    resources:
        mem_mb=1000,
    params:
        **COMP_PARAMS,
        citation=DATASET.meta["provenance"].get("citation", ""),
    script:
        "../scripts/compensation_model.py"


rule compensation_plc:
    input:
        code=code_of("compensation_plc.py"),
        model=f"{COMP}/model.json",
    output:
        st=f"{COMP}/ThermalCompensation.st",
    log:
        f"{LOGS}/compensation/plc.log",
    benchmark:
        f"{BENCH}/compensation/plc.tsv"
    conda:
        ENV
    resources:
        mem_mb=500,
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
        selection=f"{OUT}/selection/{{fold}}.json",
        final=f"{COMP}/model.json",
        sheets=dataset_sheets(),
        raw=lambda w: raw_files(w.fold),
    output:
        **{name: f"{COMP}/folds/{{fold}}/{name}.csv" for name in COMP_TABLES},
        model=f"{COMP}/folds/{{fold}}/model.json",
    log:
        f"{LOGS}/compensation/{{fold}}.log",
    benchmark:
        f"{BENCH}/compensation/{{fold}}.tsv"
    conda:
        ENV
    resources:
        mem_mb=1000,
    params:
        **COMP_PARAMS,
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        max_missing_fraction=config["errors"]["max_missing_fraction"],
    script:
        "../scripts/compensation_fold.py"


rule compensation_collect:
    input:
        **{
            name: expand(f"{COMP}/folds/{{fold}}/{name}.csv", fold=FOLDS)
            for name in COMP_TABLES
        },
        code=code_of("compensation_collect.py"),
    output:
        **{
            name: report(
                f"{COMP}/{name}.csv",
                caption="../report/compensation_tables.rst",
                category="6. Compensation",
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
        mem_mb=500,
    params:
        statement=DATA_STATEMENT,
        tables=COMP_TABLES,
    script:
        "../scripts/compensation_collect.py"
