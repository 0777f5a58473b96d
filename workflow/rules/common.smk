# All of the workflow's state: every global and every function the rules call, in blocks
# (dataset, paths, vocabulary, figures, reports, compensation, sweep, resources, targets).
# The other rule files define rules only (snakemake --lint wants functions here); their
# paths start with OUT, LOGS or BENCH.
import functools
import json
import os
import sys
from pathlib import Path

from thermaxis import vocabulary
from thermaxis.dataset.summary import data_statement
from thermaxis.figures import registry
from thermaxis.figures.captions import figure_caption, provenance_note
from thermaxis.figures.family import family_workers
from thermaxis.paper.published import PAPER_DIR as PUBLISHED_DIR
from thermaxis.pipeline import preflight
from thermaxis.pipeline.deps import library_modules, named_modules
from thermaxis.pipeline.parallel import fold_workers
from thermaxis.pipeline.resources import MIN_MEMORY_MB, MIN_RUNTIME_MIN, per_attempt
from thermaxis.reports.index import PAPER_HEADLINE
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

# --------------------------------------------------------------------------- dataset
# One dataset per Snakemake run: --config dataset=<folder>, else the first of `datasets`
# (`make results` runs each listed dataset in turn). thermaxis.pipeline.preflight is the
# one parse-time gate (the bad-input tests call it too): the config is validated once,
# its defaults filled, and the dataset, its sheets and its first data file are checked,
# so a bad value stops everything with one line before any job starts. The rules read
# the validated config.
with preflight.one_line():
    CHECKED = preflight.check_before_jobs(config)
config.update(CHECKED.config)
SETTINGS = CHECKED.settings
DATASET = CHECKED.dataset
RUNS = CHECKED.runs
FOLDS = CHECKED.folds
SIMULATED = DATASET.simulated
# The paper's audit and report belong only to a dataset that reproduces the paper.
PAPER = DATASET.reproduces == "xu2023"
DATA_STATEMENT = data_statement(
    DATASET.name,
    SIMULATED,
    DATASET.meta["provenance"].get("citation", ""),
    reproduces_paper=PAPER,
)
# The note stamped on the dataset's figures (None for measured data).
STAMP = provenance_note(SIMULATED, twin=PAPER)
AMBIENT = CHECKED.ambient
HEADLINE = (
    PAPER_HEADLINE
    if PAPER
    else DATASET.meta.get("title", DATASET.meta["description"].strip().split("\n")[0])
)
# With one target there is no line to decouple: the point-by-point branch runs alone.
DECOUPLED = CHECKED.n_positions >= 2

# What the dataset leaves out, in one line before the first job.
_LEFT_OUT = []
if not DECOUPLED:
    _LEFT_OUT.append(
        "a single target position: the decoupled (slope/intercept) branch is skipped, "
        "only point-by-point models run"
    )
if AMBIENT is None:
    _LEFT_OUT.append(
        "no ambient_sensor: the ambient figure (Fig. 3) and ambient table are left out"
    )
if DATASET.temperature_kind == "rise":
    _LEFT_OUT.append(
        "temperature rises logged, not absolute temperatures: the slope model k uses "
        "the logged rises in their place"
    )
if _LEFT_OUT:
    print(
        f"thermaxis: dataset {DATASET.name!r}: {'; '.join(_LEFT_OUT)}", file=sys.stderr
    )

# --------------------------------------------------------------------------- paths
# Every output, log and benchmark is below OUT, LOGS or BENCH (preflight.check_rules,
# the Snakefile's last line, refuses any other).
OUT = CHECKED.out
LOGS = CHECKED.logs
BENCH = CHECKED.bench
ENV = "../../envs/thermaxis.yaml"
SCRIPTS = Path(workflow.current_basedir).parent / "scripts"
# A path inside the repository, relative so the executed notebooks do not depend on
# where the work folder is; git follows the symlinks of a test work folder.
REPO = os.path.relpath(str(workflow.current_basedir))
# The paper's published values and the schemas are package data (relative paths keep the
# executed notebooks independent of where the checkout is).
PAPER_DIR = os.path.relpath(PUBLISHED_DIR)
PAPER_FILES = sorted(str(p) for p in Path(PAPER_DIR).glob("*.csv"))
MODEL_SCHEMA = os.path.relpath(schema_path("compensation_model"))


