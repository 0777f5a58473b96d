# What needs Snakemake; the plan, result files, targets and resources (thermaxis.pipeline:
# plan, paths, targets, tuning) and the pages (thermaxis.reports.pages) are library code,
# tested without Snakemake. The other rule files define rules only (paths below OUT, LOGS, BENCH).
import functools
import json
import os
import sys
from pathlib import Path

from thermaxis import vocabulary
from thermaxis.figures import registry
from thermaxis.paper.published import PAPER_DIR as PUBLISHED_DIR
from thermaxis.pipeline import paths, preflight, targets, tuning
from thermaxis.pipeline.deps import library_modules, named_modules
from thermaxis.pipeline.plan import compensation_params, plan_of, recommend_params
from thermaxis.reports import pages
from thermaxis.reports.pages import CATEGORY
from thermaxis.reports.provenance import git_state
from thermaxis.schemas import schema_path
from thermaxis.sweep.plan import cost_note


envvars:
    "PATH",


# Shell rules call `python`: the interpreter running Snakemake (the project's venv), even
# unactivated. Under --sdm conda the rule's environment is activated later, first.
os.environ["PATH"] = (
    os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", "")
)

# --------------------------------------------------------------------------- the plan
# One dataset per run (--config dataset=<folder>, else the first of `datasets`). The one
# parse-time gate validates the config once and checks the dataset: a bad value stops
# everything with one line before any job starts (the bad-input tests call it too).
with preflight.one_line():
    CHECKED = preflight.check_before_jobs(config)
config.update(CHECKED.config)
SETTINGS, DATASET, PLAN = CHECKED.settings, CHECKED.dataset, plan_of(CHECKED)
RUNS, FOLDS = list(PLAN.runs), list(PLAN.folds)
SIMULATED, PAPER, DECOUPLED = PLAN.simulated, PLAN.paper, PLAN.decoupled
AMBIENT, DATA_STATEMENT = PLAN.ambient, PLAN.statement
APPROACHES, ALGORITHMS = list(PLAN.approaches), list(PLAN.algorithms)
if PLAN.left_out():
    _left_out = "; ".join(PLAN.left_out())
    print(f"thermaxis: dataset {DATASET.name!r}: {_left_out}", file=sys.stderr)

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
dataset_sheets = functools.partial(targets.dataset_sheets, DATASET.root)
dataset_files = functools.partial(targets.dataset_files, DATASET.root)


def out(path, **wildcards):
    """A result file (thermaxis.pipeline.paths) below OUT, its ``wildcards`` filled."""
    return paths.under(OUT, path, **wildcards)


def code_of(entry):
    """Library modules a script (in workflow/scripts) or a notebook imports, directly or
    not: inputs of the rule that runs it, so editing a method reruns its results."""
    return library_modules(entry if entry.endswith(".ipynb") else SCRIPTS / entry)


wildcard_constraints:
    approach=targets.one_of(vocabulary.APPROACHES),
    algorithm=targets.one_of(vocabulary.ALGORITHMS),
    run=targets.one_of(RUNS),
    fold=targets.one_of(RUNS),
    batch=r"\d+",
    n_batches=r"\d+",


def filed(records):
    """``records`` (name: a path or a targets.Filed), filed ones in the Snakemake report."""
    return {name: in_report(r) for name, r in records.items()}


def in_report(r):
    if not isinstance(r, targets.Filed):
        return r
    category, caption = CATEGORY[r.category], f"../report/{r.caption}.rst"
    return report(r.path, caption=caption, category=category, labels=r.labels)


# --------------------------------------------------------------------------- figures
# The figure table (thermaxis.figures.registry): figures.smk has one rule per family.
FACTS = pages.figure_facts(
    PLAN, DATASET.signal_units(), config["selection"], config["decoupling"]["degree"]
)
FIGURES = registry.expand(FACTS, "all")
SWEEP_FIGURES = registry.expand(FACTS, "sweep")
FIGURE_FAMILIES = targets.families(FIGURES + SWEEP_FIGURES)


