# What needs Snakemake: the parse-time gate and the plan, the wildcard constraints, the
# report()/expand wrappers, the sweep's plan and onstart. The plan (thermaxis.pipeline.plan),
# the result files (.paths), the targets (.targets), the resources (.tuning) and the pages
# (thermaxis.reports.pages) are library code, unit-tested without Snakemake. The other
# rule files define rules only; their paths start with OUT, LOGS or BENCH.
import functools
import json
import os
import sys
from pathlib import Path

from thermaxis import vocabulary
from thermaxis.figures import registry
from thermaxis.figures.family import family_workers
from thermaxis.paper.published import PAPER_DIR as PUBLISHED_DIR
from thermaxis.pipeline import paths, preflight, targets, tuning
from thermaxis.pipeline.deps import library_modules, named_modules
from thermaxis.pipeline.plan import plan_of
from thermaxis.reports import pages
from thermaxis.reports.pages import (
    CATEGORY,
    DATA_SECTIONS,
    RUN_NOTEBOOK,
    RUN_NOTEBOOK_PAGES,
)
from thermaxis.reports.provenance import git_state
from thermaxis.schemas import schema_path
from thermaxis.sweep.plan import batch_minutes, cost_estimate


envvars:
    "PATH",


# Shell rules call `python`: make it the interpreter running Snakemake (the project's
# venv) even when Snakemake was started by path without activating it. Under
# --sdm conda the rule's environment is activated later and still comes first.
os.environ["PATH"] = (
    os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", "")
)

# --------------------------------------------------------------------------- the plan
# One dataset per Snakemake run: --config dataset=<folder>, else the first of `datasets`.
# thermaxis.pipeline.preflight is the one parse-time gate (the bad-input tests call it
# too): the config is validated once, its defaults filled, and the dataset checked, so a
# bad value stops everything with one line before any job starts.
with preflight.one_line():
    CHECKED = preflight.check_before_jobs(config)
config.update(CHECKED.config)
SETTINGS, DATASET, PLAN = CHECKED.settings, CHECKED.dataset, plan_of(CHECKED)
RUNS, FOLDS = list(PLAN.runs), list(PLAN.folds)
SIMULATED, PAPER, DECOUPLED = PLAN.simulated, PLAN.paper, PLAN.decoupled
AMBIENT, DATA_STATEMENT = PLAN.ambient, PLAN.statement
APPROACHES, ALGORITHMS = list(PLAN.approaches), list(PLAN.algorithms)
if PLAN.left_out():
    print(
        f"thermaxis: dataset {DATASET.name!r}: {'; '.join(PLAN.left_out())}",
        file=sys.stderr,
    )

# Every output, log and benchmark is below OUT, LOGS or BENCH (preflight.check_rules).
OUT, LOGS, BENCH = CHECKED.out, CHECKED.logs, CHECKED.bench
ENV = "../../envs/thermaxis.yaml"
SCRIPTS = Path(workflow.current_basedir).parent / "scripts"
# Relative paths keep the executed notebooks independent of where the checkout is (git
# follows the symlinks of a test work folder).
REPO = os.path.relpath(str(workflow.current_basedir))
PAPER_DIR = os.path.relpath(PUBLISHED_DIR)
PAPER_FILES = sorted(str(p) for p in Path(PAPER_DIR).glob("*.csv"))
MODEL_SCHEMA = os.path.relpath(schema_path("compensation_model"))
# The jobs that read raw files depend on one manifest of them, not on every raw file:
# Snakemake records a checksum of every input for every output of a job (36 s at 43 runs).
DATA_MANIFEST = f"{OUT}/{paths.DATA_MANIFEST}"
MODEL_TABLES = list(targets.MODEL_TABLES)


def out(path, **wildcards):
    """A result file (thermaxis.pipeline.paths) below OUT, its ``wildcards`` filled."""
    return paths.under(OUT, path, **wildcards)