def code_of(entry):
    """Library modules a script (in workflow/scripts) or a notebook imports, directly or not.

    They are inputs of the rule that runs it, so editing a method reruns its results.
    """
    return library_modules(entry if entry.endswith(".ipynb") else SCRIPTS / entry)


# The jobs that read raw files (clean, compensation) depend on the dataset's manifest,
# one file made from every raw file by the data_manifest job. Snakemake records a
# checksum of every input for every output of a job, so one job with every run's outputs
# and every run's files as inputs cost outputs x inputs checksums (36 s at 43 runs).
DATA_MANIFEST = f"{OUT}/data_manifest.sha256"


def dataset_sheets():
    return [str(DATASET.root / "dataset.yaml"), str(DATASET.root / "runs.tsv")]


def dataset_files():
    """Every file of the dataset but its two sheets: what provenance.json hashes."""
    sheets = set(dataset_sheets())
    files = (str(p) for p in DATASET.root.rglob("*") if p.is_file())
    return sorted(f for f in files if f not in sheets)


# --------------------------------------------------------------------------- vocabulary
APPROACHES = list(vocabulary.APPROACHES) if DECOUPLED else ["pointwise"]
ALGORITHMS = list(SETTINGS.models.algorithms)
# A stage job with many folds spreads them over this many processes (thermaxis.pipeline.
# parallel: one per FOLDS_PER_WORKER[stage] folds), which Snakemake caps at --cores.
FOLD_THREADS = {
    stage: fold_workers(len(FOLDS), len(FOLDS), stage)
    for stage in ("models", "recommend")
}
# The clean job's unit is a run (every run, whatever the folds).
CLEAN_THREADS = fold_workers(len(RUNS), len(RUNS), "clean")
# The tables each fold of the models rule writes (thermaxis.method.folds.SORT_KEYS).
MODEL_TABLES = [
    "metrics",
    "coefficients",
    "kb_predictions",
    "error_predictions",
    "fitting",
]
FIG_ALGORITHMS = [a for a in SETTINGS.figures.algorithms if a in ALGORITHMS]
REPORT_ALGORITHMS = [a for a in SETTINGS.reports.model_algorithms if a in ALGORITHMS]
# Model reports embed the prediction figures of their algorithms, so those are drawn too.
PREDICTION_ALGORITHMS = list(dict.fromkeys(FIG_ALGORITHMS + REPORT_ALGORITHMS))
# The paper's report shows its two algorithms.
PAPER_ALGORITHMS = [a for a in ("mlr", "svr") if a in FIG_ALGORITHMS]


def _one_of(names):
    return "|".join(name.replace(".", r"\.") for name in names)


wildcard_constraints:
    approach=_one_of(vocabulary.APPROACHES),
    algorithm=_one_of(vocabulary.ALGORITHMS),
    run=_one_of(RUNS),
    fold=_one_of(RUNS),
    batch=r"\d+",
    n_batches=r"\d+",


# --------------------------------------------------------------------------- assembly
def dataset_tables():
    """What assemble writes beside the assembled runs when the dataset has it: Table 1's
    ambient ranges (an ambient sensor) and the decoupling of Table 5 (two positions or more).
    """
    tables = {}
    if AMBIENT:
        tables["ambient"] = report(
            f"{OUT}/tables/ambient_ranges.csv",
            caption="../report/ambient_ranges.rst",
            category=CATEGORY["dataset"],
            labels={"table": "ambient ranges (Table 1)"},
        )
        tables["ambient_series"] = f"{OUT}/tables/ambient_series.parquet"
    if DECOUPLED:
        tables["kb"] = report(
            f"{OUT}/tables/table5_slope_intercept.csv",
            caption="../report/table5.rst",
            category=CATEGORY["decoupling"],
            labels={"table": "Table 5"},
        )
        tables["kb_markdown"] = f"{OUT}/tables/table5_slope_intercept.md"
        tables["polynomials"] = f"{OUT}/decoupled/polynomial_coefficients.csv"
    return tables


