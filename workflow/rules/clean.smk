# The dataset's manifest (common.smk, DATA_MANIFEST), then cleaning, one job for every run
# (thermaxis.cleaning.run.clean_run per run): a run's cleaning is a fraction of a second,
# less than a job's start, so its outputs stay per run while the work is dealt to the
# job's threads (more than one above a few runs a worker).


rule data_manifest:
    input:
        code=code_of("data_manifest.py"),
        sheets=dataset_sheets(),
        data=dataset_files(),
    output:
        DATA_MANIFEST,
    log:
        f"{LOGS}/data_manifest.log",
    benchmark:
        f"{BENCH}/data_manifest.tsv"
    conda:
        ENV
    resources:
        **rule_resources("data_manifest"),
    params:
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
    script:
        "../scripts/data_manifest.py"


rule clean:
    input:
        code=code_of("clean.py"),
        sheets=dataset_sheets(),
        manifest=DATA_MANIFEST,
    output:
        series=expand(f"{OUT}/clean/{{run}}/temperatures.parquet", run=RUNS),
        qc=expand(f"{OUT}/clean/{{run}}/qc.csv", run=RUNS),
        gaps=expand(f"{OUT}/clean/{{run}}/gaps.csv", run=RUNS),
        errors=expand(f"{OUT}/clean/{{run}}/errors.parquet", run=RUNS),
        temperatures=expand(
            f"{OUT}/clean/{{run}}/measurement_temperatures.parquet", run=RUNS
        ),
        windows=expand(f"{OUT}/clean/{{run}}/windows.csv", run=RUNS),
        signals=expand(f"{OUT}/clean/{{run}}/measurement_signals.parquet", run=RUNS),
        signal_series=expand(f"{OUT}/clean/{{run}}/signals.parquet", run=RUNS),
        inputs=expand(f"{OUT}/clean/{{run}}/measurement_inputs.parquet", run=RUNS),
    log:
        f"{LOGS}/clean.log",
    benchmark:
        f"{BENCH}/clean.tsv"
    conda:
        ENV
    threads: CLEAN_THREADS
    resources:
        **rule_resources("clean"),
    params:
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        runs=RUNS,
        temperatures=config["temperatures"],
        errors=config["errors"],
        lags_min=list(SETTINGS.recommend.all_lags_min),
    script:
        "../scripts/clean.py"
