# Reports: parametrised notebooks executed by papermill and turned into self-contained
# HTML (thermaxis.reports.pages.RUN_NOTEBOOK), the dataset's provenance record and the index page. The notebooks
# only read tables the workflow wrote; they recompute nothing.
#
# Provenance and reruns: provenance.json (the whole configuration, the raw-data
# manifest, the git commit and dirty flag, versions, run time) is written with the index,
# the one page that shows it, whenever the raw files, the configuration or the git state
# change.
# Each notebook records its own provenance when it runs, hashing only the
# configuration sections its inputs depend on, so changing selection.n_clusters
# reruns the model and paper reports but leaves the dataset and condition reports
# alone. The run time is the only field that differs between two builds from the
# same inputs; SOURCE_DATE_EPOCH fixes it.


rule dataset_report:
    input:
        notebook="notebooks/dataset_report.ipynb",
        library=code_of("notebooks/dataset_report.ipynb"),
        sheets=dataset_sheets(),
        summary=out(paths.DATASET_SUMMARY),
        qc=out(paths.CLEANING_QC),
        gaps=expand(out(paths.CLEAN_GAPS), run=RUNS),
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
        recommendation=out(paths.RECOMMENDATION),
        model=out(paths.DEPLOYED_MODEL),
        figures=[f["path"] for f in PAGES.dataset_report_figures().values()],
    output:
        notebook=out(paths.DATASET_REPORT, ext="ipynb"),
        html=report(
            out(paths.DATASET_REPORT, ext="html"),
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            labels={"report": "dataset"},
        ),
    log:
        f"{LOGS}/reports/dataset_report.log",
    benchmark:
        f"{BENCH}/reports/dataset_report.tsv"
    priority: rule_priority("dataset_report")
    conda:
        ENV
    resources:
        **rule_resources("dataset_report"),
    params:
        title=f"Dataset report: {DATASET.name}",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: PAGES.notebook_parameters(
            input,
            PAGES.sections(*pages.DATA_SECTIONS, "figures"),
            figures=PAGES.dataset_report_figures(),
        ),
    shell:
        pages.RUN_NOTEBOOK


rule condition_report:
    input:
        notebook="notebooks/condition_report.ipynb",
        library=code_of("notebooks/condition_report.ipynb"),
        pages=pages.page_files(PAGES.condition_report_inputs, RUNS),
    output:
        notebooks=expand(out(paths.CONDITION_REPORT), run=RUNS, ext="ipynb"),
        html=[
            report(
                out(paths.CONDITION_REPORT, run=run, ext="html"),
                caption="../report/notebook_report.rst",
                category=CATEGORY["reports"],
                subcategory="Conditions",
                labels={"report": "condition", "run": run},
            )
            for run in RUNS
        ],
    log:
        f"{LOGS}/reports/condition_report.log",
    benchmark:
        f"{BENCH}/reports/condition_report.tsv"
    priority: rule_priority("condition_report")
    conda:
        ENV
    resources:
        **rule_resources("condition_report"),
    params:
        pages=PAGES.report_pages(
            paths.CONDITION_REPORT,
            RUNS,
            PAGES.condition_report_inputs,
            lambda run: f"Condition report: run {run} ({DATASET.name})",
            PAGES.sections(*pages.DATA_SECTIONS),
            run=lambda run: run,
            captions=PAGES.condition_captions,
            stamp=PAGES.stamp,
        ),
    shell:
        pages.RUN_NOTEBOOK_PAGES


rule conditions_report:
    input:
        notebook="notebooks/conditions_report.ipynb",
        library=code_of("notebooks/conditions_report.ipynb"),
        summary=out(paths.DATASET_SUMMARY),
        errors=out(paths.ASSEMBLED_ERRORS),
        temperatures=out(paths.ASSEMBLED_TEMPERATURES),
    output:
        notebook=out(paths.CONDITIONS_REPORT, ext="ipynb"),
        html=report(
            out(paths.CONDITIONS_REPORT, ext="html"),
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            subcategory="Conditions",
            labels={"report": "conditions", "run": "all"},
        ),
    log:
        f"{LOGS}/reports/conditions.log",
    benchmark:
        f"{BENCH}/reports/conditions.tsv"
    priority: rule_priority("conditions_report")
    conda:
        ENV
    resources:
        **rule_resources("conditions_report"),
    params:
        title=f"Conditions report: all runs ({DATASET.name})",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: PAGES.notebook_parameters(
            input, PAGES.sections(*pages.DATA_SECTIONS), runs=RUNS, stamp=PAGES.stamp
        ),
    shell:
        pages.RUN_NOTEBOOK