# --------------------------------------------------------------------------- figures
# Every figure comes from the figure table (thermaxis.figures.registry); figures.smk
# defines one rule per family, one job each. FACTS is what the table's conditions and arguments name.
FIG_FORMATS = list(SETTINGS.figures.formats)
FIG_RUN = SETTINGS.figures.run or RUNS[0]
OTHER_RUNS = [r for r in RUNS if r != FIG_RUN]
FACTS = registry.Facts(
    dataset_name=DATASET.name,
    simulated=SIMULATED,
    twin=PAPER,
    decoupled=DECOUPLED,
    ambient=AMBIENT is not None,
    run=FIG_RUN,
    other_runs=OTHER_RUNS,
    folds=FOLDS,
    approaches=APPROACHES,
    prediction_algorithms=PREDICTION_ALGORITHMS,
    units=DATASET.signal_units(),
    selection=config["selection"],
    degree=config["decoupling"]["degree"],
)
FIGURES = registry.expand(FACTS, "all")
SWEEP_FIGURES = registry.expand(FACTS, "sweep")
FIGURE_FAMILIES = {}
for _figure in FIGURES + SWEEP_FIGURES:
    FIGURE_FAMILIES.setdefault(_figure.family, []).append(_figure)
# The format a report embeds.
EMBED_FORMAT = next((f for f in ("png", "svg") if f in FIG_FORMATS), FIG_FORMATS[0])


def figure_paths(figure, **wildcards):
    """Every format's file of a figure (with a per-fold figure's ``{fold}`` unless given)."""
    stem = figure.stem.format(**wildcards) if wildcards else figure.stem
    return [f"{OUT}/{figure.folder}/{stem}.{ext}" for ext in FIG_FORMATS]


def figure_code(figures):
    """plot.py's library modules, and those of its figures' drawing functions and readers."""
    names = {
        f"thermaxis.{path.rsplit('.', 1)[0]}"
        for fig in figures
        for path in (fig.draw, fig.reader)
        if path
    }
    return sorted(set(code_of("plot.py")) | set(named_modules(*names)))


def figure_threads(figures):
    """Processes a family's job can use: one per MIN_FIGURES_PER_WORKER of its figures."""
    n = len(figure_instances(figures))
    return family_workers(n, n)


def figure_instances(figures=FIGURES):
    """Each figure with its wildcards: once per fold when its stem holds the fold, else once."""
    return [
        (fig, {"fold": fold} if fold else {})
        for fig in figures
        for fold in (FOLDS if fig.per_fold else [None])
    ]


def figure_output(figure, wildcards):
    """A figure's files, filed in the Snakemake report when it has a category."""
    paths = figure_paths(figure, **wildcards)
    if figure.category is None:
        return paths
    return report(
        paths,
        caption="../report/figure.rst",
        category=CATEGORY[figure.category],
        **figure.report_fields(wildcards),
    )


def figure_files(figures=FIGURES):
    """Every file of ``figures``, a per-fold figure's for every fold, in table order."""
    return [
        path
        for fig, wildcards in figure_instances(figures)
        for path in figure_paths(fig, **wildcards)
    ]


def figure_tables(figures):
    """The tables a family reads, a per-fold figure's for every fold."""
    return sorted(
        {
            f"{OUT}/{path}".format(**wildcards)
            for fig, wildcards in figure_instances(figures)
            for path in fig.tables.values()
        }
    )


def figure_specs(figures):
    """What plot.py draws: per figure (and fold) its function, tables, arguments, files and caption."""
    specs = []
    for fig, wildcards in figure_instances(figures):
        spec = dict(
            stem=fig.stem.format(**wildcards),
            draw=fig.draw,
            tables={k: f"{OUT}/{v}".format(**wildcards) for k, v in fig.tables.items()},
            arguments={**fig.arguments, **wildcards},
            paths=figure_paths(fig, **wildcards),
            caption=registry.caption_of(fig, FACTS, wildcards),
        )
        if fig.reader:
            spec["reader"] = fig.reader
        specs.append(spec)
    return specs


def embedded(figure_id, **details):
    """A workflow figure for a report: the file to embed and its caption.

    ``details`` are the caption's; those the figure's stem names (fold, approach,
    algorithm) make the stem too.
    """
    stem = registry.stem_of(figure_id, **details)
    return {
        "path": f"{OUT}/figures/{stem}.{EMBED_FORMAT}",
        "caption": figure_caption(
            figure_id, DATASET.name, SIMULATED, twin=PAPER, **details
        ),
    }


