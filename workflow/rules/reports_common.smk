# Reports: parametrised notebooks executed by papermill and turned into self-contained
# HTML, the dataset's provenance record and an index page. The notebooks only read
# tables the workflow wrote; they recompute nothing.
#
# Provenance and reruns: provenance.json (the whole configuration, the raw-data
# manifest, the git commit and dirty flag, versions, run time) is rewritten when the
# raw files, the configuration or the git state change, and only the index reads it.
# Each notebook records its own provenance when it runs, hashing only the
# configuration sections its inputs depend on, so changing selection.n_clusters
# reruns the model and paper reports but leaves the dataset and condition reports
# alone. The run time is the only field that differs between two builds from the
# same inputs; SOURCE_DATE_EPOCH fixes it.
import json

from thermaxis.reports.provenance import git_state

REPORTS = f"{OUT}/reports"
# One model report per fold shows these side by side, as the paper compares them.
REPORT_MODELS = [
    [approach, algorithm] for approach in APPROACHES for algorithm in REPORT_ALGORITHMS
]
# A path inside the repository, relative so the executed notebooks do not depend on
# where the work folder is; git follows the symlinks of a test work folder.
REPO = os.path.relpath(str(workflow.current_basedir))
GIT_STATE = git_state(str(workflow.current_basedir))
EMBED_FORMAT = next((f for f in ("png", "svg") if f in FIG_FORMATS), FIG_FORMATS[0])
# The paper predicts its last condition; a dataset without that run shows its last fold.
REPORT_FOLD = (
    config["paper_fold"] if PAPER and config["paper_fold"] in FOLDS else FOLDS[-1]
)
PAPER_ALGORITHMS = [a for a in ("mlr", "svr") if a in FIG_ALGORITHMS]
# papermill executes each notebook in a python3 kernel that must start within 2 min;
# no cell may take over 10 min. One process runs papermill and the HTML conversion
# (src/thermaxis/reporting.py says why).
RUN_NOTEBOOK = (
    "python -m thermaxis.reports.notebooks run {input.notebook:q} {output.notebook:q} {output.html:q}"
    " --kernel python3 --start-timeout 120 --execution-timeout 600"
    " --title {params.title:q} --parameters {params.parameters:q} > {log:q} 2>&1"
)
DATA_SECTIONS = ("dataset", "ambient_sensor", "temperatures", "errors", "decoupling")


def dataset_files():
    """Every file of the dataset but its two sheets: what provenance.json hashes."""
    sheets = set(dataset_sheets())
    files = (str(p) for p in DATASET.root.rglob("*") if p.is_file())
    return sorted(f for f in files if f not in sheets)


def sections(*names):
    return {name: config[name] for name in names if name in config}


def notebook_parameters(input, sections_used, **values):
    """The notebook's parameters as JSON: every input but the notebook and the library, and ``values``."""
    inputs = {k: v for k, v in input.items() if k not in ("notebook", "library")}
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


def embedded(stem, figure_id, **details):
    """A workflow figure for a report: the file to embed and its caption."""
    return {
        "path": f"{OUT}/figures/{stem}.{EMBED_FORMAT}",
        "caption": figure_caption(figure_id, DATASET.name, SIMULATED, **details),
    }


def embedded_prediction(kind, fold, approach, algorithm):
    """A prediction figure of the workflow for a report (Figs. 11/14-17)."""
    return {
        "path": f"{OUT}/figures/{kind}_{fold}_{approach}_{algorithm}.{EMBED_FORMAT}",
        "caption": prediction_caption(kind, fold, approach, algorithm),
    }


def dataset_report_figures():
    figures = {"fig5_unzeroed": embedded("fig5_unzeroed", "fig5", run=FIG_RUN)}
    if AMBIENT:
        figures["fig3_ambient"] = embedded("fig3_ambient", "fig3")
    if OTHER_RUNS:
        figures["fig9_other_runs"] = embedded(
            "fig9_other_runs", "fig9", runs=OTHER_RUNS
        )
    if DECOUPLED:
        figures["fig12_slope_intercept"] = embedded("fig12_slope_intercept", "fig12")
    return figures