def figure_code(figures):
    """plot.py's library modules, and those of its figures' drawing functions and readers."""
    drawn = [p for f in figures for p in (f.draw, f.reader) if p]
    names = {f"thermaxis.{p.rsplit('.', 1)[0]}" for p in drawn}
    return sorted(set(code_of("plot.py")) | set(named_modules(*names)))


def figure_output(figure, wildcards):
    """A figure's files, filed in the Snakemake report when it has a category."""
    files = targets.figure_paths(PLAN, OUT, figure, **wildcards)
    if figure.category is None:
        return files
    caption, category = "../report/figure.rst", CATEGORY[figure.category]
    fields = figure.report_fields(wildcards)
    return report(files, caption=caption, category=category, **fields)


# Commit and dirty flag, taken once per run and only by a job that records them.
git_of_checkout = functools.cache(functools.partial(git_state, REPO))


# --------------------------------------------------------------------------- sweep
# `make sweep` (sweep.smk), not part of `rule all`. A cluster run is given --jobs, and a
# job the cluster runs parses the workflow again in remote mode: it must find the same
# plan (preflight.sweep_plan).
SWEEP_ON_CLUSTER = workflow.remote_exec or workflow.resource_settings.nodes is not None
SECONDS_PER_EVALUATION = SETTINGS.sweep.seconds_per_evaluation


@functools.cache
def sweep_plan():
    """The sweep's units and batches, planned the first time a sweep job asks for them."""
    with preflight.one_line():
        cores = workflow.resource_settings.cores
        return preflight.sweep_plan(CHECKED, cores, SWEEP_ON_CLUSTER)


def sweep_batch_files(wildcards):
    n = sweep_plan().batches
    return expand(out(paths.SWEEP_BATCH, n_batches=n, batch="{batch}"), batch=range(n))


def sweep_batch_benchmarks(wildcards):
    n = sweep_plan().batches
    return expand(f"{BENCH}/sweep/batch_{n}_{{batch}}.tsv", batch=range(n))


def sweep_batch_minutes(wildcards):
    n, batch, grid = int(wildcards.n_batches), int(wildcards.batch), SETTINGS.sweep.grid
    units, cost = sweep_plan().units, SECONDS_PER_EVALUATION
    return tuning.batch_minutes(grid, units, n, batch, cost, DECOUPLED)


def sweep_report_parameters(wildcards, input):
    folds, skipped = CHECKED.sweep_folds, sweep_plan().skipped
    return PAGES.sweep_parameters(SWEEP_FIGURES, folds, skipped, input)


# The cost estimate, before the first job starts and only when batches are to run.
onstart:
    if any(j.rule.name == "sweep_batch" for j in workflow.dag.needrun_jobs()):
        s = sweep_plan()
        note = cost_note(
            len(s.units), s.evaluations, s.batches, SECONDS_PER_EVALUATION
        )
        print(note, file=sys.stderr)


# --------------------------------------------------------------------------- resources
RESOURCES = tuning.resource_table(len(RUNS), len(FOLDS), sweep_batch_minutes)
rule_resources = functools.partial(tuning.rule_resources, RESOURCES)
rule_priority = tuning.rule_priority
FOLD_THREADS, CLEAN_THREADS = PLAN.fold_threads, PLAN.clean_threads


# --------------------------------------------------------------------------- params
COMP_TABLES = list(targets.COMPENSATION_TABLES)
COMP_PARAMS = compensation_params(CHECKED, PLAN)
RECOMMEND_PARAMS = recommend_params(CHECKED, PLAN)


# --------------------------------------------------------------------------- targets
PAGES = pages.Pages(PLAN, OUT, FACTS, FIGURES, config, REPO)


all_outputs = functools.partial(targets.all_outputs, PLAN, OUT, FIGURES)


def check_rules(rules):
    """The last parse-time check, once every rule is defined (preflight.check_rules)."""
    with preflight.one_line():
        preflight.check_rules(rules, CHECKED)
