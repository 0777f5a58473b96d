# Cleaning, one job for every run (thermaxis.cleaning.run.clean_run per run): a run's
# cleaning is a fraction of a second, less than a job's start, so its outputs stay per run
# while the work is dealt to the job's threads (more than one above a few runs a worker).


rule clean:
    input:
        code=code_of("clean.py"),
        sheets=dataset_sheets(),
        raw=[path for run in RUNS for path in raw_files(run)],
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
