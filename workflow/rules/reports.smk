# Reports: parametrised notebooks executed by papermill and turned into self-contained
# HTML (RUN_NOTEBOOK), the dataset's provenance record and the index page. The notebooks
# only read tables the workflow wrote; they recompute nothing.
#
# Provenance and reruns: provenance.json (the whole configuration, the raw-data
# manifest, the git commit and dirty flag, versions, run time) is rewritten when the
# raw files, the configuration or the git state change, and only the index reads it.
# Each notebook records its own provenance when it runs, hashing only the
# configuration sections its inputs depend on, so changing selection.n_clusters
# reruns the model and paper reports but leaves the dataset and condition reports
# alone. The run time is the only field that differs between two builds from the
# same inputs; SOURCE_DATE_EPOCH fixes it.


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


def condition_captions(wildcards):
    """Captions of the figures a condition report draws for its run."""
    return {
        f: figure_caption(f, DATASET.name, SIMULATED, run=wildcards.run)
        for f in (
            "fig5_unzeroed",
            "fig6_error_vs_time",
            "fig8_rezeroed",
            "fig10_temperature_rise",
        )
    }


def model_report_figures(fold):
    """The workflow figures a model report embeds: its models' predictions and the drift."""
    figures = {}
    for approach, algorithm in REPORT_MODELS:
        kinds = ["error_prediction"] + ["kb_prediction"] * (approach == "decoupled")
        for kind in kinds:
            figures[f"{kind}_{approach}_{algorithm}"] = embedded(
                kind, fold=fold, approach=approach, algorithm=algorithm
            )
    figures["compensation_drift"] = embedded("compensation_drift", fold=fold)
    return figures