# --------------------------------------------------------------------------- reports
# Snakemake report categories, numbered in this order.
CATEGORY = {
    key: f"{number}. {title}"
    for number, (key, title) in enumerate(
        [
            ("dataset", "Dataset"),
            ("data", "Errors and temperatures"),
            ("decoupling", "Decoupling"),
            ("sensitive_points", "Sensitive points"),
            ("models", "Models"),
            ("prediction", "Prediction"),
            ("compensation", "Compensation"),
            ("audit", "Audit against the paper"),
            ("reports", "Reports"),
        ],
        start=1,
    )
}
# A report notebook: papermill executes it in a python3 kernel that must start within
# 2 min, no cell may take over 10 min, and the same process writes its HTML
# (thermaxis.reports.notebooks). Parameters go on standard input: a record of many runs
# lists more files than a command line holds.
RUN_NOTEBOOK = (
    "python -m thermaxis.reports.notebooks run {input.notebook:q} {output.notebook:q} {output.html:q}"
    " --kernel python3 --start-timeout 120 --execution-timeout 600"
    " --title {params.title:q} --parameters - <<< {params.parameters:q} > {log:q} 2>&1"
)
# A report of one page per condition or fold: one kernel for every page, its namespace
# reset between them (thermaxis.reports.notebooks.execute_pages).
RUN_NOTEBOOK_PAGES = (
    "python -m thermaxis.reports.notebooks run-pages {input.notebook:q}"
    " --kernel python3 --start-timeout 120 --execution-timeout 600"
    " --pages - <<< {params.pages:q} > {log:q} 2>&1"
)
# One model report per fold shows these side by side, as the paper compares them.
REPORT_MODELS = [
    [approach, algorithm] for approach in APPROACHES for algorithm in REPORT_ALGORITHMS
]
# The paper predicts its last condition; a dataset without that run shows its last fold.
REPORT_FOLD = (
    config["paper_fold"] if PAPER and config["paper_fold"] in FOLDS else FOLDS[-1]
)
# The config sections the dataset's own reports depend on (a notebook hashes only those
# it is given, so changing selection.n_clusters leaves the dataset reports alone).
DATA_SECTIONS = ("dataset", "ambient_sensor", "temperatures", "errors", "decoupling")


@functools.cache
def git_of_checkout():
    """Commit and dirty flag, taken once per run and only by a job that records them."""
    return git_state(REPO)


def sections(*names):
    return {name: config[name] for name in names if name in config}


def notebook_parameters(input, sections_used, **values):
    """The notebook's parameters as JSON: every input but the notebook and the library, and ``values``."""
    inputs = {k: v for k, v in dict(input).items() if k not in ("notebook", "library")}
    return json.dumps(
        dict(
            dataset_name=DATASET.name,
            simulated=SIMULATED,
            statement=DATA_STATEMENT,
            dataset_root=config["dataset"],
            repo=REPO,
            config=sections_used,
            inputs=inputs,
            **values,
        ),
        sort_keys=True,
    )


# Many runs (config reports.combined_above_runs): one report of all conditions, a section
# per run, instead of a notebook per run.
COMBINED_CONDITIONS = len(RUNS) > SETTINGS.reports.combined_above_runs


def condition_reports():
    if COMBINED_CONDITIONS:
        return [f"{OUT}/reports/conditions.html"]
    return expand(f"{OUT}/reports/condition_{{run}}.html", run=RUNS)


def condition_links(run):
    """Where the index sends a run: its report, or its section of the combined one."""
    if COMBINED_CONDITIONS:
        return [("section", f"{OUT}/reports/conditions.html#run-{run}")]
    return [("condition report", f"{OUT}/reports/condition_{run}.html")]


def model_reports():
    return (
        expand(f"{OUT}/reports/model_{{fold}}.html", fold=FOLDS)
        if REPORT_MODELS
        else []
    )


def report_html():
    return [
        *([f"{OUT}/reports/paper_report.html"] if PAPER else []),
        f"{OUT}/reports/dataset_report.html",
        *condition_reports(),
        *model_reports(),
    ]


def report_outputs():
    return [f"{OUT}/provenance.json", f"{OUT}/index.html", *report_html()]


def linked_tables():
    """The tables the index links."""
    tables = [
        "dataset_summary.csv",
        "cleaning_qc.csv",
        *(["ambient_ranges.csv"] if AMBIENT else []),
        *(
            ["table5_slope_intercept.csv", "table5_slope_intercept.md"]
            if DECOUPLED
            else []
        ),
        "sensitive_points.csv",
        "metrics.csv",
        "coefficients.csv",
        "fitting.csv",
        "kb_predictions.csv",
        "error_predictions.csv",
        *(
            [
                "paper_comparison.csv",
                "paper_comparison.md",
                "faithfulness.csv",
                "faithfulness.md",
            ]
            if PAPER
            else []
        ),
    ]
    return [f"{OUT}/tables/{name}" for name in tables] + statistics_outputs()