def paper_report_figures():
    figures = {
        "fig2_positioning_error": embedded(
            "fig2_positioning_error", "fig2", run=FIG_RUN
        ),
        **dataset_report_figures(),
        "fig6_error_vs_time": embedded("fig6_error_vs_time", "fig6", run=FIG_RUN),
        "fig7_error_surface": embedded("fig7_error_surface", "fig7", run=FIG_RUN),
        "fig8_rezeroed": embedded("fig8_rezeroed", "fig8", run=FIG_RUN),
        "fig10_temperature_rise": embedded(
            "fig10_temperature_rise", "fig10", run=FIG_RUN
        ),
        "fold_comparison": embedded(
            "fold_comparison", "fold_comparison", target="error"
        ),
    }
    for algorithm in PAPER_ALGORITHMS:
        for approach in APPROACHES:
            stem = f"error_prediction_{REPORT_FOLD}_{approach}_{algorithm}"
            figures[stem] = embedded_prediction(
                "error_prediction", REPORT_FOLD, approach, algorithm
            )
        if DECOUPLED:
            stem = f"kb_prediction_{REPORT_FOLD}_decoupled_{algorithm}"
            figures[stem] = embedded_prediction(
                "kb_prediction", REPORT_FOLD, "decoupled", algorithm
            )
    return figures


def condition_captions(wildcards):
    """Captions of the figures a condition report draws for its run."""
    return {
        f: figure_caption(f, DATASET.name, SIMULATED, run=wildcards.run)
        for f in ("fig5", "fig6", "fig8", "fig10")
    }


def condition_reports():
    return expand(f"{REPORTS}/condition_{{run}}.html", run=RUNS)


def model_reports():
    return expand(f"{REPORTS}/model_{{fold}}.html", fold=FOLDS) if REPORT_MODELS else []


def model_report_figures(fold):
    """The workflow figures a model report embeds: its models' predictions and the drift."""
    figures = {}
    for approach, algorithm in REPORT_MODELS:
        kinds = ["error_prediction"] + ["kb_prediction"] * (approach == "decoupled")
        for kind in kinds:
            figures[f"{kind}_{approach}_{algorithm}"] = embedded_prediction(
                kind, fold, approach, algorithm
            )
    figures["compensation_drift"] = embedded(
        f"compensation_drift_{fold}", "compensation_drift", fold=fold
    )
    return figures


def report_html():
    return [
        *([f"{REPORTS}/paper_report.html"] if PAPER else []),
        f"{REPORTS}/dataset_report.html",
        *condition_reports(),
        *model_reports(),
    ]


def linked_tables():
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
        "kb_predictions.csv",
        "error_predictions.csv",
        *(["paper_comparison.csv", "paper_comparison.md"] if PAPER else []),
    ]
    return [f"{OUT}/tables/{name}" for name in tables]


def index_sections():
    """What the index links, in order: (title, intro, rows of (label, [(text, path)]))."""
    reports = [
        (
            "The paper, figure by figure and table by table",
            [("paper report", f"{REPORTS}/paper_report.html")],
        )
    ] * PAPER + [
        (
            "Dataset: runs, sensors, cleaning",
            [("dataset report", f"{REPORTS}/dataset_report.html")],
        ),
    ]
    reports += [
        (f"Run {run}", [("condition report", f"{REPORTS}/condition_{run}.html")])
        for run in RUNS
    ]
    models = [
        (f"Fold {fold} (held-out run)", [("model report", path)])
        for fold, path in zip(FOLDS, model_reports())
    ]
    stems = figure_stems()
    figures = [
        (stem, [(ext, f"{OUT}/figures/{stem}.{ext}") for ext in FIG_FORMATS])
        for stem in stems
    ]
    tables = [(Path(p).name, [(Path(p).suffix[1:], p)]) for p in linked_tables()]
    compensation = {}
    for p in compensation_outputs():
        compensation.setdefault(Path(p).stem, []).append((Path(p).suffix[1:], p))
    return [
        ("Reports", "", reports),
        (
            "Model reports",
            "Metrics, sensitive points, coefficients, predictions and compensation of one fold, "
            f"every approach with each algorithm of config `reports.model_algorithms` "
            f"({', '.join(REPORT_ALGORITHMS)}) side by side.",
            models,
        ),
        ("Figures", "", figures),
        ("Tables", "", tables),
        (
            "Compensation",
            f"The {COMP_APPROACH} {COMP_ALGORITHM} model fitted on all runs (model.json), the controller "
            "exports of each fold's model on its held-out run and the error left after compensating; "
            "the thermal-drift figures are under Figures (README: Compensating a machine).",
            list(compensation.items()),
        ),
    ]


def index_inputs():
    return sorted(
        {
            path
            for _, _, rows in index_sections()
            for _, links in rows
            for _, path in links
        }
    )


def report_outputs():
    return [f"{OUT}/provenance.json", f"{OUT}/index.html", *report_html()]