def index_sections():
    """What the index links, in order: (title, intro, rows of (label, [(text, path)]))."""
    reports = [
        (
            "The paper, figure by figure and table by table",
            [("paper report", f"{OUT}/reports/paper_report.html")],
        )
    ] * PAPER + [
        (
            "Dataset: runs, sensors, cleaning",
            [("dataset report", f"{OUT}/reports/dataset_report.html")],
        ),
    ]
    reports += [
        (f"Run {run}", [("condition report", f"{OUT}/reports/condition_{run}.html")])
        for run in RUNS
    ]
    models = [
        (f"Fold {fold} (held-out run)", [("model report", path)])
        for fold, path in zip(FOLDS, model_reports())
    ]
    figures = [
        (stem, [(ext, f"{OUT}/figures/{stem}.{ext}") for ext in FIG_FORMATS])
        for stem in figure_stems()
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


rule provenance:
    input:
        code=code_of("provenance.py"),
        sheets=dataset_sheets(),
        data=dataset_files(),
    output:
        f"{OUT}/provenance.json",
    log:
        f"{LOGS}/provenance.log",
    benchmark:
        f"{BENCH}/provenance.tsv"
    conda:
        ENV
    resources:
        **rule_resources("provenance"),
    params:
        config_json=json.dumps(config, sort_keys=True),
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        repo=REPO,
        git=lambda w: git_of_checkout(),
    script:
        "../scripts/provenance.py"


rule dataset_report:
    input:
        notebook="notebooks/dataset_report.ipynb",
        library=code_of("notebooks/dataset_report.ipynb"),
        sheets=dataset_sheets(),
        summary=f"{OUT}/tables/dataset_summary.csv",
        qc=f"{OUT}/tables/cleaning_qc.csv",
        gaps=expand(f"{OUT}/clean/{{run}}/gaps.csv", run=RUNS),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        figures=[f["path"] for f in dataset_report_figures().values()],
    output:
        notebook=f"{OUT}/reports/dataset_report.ipynb",
        html=report(
            f"{OUT}/reports/dataset_report.html",
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            labels={"report": "dataset"},
        ),
    log:
        f"{LOGS}/reports/dataset_report.log",
    benchmark:
        f"{BENCH}/reports/dataset_report.tsv"
    conda:
        ENV
    resources:
        **rule_resources("dataset_report"),
    params:
        title=f"Dataset report: {DATASET.name}",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: notebook_parameters(
            input,
            sections(*DATA_SECTIONS, "figures"),
            figures=dataset_report_figures(),
        ),
    shell:
        RUN_NOTEBOOK


rule condition_report:
    input:
        notebook="notebooks/condition_report.ipynb",
        library=code_of("notebooks/condition_report.ipynb"),
        summary=f"{OUT}/tables/dataset_summary.csv",
        errors=f"{OUT}/clean/{{run}}/errors.parquet",
        temperatures=f"{OUT}/clean/{{run}}/measurement_temperatures.parquet",
        series=f"{OUT}/clean/{{run}}/temperatures.parquet",
        qc=f"{OUT}/clean/{{run}}/qc.csv",
        gaps=f"{OUT}/clean/{{run}}/gaps.csv",
        windows=f"{OUT}/clean/{{run}}/windows.csv",
        kb=[f"{OUT}/tables/table5_slope_intercept.csv"] if DECOUPLED else [],
    output:
        notebook=f"{OUT}/reports/condition_{{run}}.ipynb",
        html=report(
            f"{OUT}/reports/condition_{{run}}.html",
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            subcategory="Conditions",
            labels={"report": "condition", "run": "{run}"},
        ),
    log:
        f"{LOGS}/reports/condition_{{run}}.log",
    benchmark:
        f"{BENCH}/reports/condition_{{run}}.tsv"
    conda:
        ENV
    resources:
        **rule_resources("condition_report"),
    params:
        title=lambda w: f"Condition report: run {w.run} ({DATASET.name})",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: notebook_parameters(
            input,
            sections(*DATA_SECTIONS),
            run=w.run,
            captions=condition_captions(w),
        ),
    shell:
        RUN_NOTEBOOK


rule model_report:
    input:
        notebook="notebooks/model_report.ipynb",
        library=code_of("notebooks/model_report.ipynb"),
        selection=f"{OUT}/selection/{{fold}}.csv",
        selection_json=f"{OUT}/selection/{{fold}}.json",
        metrics=f"{OUT}/models/{{fold}}/metrics.csv",
        coefficients=f"{OUT}/models/{{fold}}/coefficients.csv",
        kb=f"{OUT}/models/{{fold}}/kb_predictions.csv",
        errors=f"{OUT}/models/{{fold}}/error_predictions.csv",
        compensation=lambda w: [
            f"{OUT}/compensation/folds/{w.fold}/{n}.csv"
            for n in ("summary", "iso230_2", "siemens_840d", "twincat")
        ],
        figures=lambda w: [f["path"] for f in model_report_figures(w.fold).values()],
    output:
        notebook=f"{OUT}/reports/model_{{fold}}.ipynb",
        html=report(
            f"{OUT}/reports/model_{{fold}}.html",
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            subcategory="Models",
            labels={"report": "model", "fold": "{fold}"},
        ),
    log:
        f"{LOGS}/reports/model_{{fold}}.log",
    benchmark:
        f"{BENCH}/reports/model_{{fold}}.tsv"
    conda:
        ENV
    resources:
        **rule_resources("model_report"),
    params:
        title=lambda w: f"Model report: fold {w.fold} ({DATASET.name})",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: notebook_parameters(
            input,
            sections(
                *DATA_SECTIONS,
                "selection",
                "models",
                "folds",
                "compensation",
                "figures",
            ),
            fold=w.fold,
            models=REPORT_MODELS,
            runs=RUNS,
            figures=model_report_figures(w.fold),
        ),
    shell:
        RUN_NOTEBOOK


rule paper_report:
    input:
        notebook="notebooks/paper_report.ipynb",
        library=code_of("notebooks/paper_report.ipynb"),
        sheets=dataset_sheets(),
        summary=f"{OUT}/tables/dataset_summary.csv",
        ambient=f"{OUT}/tables/ambient_ranges.csv",
        kb=[f"{OUT}/tables/table5_slope_intercept.csv"] if DECOUPLED else [],
        metrics=f"{OUT}/tables/metrics.csv",
        coefficients=f"{OUT}/tables/coefficients.csv",
        sensitive_points=f"{OUT}/tables/sensitive_points.csv",
        comparison=f"{OUT}/tables/paper_comparison.csv",
        paper=PAPER_FILES,
        figures=[f["path"] for f in paper_report_figures().values()],
    output:
        notebook=f"{OUT}/reports/paper_report.ipynb",
        html=report(
            f"{OUT}/reports/paper_report.html",
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            labels={"report": "paper"},
        ),
    log:
        f"{LOGS}/reports/paper_report.log",
    benchmark:
        f"{BENCH}/reports/paper_report.tsv"
    conda:
        ENV
    resources:
        **rule_resources("paper_report"),
    params:
        title=f"Paper report: Xu et al. reproduced on {DATASET.name}",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: notebook_parameters(
            input,
            {k: v for k, v in config.items() if k not in ("reports", "sweep")},
            paper_fold=config["paper_fold"],
            fold=REPORT_FOLD,
            algorithms=PAPER_ALGORITHMS,
            approaches=APPROACHES,
            paper_dir=PAPER_DIR,
            figures=paper_report_figures(),
        ),
    shell:
        RUN_NOTEBOOK


rule index:
    input:
        code=code_of("index.py"),
        provenance=f"{OUT}/provenance.json",
        linked=index_inputs(),
    output:
        f"{OUT}/index.html",
    log:
        f"{LOGS}/index.log",
    benchmark:
        f"{BENCH}/index.tsv"
    conda:
        ENV
    resources:
        **rule_resources("index"),
    params:
        dataset_name=DATASET.name,
        simulated=SIMULATED,
        statement=DATA_STATEMENT,
        sections=index_sections(),
        sweep=f"{OUT}/sweep/sweep_report.html",
        headline=HEADLINE,
    script:
        "../scripts/index.py"
