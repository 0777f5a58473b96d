import os
import sys
from pathlib import Path

from thermaxis.dataset.safety import check_rule_outputs
from thermaxis.errors import DataError
from thermaxis.paper.published import PAPER_DIR as PUBLISHED_DIR
from thermaxis.schemas import schema_path
from thermaxis.pipeline.deps import library_modules
from thermaxis.pipeline.preflight import check_before_jobs
from thermaxis.figures.captions import figure_caption
from thermaxis.dataset.summary import data_statement
from thermaxis.reports.index import PAPER_HEADLINE


envvars:
    "PATH",


# Shell rules call `python`: make it the interpreter running Snakemake (the project's
# venv) even when Snakemake was started by path without activating it. Under
# --sdm conda the rule's environment is activated later and still comes first.
os.environ["PATH"] = (
    os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", "")
)

# One dataset per Snakemake run: --config dataset=<folder>, else the first of `datasets`
# (`make results` runs each listed dataset in turn).
# The config, the dataset and its first data file are validated when the workflow is
# parsed (thermaxis.pipeline.preflight, which the bad-input tests call too), so a bad sheet, a
# missing run folder or a bad config value stops everything with one line before any
# job starts.
try:
    CHECKED = check_before_jobs(config)
except ValueError as exc:
    sys.exit(f"thermaxis error: {exc}")
config["dataset"] = CHECKED.config["dataset"]
DATASET = CHECKED.dataset


RUNS = list(DATASET.run_ids)
OUT = CHECKED.out
LOGS = f"logs/{DATASET.name}"
BENCH = f"benchmarks/{DATASET.name}"
ENV = "../../envs/thermaxis.yaml"
SIMULATED = DATASET.simulated
FOLDS = list(config["folds"]) or RUNS
ALGORITHMS = list(SETTINGS.models.algorithms)
FIG_FORMATS = list(SETTINGS.figures.formats)
FIG_RUN = SETTINGS.figures.run or RUNS[0]
OTHER_RUNS = [r for r in RUNS if r != FIG_RUN]
DATA_STATEMENT = data_statement(
    DATASET.name, SIMULATED, DATASET.meta["provenance"].get("citation", "")
)
# The paper's audit and report belong only to a dataset that reproduces the paper.
PAPER = DATASET.reproduces == "xu2023"
AMBIENT = CHECKED.ambient
HEADLINE = (
    PAPER_HEADLINE
    if PAPER
    else DATASET.meta.get("title", DATASET.meta["description"].strip().split("\n")[0])
)
SIGNALS = list(DATASET.signals)
FIG_ALGORITHMS = [a for a in SETTINGS.figures.algorithms if a in ALGORITHMS]
REPORT_ALGORITHMS = [a for a in SETTINGS.reports.model_algorithms if a in ALGORITHMS]
# Model reports embed the prediction figures of their algorithms, so those are drawn too.
PREDICTION_ALGORITHMS = list(dict.fromkeys(FIG_ALGORITHMS + REPORT_ALGORITHMS))
# The paper's published values and the schemas are package data (relative paths keep the
# executed notebooks independent of where the checkout is).
PAPER_DIR = os.path.relpath(PUBLISHED_DIR)
PAPER_FILES = sorted(str(p) for p in Path(PAPER_DIR).glob("*.csv"))
MODEL_SCHEMA = os.path.relpath(schema_path("compensation_model"))


# With one target there is no line to decouple: the point-by-point branch runs alone.
DECOUPLED = CHECKED.n_positions >= 2
APPROACHES = ["decoupled", "pointwise"] if DECOUPLED else ["pointwise"]
if not DECOUPLED:
    print(
        "thermaxis: the dataset has a single target position; the decoupled (slope/intercept) branch is skipped, "
        "only point-by-point models run",
        file=sys.stderr,
    )

if AMBIENT is None:
    print(
        f"thermaxis: dataset {DATASET.name!r} declares no ambient_sensor; the ambient figure (Fig. 3) and "
        "ambient table are left out",
        file=sys.stderr,
    )
if DATASET.temperature_kind == "rise":
    print(
        f"thermaxis: dataset {DATASET.name!r} logs temperature rises, not absolute temperatures; "
        "the slope model k uses the logged rises in their place",
        file=sys.stderr,
    )


wildcard_constraints:
    approach="decoupled|pointwise",
    algorithm="mlr|svr|ridge|pls|gpr",
    run="|".join(map(lambda r: r.replace(".", r"\."), RUNS)),
    fold="|".join(map(lambda r: r.replace(".", r"\."), RUNS)),


SCRIPTS = Path(workflow.current_basedir).parent / "scripts"


def code_of(entry):
    """Library modules a script (in workflow/scripts) or a notebook imports, directly or not.

    They are inputs of the rule that runs it, so editing a method reruns its results.
    """
    return library_modules(entry if entry.endswith(".ipynb") else SCRIPTS / entry)


def raw_files(run):
    """Every file of a run, so editing any raw log reruns its cleaning."""
    folder = DATASET.root / run
    return sorted(str(p) for p in folder.rglob("*.csv"))


def dataset_sheets():
    return [str(DATASET.root / "dataset.yaml"), str(DATASET.root / "runs.tsv")]


def figure_paths(stem):
    return [f"{OUT}/figures/{stem}.{ext}" for ext in FIG_FORMATS]


def prediction_caption(kind, fold, approach, algorithm):
    """Figs. 11/14-17 share two drawings; the caption names the paper's figure it mirrors."""
    if kind == "error_prediction" and approach == "pointwise":
        return figure_caption(
            "fig11", DATASET.name, SIMULATED, fold=fold, algorithm=algorithm
        )
    return figure_caption(
        kind, DATASET.name, SIMULATED, fold=fold, approach=approach, algorithm=algorithm
    )


def compensation_outputs():
    """model.json, the ST block and the tables (compensation.smk); drift figures are figures."""
    paths = [f"{COMP}/model.json", f"{COMP}/ThermalCompensation.st"]
    return paths + [f"{COMP}/{name}.csv" for name in COMP_TABLES]


def all_outputs():
    return [
        *(p for stem in figure_stems() for p in figure_paths(stem)),
        f"{OUT}/tables/dataset_summary.csv",
        f"{OUT}/assembled/errors.parquet",
        f"{OUT}/tables/cleaning_qc.csv",
        f"{OUT}/tables/metrics.csv",
        *([f"{OUT}/tables/paper_comparison.csv"] if PAPER else []),
        *([f"{OUT}/tables/table5_slope_intercept.csv"] if DECOUPLED else []),
        *compensation_outputs(),
        *report_outputs(),
    ]
