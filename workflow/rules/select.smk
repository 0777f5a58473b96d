rule select_sensitive_points:
    input:
        code=code_of("select.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
    output:
        selection=f"{OUT}/selection/{{fold}}.json",
        table=f"{OUT}/selection/{{fold}}.csv",
    log:
        f"{LOGS}/select/{{fold}}.log",
    benchmark:
        f"{BENCH}/select/{{fold}}.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        selection=config["selection"],
        decoupling=config["decoupling"],
        decoupled=DECOUPLED,
    script:
        "../scripts/select.py"
