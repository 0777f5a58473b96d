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
        series=expand(out(paths.CLEAN_SERIES), run=RUNS),
        qc=expand(out(paths.CLEAN_QC), run=RUNS),
        gaps=expand(out(paths.CLEAN_GAPS), run=RUNS),
        errors=expand(out(paths.CLEAN_ERRORS), run=RUNS),
        temperatures=expand(out(paths.CLEAN_TEMPERATURES), run=RUNS),
        windows=expand(out(paths.CLEAN_WINDOWS), run=RUNS),
        signals=expand(out(paths.CLEAN_SIGNALS), run=RUNS),
        signal_series=expand(out(paths.CLEAN_SIGNAL_SERIES), run=RUNS),
        inputs=expand(out(paths.CLEAN_INPUTS), run=RUNS),
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