# The figures and captions each report embeds, and what the index links.
def dataset_report_figures():
    figures = {"fig5_unzeroed": embedded("fig5_unzeroed", run=FIG_RUN)}
    if AMBIENT:
        figures["fig3_ambient"] = embedded("fig3_ambient")
    if OTHER_RUNS:
        figures["fig9_other_runs"] = embedded("fig9_other_runs", runs=OTHER_RUNS)
    if DECOUPLED:
        figures["fig12_slope_intercept"] = embedded("fig12_slope_intercept")
    return figures


def paper_report_figures():
    figures = {
        "fig2_positioning_error": embedded("fig2_positioning_error", run=FIG_RUN),
        **dataset_report_figures(),
        "fig6_error_vs_time": embedded("fig6_error_vs_time", run=FIG_RUN),
        "fig7_error_surface": embedded("fig7_error_surface", run=FIG_RUN),
        "fig8_rezeroed": embedded("fig8_rezeroed", run=FIG_RUN),
        "fig10_temperature_rise": embedded("fig10_temperature_rise", run=FIG_RUN),
        "fold_comparison": embedded("fold_comparison", target="error"),
    }
    for algorithm in PAPER_ALGORITHMS:
        kinds = [("error_prediction", a) for a in APPROACHES]
        kinds += [("kb_prediction", "decoupled")] if DECOUPLED else []
        for kind, approach in kinds:
            figure = embedded(
                kind, fold=REPORT_FOLD, approach=approach, algorithm=algorithm
            )
            figures[Path(figure["path"]).stem] = figure
    return figures


def condition_captions(run):
    """Captions of the figures a condition report draws for its run."""
    return {
        f: figure_caption(f, DATASET.name, SIMULATED, twin=PAPER, run=run)
        for f in (
            "fig5_unzeroed",
            "fig6_error_vs_time",
            "fig8_rezeroed",
            "fig10_temperature_rise",
        )
    }


def condition_report_inputs(run):
    """What the condition report of ``run`` reads, by the notebook's input names."""
    return dict(
        summary=f"{OUT}/tables/dataset_summary.csv",
        errors=f"{OUT}/clean/{run}/errors.parquet",
        temperatures=f"{OUT}/clean/{run}/measurement_temperatures.parquet",
        series=f"{OUT}/clean/{run}/temperatures.parquet",
        qc=f"{OUT}/clean/{run}/qc.csv",
        gaps=f"{OUT}/clean/{run}/gaps.csv",
        windows=f"{OUT}/clean/{run}/windows.csv",
        kb=[f"{OUT}/tables/table5_slope_intercept.csv"] if DECOUPLED else [],
    )


def model_report_inputs(fold):
    """What the model report of ``fold`` reads, by the notebook's input names."""
    return dict(
        selection=f"{OUT}/selection/{fold}.csv",
        selection_json=f"{OUT}/selection/{fold}.json",
        metrics=f"{OUT}/models/{fold}/metrics.csv",
        coefficients=f"{OUT}/models/{fold}/coefficients.csv",
        kb=f"{OUT}/models/{fold}/kb_predictions.csv",
        errors=f"{OUT}/models/{fold}/error_predictions.csv",
        fitting=f"{OUT}/models/{fold}/fitting.csv",
        compensation=[
            f"{OUT}/compensation/folds/{fold}/{n}.csv"
            for n in ("summary", "iso230_2", "siemens_840d", "twincat")
        ],
        fold_model=f"{OUT}/compensation/folds/{fold}/model.json",
        deployed=f"{OUT}/compensation/model.json",
        figures=[f["path"] for f in model_report_figures(fold).values()],
    )


def page_files(inputs_of, keys):
    """Every file the pages of ``keys`` read (a page's inputs are files or lists of them)."""
    return sorted(
        {
            path
            for key in keys
            for value in inputs_of(key).values()
            for path in (value if isinstance(value, list) else [value])
        }
    )


