rule clean_run:
    input:
        code=code_of("clean_run.py"),
        sheets=dataset_sheets(),
        raw=lambda wc: raw_files(wc.run),
    output:
        series=f"{OUT}/clean/{{run}}/temperatures.parquet",
        qc=f"{OUT}/clean/{{run}}/qc.csv",
        gaps=f"{OUT}/clean/{{run}}/gaps.csv",
        errors=f"{OUT}/clean/{{run}}/errors.parquet",
        temperatures=f"{OUT}/clean/{{run}}/measurement_temperatures.parquet",
        windows=f"{OUT}/clean/{{run}}/windows.csv",
        signals=f"{OUT}/clean/{{run}}/measurement_signals.parquet",
        signal_series=f"{OUT}/clean/{{run}}/signals.parquet",
        inputs=f"{OUT}/clean/{{run}}/measurement_inputs.parquet",
    log:
        f"{LOGS}/clean/{{run}}.log",
    benchmark:
        f"{BENCH}/clean/{{run}}.tsv"
    conda:
        ENV
    resources:
        **rule_resources("clean_run"),
    params:
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        temperatures=config["temperatures"],
        errors=config["errors"],
        lags_min=list(SETTINGS.recommend.all_lags_min),
    script:
        "../scripts/clean_run.py"
