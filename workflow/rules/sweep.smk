# The sweep (`make sweep`, i.e. `snakemake sweep`): every configuration of config `sweep`
# on every leave-one-condition-out fold. Not part of `rule all`: the default run stays fast.
#
# Batches, not one job per configuration: each batch is one process that reads the
# assembled tables once and evaluates its share of the grid with the library function
# the main workflow uses (thermaxis.method.folds.evaluate_configuration). Locally there
# is one batch per core given; on a cluster one per sweep.cluster_batch_size evaluations,
# since the cluster has more cores than a workflow asks for and each job pays a
# scheduling delay (config sweep.batches overrides both). The batch count is part of
# the batch files' path, so runs with other counts do not mix shares of two plans.
import json
import sys

from thermaxis.sweep.plan import (
    batch_count,
    batch_minutes,
    cluster_batch_count,
    cost_estimate,
    plan_units,
)

SWEEP = f"{OUT}/sweep"
SWEEP_GRID = SETTINGS.sweep.grid
SWEEP_FOLDS = list(SETTINGS.sweep.folds) or RUNS
try:
    SWEEP_UNITS, SWEEP_SKIPPED = plan_units(SWEEP_GRID, SWEEP_FOLDS, DATASET.sensors)
except ValueError as exc:
    sys.exit(f"thermaxis error: {exc}")
SWEEP_UNIT_SIZES = [
    len(SWEEP_GRID.unit_configurations(u.selection, DECOUPLED)) for u in SWEEP_UNITS
]
# The executor is chosen after the Snakefile is parsed; what is known then is that a
# cluster run is given --jobs (a profile's `jobs:`; locally --jobs means --cores), and
# that a job the cluster runs parses the workflow again in remote mode: it must find
# the same plan.
SWEEP_ON_CLUSTER = workflow.remote_exec or workflow.resource_settings.nodes is not None
if SWEEP_ON_CLUSTER:
    SWEEP_BATCHES = cluster_batch_count(
        SETTINGS.sweep.batches, SWEEP_UNIT_SIZES, SETTINGS.sweep.cluster_batch_size
    )
else:
    # One batch per core given (None without --cores: one batch).
    SWEEP_BATCHES = batch_count(
        SETTINGS.sweep.batches, workflow.resource_settings.cores, len(SWEEP_UNITS)
    )


SWEEP_BATCH_FILES = expand(
    f"{SWEEP}/batches/{SWEEP_BATCHES}/{{batch}}.parquet", batch=range(SWEEP_BATCHES)
)
SWEEP_PAPERMILL = (
    "papermill {input.notebook:q} {output.notebook:q} -k python3 --no-progress-bar"
    " --start-timeout 120 --execution-timeout 600 -y {params.parameters:q} > {log:q} 2>&1"
    " && python -m thermaxis.reports.notebooks html {output.notebook:q} {output.html:q}"
    " --title {params.title:q} >> {log:q} 2>&1"
)

for _fold in SWEEP_FOLDS:
    if _fold not in RUNS:
        sys.exit(
            f"thermaxis error: config sweep.folds: {_fold!r} is not a run of {DATASET.root / 'runs.tsv'}"
        )
if not SWEEP_UNITS:
    sys.exit(
        "thermaxis error: config sweep: no selection setting fits the dataset "
        f"({'; '.join(SWEEP_SKIPPED)})"
    )

SWEEP_HEATMAP = [f"{SWEEP}/figures/sweep_heatmap.{ext}" for ext in FIG_FORMATS]
SWEEP_EFFECTS = [f"{SWEEP}/figures/sweep_factor_effects.{ext}" for ext in FIG_FORMATS]
SWEEP_EMBED = next((f for f in ("png", "svg") if f in FIG_FORMATS), None)
# papermill parameters of the report (JSON, valid YAML for `papermill -y`); the input
# paths are added per job.
SWEEP_REPORT = dict(
    dataset_name=DATASET.name,
    simulated=SIMULATED,
    statement=DATA_STATEMENT,
    figures={
        stem: f"{SWEEP}/figures/{stem}.{SWEEP_EMBED}" if SWEEP_EMBED else ""
        for stem in ("sweep_heatmap", "sweep_factor_effects")
    },
    grid=config["sweep"],
    folds=SWEEP_FOLDS,
    skipped=SWEEP_SKIPPED,
    selection=config["selection"],
    degree=config["decoupling"]["degree"],
)


# The cost estimate, before the first job starts and only when batches are to run.
onstart:
    if any(j.rule.name == "sweep_batch" for j in workflow.dag.needrun_jobs()):
        _cost = cost_estimate(
            sum(SWEEP_UNIT_SIZES),
            SETTINGS.sweep.seconds_per_evaluation,
            SWEEP_BATCHES,
        )
        print(
            f"thermaxis: sweep of {len(SWEEP_UNITS)} fold x selection units, "
            f"{_cost['evaluations']} evaluations in {SWEEP_BATCHES} batches; estimated "
            f"{_cost['cpu_hours']:.2f} CPU-hours at {_cost['seconds_per_evaluation']:g} s each "
            "(config sweep.seconds_per_evaluation), "
            f">= {_cost['wall_minutes']:.1f} min wall with every batch running at once",
            file=sys.stderr,
        )


