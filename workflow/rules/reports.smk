# Reports: parametrised notebooks executed by papermill and turned into self-contained
# HTML (RUN_NOTEBOOK), the dataset's provenance record and the index page. The notebooks
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
        summary=f"{OUT}/tables/dataset_summary.csv",
        qc=f"{OUT}/tables/cleaning_qc.csv",
        gaps=expand(f"{OUT}/clean/{{run}}/gaps.csv", run=RUNS),
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
        recommendation=f"{OUT}/tables/recommendation.csv",
        model=f"{OUT}/compensation/model.json",
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
    priority: rule_priority("dataset_report")
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
        pages=page_files(condition_report_inputs, RUNS),
    output:
        notebooks=expand(f"{OUT}/reports/condition_{{run}}.ipynb", run=RUNS),
        html=[
            report(
                f"{OUT}/reports/condition_{run}.html",
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
        pages=report_pages(
            "condition",
            RUNS,
            condition_report_inputs,
            lambda run: f"Condition report: run {run} ({DATASET.name})",
            sections(*DATA_SECTIONS),
            run=lambda run: run,
            captions=condition_captions,
            stamp=STAMP,
        ),
    shell:
        RUN_NOTEBOOK_PAGES


rule conditions_report:
    input:
        notebook="notebooks/conditions_report.ipynb",
        library=code_of("notebooks/conditions_report.ipynb"),
        summary=f"{OUT}/tables/dataset_summary.csv",
        errors=f"{OUT}/assembled/errors.parquet",
        temperatures=f"{OUT}/assembled/temperatures.parquet",
    output:
        notebook=f"{OUT}/reports/conditions.ipynb",
        html=report(
            f"{OUT}/reports/conditions.html",
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
        parameters=lambda w, input: notebook_parameters(
            input, sections(*DATA_SECTIONS), runs=RUNS, stamp=STAMP
        ),
    shell:
        RUN_NOTEBOOK


rule model_report:
    input:
        notebook="notebooks/model_report.ipynb",
        library=code_of("notebooks/model_report.ipynb"),
        pages=page_files(model_report_inputs, FOLDS),
    output:
        notebooks=expand(f"{OUT}/reports/model_{{fold}}.ipynb", fold=FOLDS),
        html=[
            report(
                f"{OUT}/reports/model_{fold}.html",
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
        pages=report_pages(
            "model",
            FOLDS,
            model_report_inputs,
            lambda fold: f"Model report: fold {fold} ({DATASET.name})",
            sections(
                *DATA_SECTIONS,
                "selection",
                "models",
                "folds",
                "compensation",
                "figures",
            ),
            fold=lambda fold: fold,
            models=REPORT_MODELS,
            runs=RUNS,
            figures=model_report_figures,
        ),
    shell:
        RUN_NOTEBOOK_PAGES


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
        faithfulness=f"{OUT}/tables/faithfulness.csv",
        claims=f"{OUT}/tables/claims.csv",
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
    priority: rule_priority("paper_report")
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
        sheets=dataset_sheets(),
        data=dataset_files(),
        linked=index_inputs(),
    output:
        index=f"{OUT}/index.html",
        provenance=f"{OUT}/provenance.json",
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
        sections=index_sections(),
        figures=index_figures(),
        tables=INDEX_TABLES,
        sweep=f"{OUT}/sweep/sweep_report.html",
        headline=HEADLINE,
        answer=dict(
            markdown=f"{OUT}/tables/recommendation.md",
            recommendation=f"{OUT}/tables/recommendation.csv",
            metrics=f"{OUT}/tables/metrics.csv",
            model=f"{OUT}/compensation/model.json",
            # The paper's claims, tested (an input of the index through linked_tables).
            claims=f"{OUT}/tables/claims.csv",
            # Beside the answer: each held-out run's error, recommended and the paper's.
            figure=embedded("recommendation"),
        ),
    script:
        "../scripts/index.py"