def report_pages(kind, keys, inputs_of, title, sections_used, **values_of):
    """The JSON of a page-per-key report (RUN_NOTEBOOK_PAGES): per key its files, title
    and parameters; ``values_of`` maps a parameter to its value or a function of the key.
    """
    return json.dumps(
        [
            dict(
                executed=f"{OUT}/reports/{kind}_{key}.ipynb",
                html=f"{OUT}/reports/{kind}_{key}.html",
                title=title(key),
                parameters=json.loads(
                    notebook_parameters(
                        inputs_of(key),
                        sections_used,
                        **{
                            name: value(key) if callable(value) else value
                            for name, value in values_of.items()
                        },
                    )
                ),
            )
            for key in keys
        ],
        sort_keys=True,
    )


def model_report_figures(fold):
    """The workflow figures a model report embeds: its models' predictions and the drift."""
    figures = {}
    for approach, algorithm in REPORT_MODELS:
        kinds = ["error_prediction"]
        if approach == "decoupled":
            kinds.append("kb_prediction")
        for kind in kinds:
            figures[f"{kind}_{approach}_{algorithm}"] = embedded(
                kind, fold=fold, approach=approach, algorithm=algorithm
            )
    figures["compensation_drift"] = embedded("compensation_drift", fold=fold)
    return figures


def index_sections():
    """What the index links, in order: (title, intro, rows of (label, [(text, path)]))."""
    reports = []
    if PAPER:
        reports.append(
            (
                "The paper, figure by figure and table by table",
                [("paper report", f"{OUT}/reports/paper_report.html")],
            )
        )
    reports.append(
        (
            "Dataset: runs, sensors, cleaning",
            [("dataset report", f"{OUT}/reports/dataset_report.html")],
        )
    )
    if COMBINED_CONDITIONS:
        reports.append(
            (
                f"All {len(RUNS)} runs",
                [("conditions report", f"{OUT}/reports/conditions.html")],
            )
        )
    reports += [(f"Run {run}", condition_links(run)) for run in RUNS]
    models = [
        (f"Fold {fold} (held-out run)", [("model report", path)])
        for fold, path in zip(FOLDS, model_reports())
    ]
    tables = [(Path(p).name, [(Path(p).suffix[1:], p)]) for p in linked_tables()]
    compensation = {}
    for p in compensation_outputs():
        compensation.setdefault(Path(p).stem, []).append((Path(p).suffix[1:], p))
    answer = [
        (
            "recommendation",
            [
                ("csv", f"{OUT}/tables/recommendation.csv"),
                ("md", f"{OUT}/tables/recommendation.md"),
            ],
        ),
        ("candidates", [("csv", f"{OUT}/recommend/candidates.csv")]),
        (
            "deployed model and its verdict",
            [("json", f"{OUT}/compensation/model.json")],
        ),
    ]
    return [
        # Its intro, the answer in words, is written by the index job from these files.
        ("Which model to deploy", "", answer),
        ("Reports", "", reports),
        (
            "Model reports",
            "Metrics, sensitive points, coefficients, predictions and compensation of one fold, "
            f"every approach with each algorithm of config `reports.model_algorithms` "
            f"({', '.join(REPORT_ALGORITHMS)}) side by side.",
            models,
        ),
        ("All tables", "", tables),
        (
            "Compensation",
            f"The deployed model (config compensation.model: {SETTINGS.compensation.model}) fitted on all "
            "runs (model.json), the controller "
            "exports of each fold's model on its held-out run and the error left after compensating; "
            "the thermal-drift figures are under Figures (README: Compensating a machine).",
            list(compensation.items()),
        ),
    ]


def index_figures():
    """The index's thumbnails by stage: (stage, [(stem, caption, thumbnail, [(ext, path)])])."""
    groups = {}
    for fig, wildcards in figure_instances():
        paths = figure_paths(fig, **wildcards)
        thumbnail = next((p for p in paths if p.endswith((".png", ".svg"))), None)
        groups.setdefault(fig.category, []).append(
            (
                fig.stem.format(**wildcards),
                registry.caption_of(fig, FACTS, wildcards) or "",
                thumbnail,
                [(Path(p).suffix[1:], p) for p in paths],
            )
        )
    order = list(CATEGORY)
    return [
        (CATEGORY[key].split(". ", 1)[1], figures)
        for key, figures in sorted(groups.items(), key=lambda kv: order.index(kv[0]))
    ]


