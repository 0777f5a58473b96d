rule select_sensitive_points:
    input:
        code=lib("selection", "experiment", "assemble", "decouple"),
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
    params:
        selection=config["selection"],
        decoupling=config["decoupling"],
        decoupled=DECOUPLED,
    script:
        "../scripts/select.py"
