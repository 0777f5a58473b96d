rule fit_predict:
    input:
        code=code_of("fit_predict.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        signals=f"{OUT}/assembled/signals.parquet",
        selection=f"{OUT}/selection/{{fold}}.json",
    output:
        metrics=f"{OUT}/models/{{fold}}/metrics.csv",
        coefficients=f"{OUT}/models/{{fold}}/coefficients.csv",
        kb_predictions=f"{OUT}/models/{{fold}}/kb_predictions.csv",
        error_predictions=f"{OUT}/models/{{fold}}/error_predictions.csv",
    log:
        f"{LOGS}/models/{{fold}}.log",
    benchmark:
        f"{BENCH}/models/{{fold}}.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        approaches=APPROACHES,
        algorithms=ALGORITHMS,
        models=config["models"],
        decoupling=config["decoupling"],
    script:
        "../scripts/fit_predict.py"