# The tables the index shows in the page (title, file, note); the others are linked.
INDEX_TABLES = [
    ("Runs", f"{OUT}/tables/dataset_summary.csv", ""),
    (
        "Cleaning events: excursions, unusable and flat sensors, merged timestamps, displacement findings",
        f"{OUT}/tables/cleaning_events.csv",
        "docs/your-data.md",
    ),
    (
        "Held-out error per fold, approach, algorithm and target",
        f"{OUT}/tables/metrics.csv",
        "",
    ),
    (
        "Recommendation per held-out run",
        f"{OUT}/tables/recommendation.csv",
        "docs/recommendation.md",
    ),
    (
        "Compensation: each held-out run before and after compensating",
        f"{OUT}/compensation/summary.csv",
        "",
    ),
    ("Sensitive points per fold", f"{OUT}/tables/sensitive_points.csv", ""),
    *(
        [
            (
                "Faithfulness: every calibration target, published against reproduced",
                f"{OUT}/tables/faithfulness.csv",
                "docs/datasets.md",
            )
        ]
        if PAPER
        else []
    ),
]


def index_inputs():
    linked = {
        path.split("#", 1)[0]
        for _, _, rows in index_sections()
        for _, links in rows
        for _, path in links
    }
    drawn = {
        path
        for _, figures in index_figures()
        for *_, links in figures
        for _, path in links
    }
    return sorted(linked | drawn | {path for _, path, _ in INDEX_TABLES})


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


def compensation_outputs():
    """model.json, the ST block and the tables; the drift figures are figures."""
    paths = [
        f"{OUT}/compensation/model.json",
        f"{OUT}/compensation/ThermalCompensation.st",
    ]
    return paths + [f"{OUT}/compensation/{name}.csv" for name in COMP_TABLES]


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


def recommendation_outputs():
    return [
        f"{OUT}/tables/recommendation.csv",
        f"{OUT}/tables/recommendation.md",
        f"{OUT}/recommend/candidates.csv",
        f"{OUT}/recommend/choice.json",
    ]


# --------------------------------------------------------------------------- statistics
# The uncertainty of every comparison (thermaxis.statistics, docs/statistics.md):
# comparisons.csv, the paper's claims and the stability of the sensitive points.
def audit_tables():
    """What the statistics job writes for a dataset that reproduces the paper: the paper's
    published values beside the reproduced ones, and the faithfulness of the twin."""
    if not PAPER:
        return {}
    return dict(
        paper_csv=report(
            f"{OUT}/tables/paper_comparison.csv",
            caption="../report/paper_comparison.rst",
            category=CATEGORY["audit"],
            labels={"table": "paper comparison"},
        ),
        paper_markdown=f"{OUT}/tables/paper_comparison.md",
        faithfulness=report(
            f"{OUT}/tables/faithfulness.csv",
            caption="../report/faithfulness.rst",
            category=CATEGORY["audit"],
            labels={"table": "faithfulness"},
        ),
        faithfulness_markdown=f"{OUT}/tables/faithfulness.md",
    )


def statistics_outputs():
    return [
        f"{OUT}/tables/comparisons.csv",
        f"{OUT}/tables/claims.csv",
        f"{OUT}/tables/claims.md",
        f"{OUT}/tables/selection_stability.csv",
    ]


# --------------------------------------------------------------------------- sweep
# The sweep (`make sweep`, i.e. `snakemake sweep`): every configuration of config `sweep`
# on every leave-one-condition-out fold; not part of `rule all`. Batches, not one job per
# configuration: each batch is one process that reads the assembled tables once and
# evaluates its share of the grid with the function the main workflow uses
# (thermaxis.method.folds.evaluate_configuration). The batch count is part of the batch
# files' path, so runs with other counts do not mix shares of two plans.
#
# The executor is chosen after the Snakefile is parsed; what is known then is that a
# cluster run is given --jobs (a profile's `jobs:`; locally --jobs means --cores), and
# that a job the cluster runs parses the workflow again in remote mode: it must find
# the same plan (preflight.sweep_plan).
SWEEP_ON_CLUSTER = workflow.remote_exec or workflow.resource_settings.nodes is not None
SWEEP_EMBED = next((f for f in ("png", "svg") if f in FIG_FORMATS), None)


@functools.cache
def sweep_plan():
    """The sweep's units and batches, planned the first time a sweep job asks for them."""
    with preflight.one_line():
        return preflight.sweep_plan(
            CHECKED, workflow.resource_settings.cores, SWEEP_ON_CLUSTER
        )