def code_of(entry):
    """Library modules a script (in workflow/scripts) or a notebook imports, directly or
    not: inputs of the rule that runs it, so editing a method reruns its results."""
    return library_modules(entry if entry.endswith(".ipynb") else SCRIPTS / entry)


def dataset_sheets():
    return targets.dataset_sheets(DATASET.root)


def dataset_files():
    return targets.dataset_files(DATASET.root)


def _one_of(names):
    return "|".join(name.replace(".", r"\.") for name in names)


wildcard_constraints:
    approach=_one_of(vocabulary.APPROACHES),
    algorithm=_one_of(vocabulary.ALGORITHMS),
    run=_one_of(RUNS),
    fold=_one_of(RUNS),
    batch=r"\d+",
    n_batches=r"\d+",


# --------------------------------------------------------------------------- report()
def filed(record):
    """A path, or a targets.Filed record filed in the Snakemake report."""
    if not isinstance(record, targets.Filed):
        return record
    caption = f"../report/{record.caption}.rst"
    category = CATEGORY[record.category]
    return report(record.path, caption=caption, category=category, labels=record.labels)


def dataset_tables():
    return {k: filed(v) for k, v in targets.dataset_tables(PLAN, OUT).items()}


def audit_tables():
    return {k: filed(v) for k, v in targets.audit_tables(PLAN, OUT).items()}


# --------------------------------------------------------------------------- figures
# The figure table (thermaxis.figures.registry): figures.smk has one rule per family.
units, selection = DATASET.signal_units(), config["selection"]
FACTS = pages.figure_facts(PLAN, units, selection, config["decoupling"]["degree"])
FIGURES = registry.expand(FACTS, "all")
SWEEP_FIGURES = registry.expand(FACTS, "sweep")
FIGURE_FAMILIES = {}
for _figure in FIGURES + SWEEP_FIGURES:
    FIGURE_FAMILIES.setdefault(_figure.family, []).append(_figure)


def figure_code(figures):
    """plot.py's library modules, and those of its figures' drawing functions and readers."""
    drawn = [p for f in figures for p in (f.draw, f.reader) if p]
    names = {f"thermaxis.{p.rsplit('.', 1)[0]}" for p in drawn}
    return sorted(set(code_of("plot.py")) | set(named_modules(*names)))


def figure_threads(figures):
    """Processes a family's job can use: one per MIN_FIGURES_PER_WORKER of its figures."""
    n = len(targets.figure_instances(PLAN, figures))
    return family_workers(n, n)


def figure_output(figure, wildcards):
    """A figure's files, filed in the Snakemake report when it has a category."""
    files = targets.figure_paths(PLAN, OUT, figure, **wildcards)
    if figure.category is None:
        return files
    caption, category = "../report/figure.rst", CATEGORY[figure.category]
    fields = figure.report_fields(wildcards)
    return report(files, caption=caption, category=category, **fields)


# --------------------------------------------------------------------------- reports
@functools.cache
def git_of_checkout():
    """Commit and dirty flag, taken once per run and only by a job that records them."""
    return git_state(REPO)


# --------------------------------------------------------------------------- sweep
# The sweep (`make sweep`, i.e. `snakemake sweep`): every configuration of config `sweep`
# on every leave-one-condition-out fold, in batches (sweep.smk); not part of `rule all`.
# The executor is chosen after the Snakefile is parsed; what is known then is that a
# cluster run is given --jobs (a profile's `jobs:`; locally --jobs means --cores), and
# that a job the cluster runs parses the workflow again in remote mode: it must find
# the same plan (preflight.sweep_plan).
SWEEP_ON_CLUSTER = workflow.remote_exec or workflow.resource_settings.nodes is not None


@functools.cache
def sweep_plan():
    """The sweep's units and batches, planned the first time a sweep job asks for them."""
    with preflight.one_line():
        return preflight.sweep_plan(
            CHECKED, workflow.resource_settings.cores, SWEEP_ON_CLUSTER
        )