rule model_report:
    input:
        notebook="notebooks/model_report.ipynb",
        library=code_of("notebooks/model_report.ipynb"),
        pages=pages.page_files(PAGES.model_report_inputs, FOLDS),
    output:
        notebooks=expand(out(paths.MODEL_REPORT), fold=FOLDS, ext="ipynb"),
        html=[
            report(
                out(paths.MODEL_REPORT, fold=fold, ext="html"),
                caption="../report/notebook_report.rst",
                category=CATEGORY["reports"],
                subcategory="Models",
                labels={"report": "model", "fold": fold},
            )
            for fold in FOLDS
        ],
    log:
        f"{LOGS}/reports/model_report.log",
    benchmark:
        f"{BENCH}/reports/model_report.tsv"
    priority: rule_priority("model_report")
    conda:
        ENV
    resources:
        **rule_resources("model_report"),
    params:
        pages=PAGES.report_pages(
            paths.MODEL_REPORT,
            FOLDS,
            PAGES.model_report_inputs,
            lambda fold: f"Model report: fold {fold} ({DATASET.name})",
            PAGES.sections(
                *pages.DATA_SECTIONS,
                "selection",
                "models",
                "folds",
                "compensation",
                "figures",
            ),
            fold=lambda fold: fold,
            models=PLAN.report_models,
            runs=RUNS,
            figures=PAGES.model_report_figures,
        ),
    shell:
        pages.RUN_NOTEBOOK_PAGES


rule paper_report:
    input:
        notebook="notebooks/paper_report.ipynb",
        library=code_of("notebooks/paper_report.ipynb"),
        sheets=dataset_sheets(),
        summary=out(paths.DATASET_SUMMARY),
        ambient=out(paths.AMBIENT_RANGES),
        kb=[out(paths.TABLE5)] if DECOUPLED else [],
        metrics=out(paths.METRICS),
        coefficients=out(paths.COEFFICIENTS),
        sensitive_points=out(paths.SENSITIVE_POINTS),
        comparison=out(paths.PAPER_COMPARISON),
        faithfulness=out(paths.FAITHFULNESS),
        claims=out(paths.CLAIMS),
        paper=PAPER_FILES,
        figures=[f["path"] for f in PAGES.paper_report_figures().values()],
    output:
        notebook=out(paths.PAPER_REPORT, ext="ipynb"),
        html=report(
            out(paths.PAPER_REPORT, ext="html"),
            caption="../report/notebook_report.rst",
            category=CATEGORY["reports"],
            labels={"report": "paper"},
        ),
    log:
        f"{LOGS}/reports/paper_report.log",
    benchmark:
        f"{BENCH}/reports/paper_report.tsv"
    priority: rule_priority("paper_report")
    conda:
        ENV
    resources:
        **rule_resources("paper_report"),
    params:
        title=f"Paper report: Xu et al. reproduced on {DATASET.name}",
        statement=DATA_STATEMENT,
        parameters=lambda w, input: PAGES.notebook_parameters(
            input,
            {k: v for k, v in config.items() if k not in ("reports", "sweep")},
            paper_fold=config["paper_fold"],
            fold=PLAN.report_fold,
            algorithms=list(PLAN.paper_algorithms),
            approaches=APPROACHES,
            paper_dir=PAPER_DIR,
            figures=PAGES.paper_report_figures(),
        ),
    shell:
        pages.RUN_NOTEBOOK


rule index:
    input:
        code=code_of("index.py"),
        sheets=dataset_sheets(),
        data=dataset_files(),
        linked=PAGES.index_inputs(),
    output:
        index=out(paths.INDEX),
        provenance=out(paths.PROVENANCE),
    log:
        f"{LOGS}/index.log",
    benchmark:
        f"{BENCH}/index.tsv"
    conda:
        ENV
    resources:
        **rule_resources("index"),
    params:
        config_json=json.dumps(config, sort_keys=True),
        dataset=lambda w, input: os.path.dirname(input.sheets[0]),
        repo=REPO,
        git=lambda w: git_of_checkout(),
        dataset_name=DATASET.name,
        simulated=SIMULATED,
        statement=DATA_STATEMENT,
        sections=PAGES.index_sections(),
        figures=PAGES.index_figures(),
        tables=PAGES.index_tables(),
        sweep=out(paths.SWEEP_REPORT, ext="html"),
        headline=pages.headline(PLAN, DATASET.meta),
        answer=dict(
            markdown=out(paths.RECOMMENDATION_MARKDOWN),
            recommendation=out(paths.RECOMMENDATION),
            metrics=out(paths.METRICS),
            model=out(paths.DEPLOYED_MODEL),
            # The paper's claims, tested (an input of the index through linked_tables).
            claims=out(paths.CLAIMS),
            # Beside the answer: each held-out run's error, recommended and the paper's.
            figure=PAGES.embedded("recommendation"),
        ),
    script:
        "../scripts/index.py"