def sweep_batch_files(wildcards):
    n = sweep_plan().batches
    return expand(f"{OUT}/sweep/batches/{n}/{{batch}}.parquet", batch=range(n))


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
    """papermill parameters of the sweep report: the grid, the plan's notes, the inputs."""
    return json.dumps(
        dict(
            dataset_name=DATASET.name,
            simulated=SIMULATED,
            statement=DATA_STATEMENT,
            figures={
                fig.id: (
                    f"{OUT}/{fig.folder}/{fig.stem}.{SWEEP_EMBED}"
                    if SWEEP_EMBED
                    else ""
                )
                for fig in SWEEP_FIGURES
            },
            grid=config["sweep"],
            folds=CHECKED.sweep_folds,
            skipped=sweep_plan().skipped,
            selection=config["selection"],
            degree=config["decoupling"]["degree"],
            summary=input.summary,
            ranking=input.ranking,
            effects=input.effects,
            benchmarks=list(input.benchmarks),
        ),
        sort_keys=True,
    )


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
# Memory (MB) and runtime (minutes) of a rule's first attempt; a retry (--retries) asks
# for attempt x both. Rules not listed get the floors of the requests that
# `python -m thermaxis.pipeline.resources benchmarks/<dataset>` derives from a run's
# benchmarks; the sweep's batches get a runtime from their share of the grid.
RESOURCES = {
    "default": (MIN_MEMORY_MB, MIN_RUNTIME_MIN),
    **{
        name: (750, MIN_RUNTIME_MIN)
        for name in (
            "dataset_report",
            "condition_report",
            "conditions_report",
            "model_report",
            "paper_report",
            "sweep_report",
        )
    },
    "compensation": (1000, MIN_RUNTIME_MIN),
    # Every run in one job, two workers at most locally: 0.49 GB peak at 43 and 86 runs
    # (benchmarks of the scale bench), about 0.3 s a run.
    "clean": (1000, max(MIN_RUNTIME_MIN, len(RUNS) // 20)),
    # Every candidate on every inner split of every fold: the heaviest job of a run.
    "recommend": (1000, max(30, 10 * len(FOLDS))),
    "sweep_batch": (MIN_MEMORY_MB, sweep_batch_minutes),
}


def rule_resources(name):
    """The ``resources:`` of rule ``name`` (RESOURCES)."""
    return per_attempt(*RESOURCES.get(name, RESOURCES["default"]))


# --------------------------------------------------------------------------- priorities
# Of the jobs ready at once, Snakemake starts the set with the largest sum of priorities
# that fits the cores. A rule ranks by the longest chain of work from its start to the end
# of the run, in the jobs' times of the twin and fl_thermal (benchmarks/): the fits feed
# every later stage; the prediction figures, the largest job, feed the model pages; the
# compensation feeds the results figures and three reports. Left to its ties, Snakemake
# gave the core the prediction figures waited for to a report that only the index needs.
# The recommendation's chain is the longest and grows fastest with the runs: above any
# two other priorities together, it never waits for both cores behind two one-core jobs,
# as it did for 49 s on a 12-run record (docs/performance.md).
PRIORITY = {
    "recommend": 20,
    "models": 9,
    "fig_predictions": 8,
    "compensation": 7,
    "statistics": 6,
    "fig_results": 5,
    "fig_data": 4,
    "condition_report": 4,
    "conditions_report": 4,
    "model_report": 3,
    "paper_report": 2,
    "dataset_report": 1,
}


def rule_priority(name):
    """The ``priority:`` of rule ``name`` (PRIORITY; 0 for a rule not listed)."""
    return PRIORITY.get(name, 0)


# --------------------------------------------------------------------------- targets
def all_outputs():
    return [
        *figure_files(FIGURES),
        f"{OUT}/tables/dataset_summary.csv",
        f"{OUT}/assembled/errors.parquet",
        f"{OUT}/tables/cleaning_qc.csv",
        f"{OUT}/tables/metrics.csv",
        *([f"{OUT}/tables/paper_comparison.csv"] if PAPER else []),
        *([f"{OUT}/tables/table5_slope_intercept.csv"] if DECOUPLED else []),
        *recommendation_outputs(),
        *statistics_outputs(),
        *compensation_outputs(),
        *report_outputs(),
    ]


def check_rules(rules):
    """The last parse-time check, once every rule is defined (preflight.check_rules)."""
    with preflight.one_line():
        preflight.check_rules(rules, CHECKED)