def sweep_batch_files(wildcards):
    n = sweep_plan().batches
    return expand(out(paths.SWEEP_BATCH, n_batches=n, batch="{batch}"), batch=range(n))


def sweep_batch_benchmarks(wildcards):
    n = sweep_plan().batches
    return expand(f"{BENCH}/sweep/batch_{n}_{{batch}}.tsv", batch=range(n))


def sweep_batch_minutes(wildcards):
    return batch_minutes(
        SETTINGS.sweep.grid,
        sweep_plan().units,
        int(wildcards.n_batches),
        int(wildcards.batch),
        SETTINGS.sweep.seconds_per_evaluation,
        DECOUPLED,
    )


def sweep_report_parameters(wildcards, input):
    folds, skipped = CHECKED.sweep_folds, sweep_plan().skipped
    return PAGES.sweep_parameters(SWEEP_FIGURES, folds, skipped, input)


# The cost estimate, before the first job starts and only when batches are to run.
onstart:
    if any(j.rule.name == "sweep_batch" for j in workflow.dag.needrun_jobs()):
        _plan = sweep_plan()
        _cost = cost_estimate(
            _plan.evaluations, SETTINGS.sweep.seconds_per_evaluation, _plan.batches
        )
        print(
            f"thermaxis: sweep of {len(_plan.units)} fold x selection units, "
            f"{_cost['evaluations']} evaluations in {_plan.batches} batches; estimated "
            f"{_cost['cpu_hours']:.2f} CPU-hours at {_cost['seconds_per_evaluation']:g} s each "
            "(config sweep.seconds_per_evaluation), "
            f">= {_cost['wall_minutes']:.1f} min wall with every batch running at once",
            file=sys.stderr,
        )


# --------------------------------------------------------------------------- resources
RESOURCES = tuning.resource_table(len(RUNS), len(FOLDS), sweep_batch_minutes)


def rule_resources(name):
    return tuning.rule_resources(RESOURCES, name)


rule_priority = tuning.rule_priority
FOLD_THREADS, CLEAN_THREADS = PLAN.fold_threads, PLAN.clean_threads


# --------------------------------------------------------------------------- compensation
# The deployable compensation: the configured model fitted on all runs (model.json and a
# Structured Text block), and per held-out run the controller exports of that fold's
# model and the error left after compensating. Folds stay for evaluation only.
# A single target has no slope: the point-by-point model gives an offset (SD43900 alone).
COMP_APPROACH = SETTINGS.compensation.approach if DECOUPLED else "pointwise"
COMP_ALGORITHM = SETTINGS.compensation.algorithm
COMP_TABLES = ["siemens_840d", "twincat", "residuals", "iso230_2", "summary"]
COMP_PARAMS = dict(
    approach=COMP_APPROACH,
    model=SETTINGS.compensation.model,
    sections={
        name: config[name]
        for name in ("selection", "decoupling", "models", "compensation")
    },
    about=dict(dataset=DATASET.name, simulated=SIMULATED, statement=DATA_STATEMENT),
    signals=list(DATASET.signals),
)


# --------------------------------------------------------------------------- recommendation
# Which model the runs support: one job per outer fold scores every candidate (inner
# leave-one-condition-out on the other runs, and the held-out run), one job chooses
# (thermaxis.method.recommend). The compensation deploys its choice (compensation.model).
RECOMMEND_PARAMS = dict(
    recommend=config["recommend"],
    selection=config["selection"],
    models=config["models"],
    decoupling=config["decoupling"],
    decoupled=DECOUPLED,
    signals=list(DATASET.signals),
)


# --------------------------------------------------------------------------- targets
PAGES = pages.Pages(PLAN, OUT, FACTS, FIGURES, config, REPO, tuple(COMP_TABLES))


def all_outputs():
    return targets.all_outputs(PLAN, OUT, FIGURES, COMP_TABLES)


def check_rules(rules):
    """The last parse-time check, once every rule is defined (preflight.check_rules)."""
    with preflight.one_line():
        preflight.check_rules(rules, CHECKED)