wildcard_constraints:
    batch=r"\d+",
    n_batches=r"\d+",


rule sweep_batch:
    input:
        code=code_of("sweep_batch.py"),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
    output:
        f"{SWEEP}/batches/{{n_batches}}/{{batch}}.parquet",
    log:
        f"{LOGS}/sweep/batch_{{n_batches}}_{{batch}}.log",
    benchmark:
        f"{BENCH}/sweep/batch_{{n_batches}}_{{batch}}.tsv"
    conda:
        ENV
    threads: 1
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: attempt
        * batch_minutes(
            SWEEP_GRID,
            SWEEP_UNITS,
            int(w.n_batches),
            int(w.batch),
            SETTINGS.sweep.seconds_per_evaluation,
            DECOUPLED,
        ),
    params:
        sweep=config["sweep"],
        selection=config["selection"],
        models=config["models"],
        folds=SWEEP_FOLDS,
        sensors=list(DATASET.sensors),
        n_batches=lambda w: int(w.n_batches),
        decoupled=DECOUPLED,
    script:
        "../scripts/sweep_batch.py"


rule sweep_collect:
    input:
        code=code_of("sweep_collect.py"),
        batches=SWEEP_BATCH_FILES,
    output:
        summary=f"{SWEEP}/summary.csv",
        ranking=f"{SWEEP}/ranking.csv",
        effects=f"{SWEEP}/factor_effects.csv",
    log:
        f"{LOGS}/sweep/collect.log",
    benchmark:
        f"{BENCH}/sweep/collect.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        selection=config["selection"],
        decoupling=config["decoupling"],
    script:
        "../scripts/sweep_collect.py"


rule sweep_heatmap:
    input:
        code=code_of("sweep_plot.py"),
        ranking=f"{SWEEP}/ranking.csv",
    output:
        figures=SWEEP_HEATMAP,
    log:
        f"{LOGS}/sweep/heatmap.log",
    benchmark:
        f"{BENCH}/sweep/heatmap.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        selection=config["selection"],
        decoupling=config["decoupling"],
        simulated=SIMULATED,
        dpi=SETTINGS.figures.dpi,
    script:
        "../scripts/sweep_plot.py"


rule sweep_factor_effects:
    input:
        code=code_of("sweep_plot.py"),
        ranking=f"{SWEEP}/ranking.csv",
    output:
        figures=SWEEP_EFFECTS,
    log:
        f"{LOGS}/sweep/factor_effects.log",
    benchmark:
        f"{BENCH}/sweep/factor_effects.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 500 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        simulated=SIMULATED,
        dpi=SETTINGS.figures.dpi,
    script:
        "../scripts/sweep_plot.py"


rule sweep_report:
    input:
        library=code_of("notebooks/sweep_report.ipynb"),
        notebook="notebooks/sweep_report.ipynb",
        summary=f"{SWEEP}/summary.csv",
        ranking=f"{SWEEP}/ranking.csv",
        effects=f"{SWEEP}/factor_effects.csv",
        figures=SWEEP_HEATMAP + SWEEP_EFFECTS,
        benchmarks=expand(
            f"{BENCH}/sweep/batch_{SWEEP_BATCHES}_{{batch}}.tsv",
            batch=range(SWEEP_BATCHES),
        ),
    output:
        notebook=f"{SWEEP}/sweep_report.ipynb",
        html=report(
            f"{SWEEP}/sweep_report.html",
            caption="../report/notebook_report.rst",
            category="8. Sweep",
            labels={"report": "sweep"},
        ),
    log:
        f"{LOGS}/sweep/report.log",
    benchmark:
        f"{BENCH}/sweep/report.tsv"
    conda:
        ENV
    resources:
        mem_mb=lambda w, attempt: 750 * attempt,
        runtime=lambda w, attempt: 5 * attempt,
    params:
        title=f"Sweep report: {DATASET.name}",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: json.dumps(
            {
                **SWEEP_REPORT,
                **{k: input[k] for k in ("summary", "ranking", "effects")},
                "benchmarks": list(input.benchmarks),
            },
            sort_keys=True,
        ),
    shell:
        SWEEP_PAPERMILL


rule sweep:
    input:
        f"{SWEEP}/summary.csv",
        f"{SWEEP}/ranking.csv",
        f"{SWEEP}/factor_effects.csv",
        SWEEP_HEATMAP,
        SWEEP_EFFECTS,
        f"{SWEEP}/sweep_report.html",
