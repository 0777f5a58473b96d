"""The workflow's pages, composed and worded: the Snakemake report's categories, what each
report notebook reads and embeds and its parameters, the index's sections, thumbnails and
tables, and what plot.py draws. Built from the workflow's plan (thermaxis.pipeline.plan)
and the figure table; nothing here needs Snakemake.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from thermaxis.figures import registry
from thermaxis.figures.captions import figure_caption, provenance_note
from thermaxis.figures.family import family_workers
from thermaxis.pipeline import paths, targets
from thermaxis.pipeline.paths import under
from thermaxis.pipeline.plan import Plan
from thermaxis.reports.index import PAPER_HEADLINE

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
# The config sections the dataset's own reports depend on (a notebook hashes only those
# it is given, so changing selection.n_clusters leaves the dataset reports alone).
DATA_SECTIONS = ("dataset", "ambient_sensor", "temperatures", "errors", "decoupling")
# The figures a condition report draws for its run.
CONDITION_FIGURES = (
    "fig5_unzeroed",
    "fig6_error_vs_time",
    "fig8_rezeroed",
    "fig10_temperature_rise",
)
# The controller exports and summary a model report shows of its fold's compensation.
FOLD_COMPENSATION = ("summary", "iso230_2", "siemens_840d", "twincat")


def headline(plan: Plan, meta: Mapping) -> str:
    """The index's first line: the paper's title for a dataset that reproduces it, else the dataset's."""
    if plan.paper:
        return PAPER_HEADLINE
    return meta.get("title", meta["description"].strip().split("\n")[0])


def figure_facts(plan: Plan, units: Mapping, selection: Mapping, degree: int) -> registry.Facts:
    """What the figure table's conditions and arguments name."""
    return registry.Facts(
        dataset_name=plan.dataset_name,
        simulated=plan.simulated,
        twin=plan.paper,
        decoupled=plan.decoupled,
        ambient=plan.ambient is not None,
        run=plan.fig_run,
        other_runs=list(plan.other_runs),
        folds=list(plan.folds),
        approaches=list(plan.approaches),
        prediction_algorithms=list(plan.prediction_algorithms),
        units=units,
        selection=selection,
        degree=degree,
    )


@dataclass(frozen=True)
class Pages:
    """The pages of one dataset's run: ``root`` is its results folder, ``figures`` the
    figure table expanded for `rule all`, ``config`` the validated config and ``repo`` the
    workflow's folder (relative, as the notebooks record it)."""

    plan: Plan
    root: str
    facts: registry.Facts
    figures: list
    config: Mapping
    repo: str

    def out(self, path: str, **wildcards) -> str:
        return under(self.root, path, **wildcards)

    @property
    def stamp(self) -> str | None:
        """The note stamped on the dataset's figures (None for measured data)."""
        return provenance_note(self.plan.simulated, twin=self.plan.paper)

    def sections(self, *names) -> dict:
        return {name: self.config[name] for name in names if name in self.config}

    # ----------------------------------------------------------------------- figures
    def caption(self, figure_id: str, **details) -> str:
        plan = self.plan
        return figure_caption(
            figure_id, plan.dataset_name, plan.simulated, twin=plan.paper, **details
        )

    def embedded(self, figure_id: str, **details) -> dict:
        """A workflow figure for a report: the file to embed and its caption.

        ``details`` are the caption's; those the figure's stem names (fold, approach,
        algorithm) make the stem too.
        """
        stem = registry.stem_of(figure_id, **details)
        return {
            "path": targets.embedded_path(self.plan, self.root, stem),
            "caption": self.caption(figure_id, **details),
        }

    def figure_specs(self, figures) -> list[dict]:
        """What plot.py draws: per figure (and fold) its function, tables, arguments, files and caption."""
        specs = []
        for fig, wildcards in targets.figure_instances(self.plan, figures):
            spec = dict(
                stem=fig.stem.format(**wildcards),
                draw=fig.draw,
                tables={k: self.out(v, **wildcards) for k, v in fig.tables.items()},
                arguments={**fig.arguments, **wildcards},
                paths=targets.figure_paths(self.plan, self.root, fig, **wildcards),
                caption=registry.caption_of(fig, self.facts, wildcards),
            )
            if fig.reader:
                spec["reader"] = fig.reader
            specs.append(spec)
        return specs

    def figure_threads(self, figures) -> int:
        """Processes a family's job can use: one per MIN_FIGURES_PER_WORKER of its figures."""
        n = len(targets.figure_instances(self.plan, figures))
        return family_workers(n, n)

    def dataset_report_figures(self) -> dict:
        plan = self.plan
        figures = {"fig5_unzeroed": self.embedded("fig5_unzeroed", run=plan.fig_run)}
        if plan.ambient:
            figures["fig3_ambient"] = self.embedded("fig3_ambient")
        if plan.other_runs:
            figures["fig9_other_runs"] = self.embedded(
                "fig9_other_runs", runs=list(plan.other_runs)
            )
        if plan.decoupled:
            figures["fig12_slope_intercept"] = self.embedded("fig12_slope_intercept")
        return figures

    def paper_report_figures(self) -> dict:
        plan, run = self.plan, self.plan.fig_run
        figures = {
            "fig2_positioning_error": self.embedded("fig2_positioning_error", run=run),
            **self.dataset_report_figures(),
            "fig6_error_vs_time": self.embedded("fig6_error_vs_time", run=run),
            "fig7_error_surface": self.embedded("fig7_error_surface", run=run),
            "fig8_rezeroed": self.embedded("fig8_rezeroed", run=run),
            "fig10_temperature_rise": self.embedded("fig10_temperature_rise", run=run),
            "fold_comparison": self.embedded("fold_comparison", target="error"),
        }
        for algorithm in plan.paper_algorithms:
            kinds = [("error_prediction", a) for a in plan.approaches]
            kinds += [("kb_prediction", "decoupled")] if plan.decoupled else []
            for kind, approach in kinds:
                figure = self.embedded(
                    kind, fold=plan.report_fold, approach=approach, algorithm=algorithm
                )
                figures[Path(figure["path"]).stem] = figure
        return figures

    def model_report_figures(self, fold: str) -> dict:
        """The workflow figures a model report embeds: its models' predictions and the drift."""
        figures = {}
        for approach, algorithm in self.plan.report_models:
            kinds = ["error_prediction"]
            if approach == "decoupled":
                kinds.append("kb_prediction")
            for kind in kinds:
                figures[f"{kind}_{approach}_{algorithm}"] = self.embedded(
                    kind, fold=fold, approach=approach, algorithm=algorithm
                )
        figures["compensation_drift"] = self.embedded("compensation_drift", fold=fold)
        return figures

    def condition_captions(self, run: str) -> dict:
        """Captions of the figures a condition report draws for its run."""
        return {f: self.caption(f, run=run) for f in CONDITION_FIGURES}

    # ----------------------------------------------------------------------- notebooks
    def condition_report_inputs(self, run: str) -> dict:
        """What the condition report of ``run`` reads, by the notebook's input names."""
        return dict(
            summary=self.out(paths.DATASET_SUMMARY),
            errors=self.out(paths.CLEAN_ERRORS, run=run),
            temperatures=self.out(paths.CLEAN_TEMPERATURES, run=run),
            series=self.out(paths.CLEAN_SERIES, run=run),
            qc=self.out(paths.CLEAN_QC, run=run),
            gaps=self.out(paths.CLEAN_GAPS, run=run),
            windows=self.out(paths.CLEAN_WINDOWS, run=run),
            kb=[self.out(paths.TABLE5)] if self.plan.decoupled else [],
        )

    def model_report_inputs(self, fold: str) -> dict:
        """What the model report of ``fold`` reads, by the notebook's input names."""

        def table(name):
            return self.out(paths.FOLD_TABLE, fold=fold, table=name)

        return dict(
            selection=self.out(paths.SELECTION_TABLE, fold=fold),
            selection_json=self.out(paths.SELECTION, fold=fold),
            metrics=table("metrics"),
            coefficients=table("coefficients"),
            kb=table("kb_predictions"),
            errors=table("error_predictions"),
            fitting=table("fitting"),
            compensation=[
                self.out(paths.FOLD_COMPENSATION, fold=fold, table=n) for n in FOLD_COMPENSATION
            ],
            fold_model=self.out(paths.FOLD_MODEL, fold=fold),
            deployed=self.out(paths.DEPLOYED_MODEL),
            figures=[f["path"] for f in self.model_report_figures(fold).values()],
        )

    def notebook_parameters(self, input, sections_used, **values) -> str:
        """The notebook's parameters as JSON: every input but the notebook and the library, and ``values``."""
        inputs = {k: v for k, v in dict(input).items() if k not in ("notebook", "library")}
        return json.dumps(
            dict(
                dataset_name=self.plan.dataset_name,
                simulated=self.plan.simulated,
                statement=self.plan.statement,
                dataset_root=self.config["dataset"],
                repo=self.repo,
                config=sections_used,
                inputs=inputs,
                **values,
            ),
            sort_keys=True,
        )

    def report_pages(self, stem, keys, inputs_of, title, sections_used, **values_of) -> str:
        """The JSON of a page-per-key report (RUN_NOTEBOOK_PAGES): per key its files
        (``stem`` of a key: paths.CONDITION_REPORT or paths.MODEL_REPORT), title and
        parameters; ``values_of`` maps a parameter to its value or a function of the key.
        """
        wildcard = "run" if "{run}" in stem else "fold"
        return json.dumps(
            [
                dict(
                    executed=self.out(stem, **{wildcard: key}, ext="ipynb"),
                    html=self.out(stem, **{wildcard: key}, ext="html"),
                    title=title(key),
                    parameters=json.loads(
                        self.notebook_parameters(
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

    # ----------------------------------------------------------------------- the index
    def condition_links(self, run: str) -> list:
        """Where the index sends a run: its report, or its section of the combined one."""
        if self.plan.combined_conditions:
            return [("section", self.out(paths.CONDITIONS_REPORT, ext="html") + f"#run-{run}")]
        return [("condition report", self.out(paths.CONDITION_REPORT, run=run, ext="html"))]

    def index_sections(self) -> list:
        """What the index links, in order: (title, intro, rows of (label, [(text, path)]))."""
        plan, suffix = self.plan, targets.suffix
        reports = self.report_rows()
        models = [
            (f"Fold {fold} (held-out run)", [("model report", path)])
            for fold, path in zip(plan.folds, targets.model_reports(plan, self.root), strict=False)
        ]
        tables = [(Path(p).name, [(suffix(p), p)]) for p in targets.linked_tables(plan, self.root)]
        compensation = {}
        for p in targets.compensation_outputs(self.root):
            compensation.setdefault(Path(p).stem, []).append((suffix(p), p))
        answer = [
            (
                "recommendation",
                [
                    ("csv", self.out(paths.RECOMMENDATION)),
                    ("md", self.out(paths.RECOMMENDATION_MARKDOWN)),
                ],
            ),
            ("candidates", [("csv", self.out(paths.CANDIDATES))]),
            ("deployed model and its verdict", [("json", self.out(paths.DEPLOYED_MODEL))]),
        ]
        return [
            # Its intro, the answer in words, is written by the index job from these files.
            ("Which model to deploy", "", answer),
            ("Reports", "", reports),
            (
                "Model reports",
                "Metrics, sensitive points, coefficients, predictions and compensation of one fold, "
                f"every approach with each algorithm of config `reports.model_algorithms` "
                f"({', '.join(plan.report_algorithms)}) side by side.",
                models,
            ),
            ("All tables", "", tables),
            (
                "Compensation",
                f"The deployed model (config compensation.model: {self.config['compensation']['model']}) "
                "fitted on all runs (model.json), the controller "
                "exports of each fold's model on its held-out run and the error left after compensating; "
                "the thermal-drift figures are under Figures (README: Compensating a machine).",
                list(compensation.items()),
            ),
        ]

    def report_rows(self) -> list:
        """The dataset's reports: the paper's, the dataset's, the conditions' and each run's."""
        plan = self.plan
        reports = []
        if plan.paper:
            reports.append(
                (
                    "The paper, figure by figure and table by table",
                    [("paper report", self.out(paths.PAPER_REPORT, ext="html"))],
                )
            )
        reports.append(
            (
                "Dataset: runs, sensors, cleaning",
                [("dataset report", self.out(paths.DATASET_REPORT, ext="html"))],
            )
        )
        if plan.combined_conditions:
            reports.append(
                (
                    f"All {len(plan.runs)} runs",
                    [("conditions report", self.out(paths.CONDITIONS_REPORT, ext="html"))],
                )
            )
        reports += [(f"Run {run}", self.condition_links(run)) for run in plan.runs]
        return reports

    def index_figures(self) -> list:
        """The index's thumbnails by stage: (stage, [(stem, caption, thumbnail, [(ext, path)])])."""
        groups = {}
        for fig, wildcards in targets.figure_instances(self.plan, self.figures):
            files = targets.figure_paths(self.plan, self.root, fig, **wildcards)
            thumbnail = next((p for p in files if p.endswith((".png", ".svg"))), None)
            groups.setdefault(fig.category, []).append(
                (
                    fig.stem.format(**wildcards),
                    registry.caption_of(fig, self.facts, wildcards) or "",
                    thumbnail,
                    [(targets.suffix(p), p) for p in files],
                )
            )
        order = list(CATEGORY)
        return [
            (CATEGORY[key].split(". ", 1)[1], figures)
            for key, figures in sorted(groups.items(), key=lambda kv: order.index(kv[0]))
        ]

    def index_tables(self) -> list:
        """The tables the index shows in the page (title, file, note); the others are linked."""
        return [
            ("Runs", self.out(paths.DATASET_SUMMARY), ""),
            (
                "Cleaning events: excursions, unusable and flat sensors, merged timestamps, displacement findings",
                self.out(paths.CLEANING_EVENTS),
                "docs/your-data.md",
            ),
            (
                "Held-out error per fold, approach, algorithm and target",
                self.out(paths.METRICS),
                "",
            ),
            (
                "Recommendation per held-out run",
                self.out(paths.RECOMMENDATION),
                "docs/recommendation.md",
            ),
            (
                "Compensation: each held-out run before and after compensating",
                self.out(paths.COMPENSATION_TABLE, table="summary"),
                "",
            ),
            ("Sensitive points per fold", self.out(paths.SENSITIVE_POINTS), ""),
            *(
                [
                    (
                        "Faithfulness: every calibration target, published against reproduced",
                        self.out(paths.FAITHFULNESS),
                        "docs/datasets.md",
                    )
                ]
                if self.plan.paper
                else []
            ),
        ]

    def index_inputs(self) -> list[str]:
        linked = {
            path.split("#", 1)[0]
            for _, _, rows in self.index_sections()
            for _, links in rows
            for _, path in links
        }
        drawn = {
            path
            for _, figures in self.index_figures()
            for *_, links in figures
            for _, path in links
        }
        return sorted(linked | drawn | {path for _, path, _ in self.index_tables()})

    def sweep_parameters(self, sweep_figures, folds, skipped, input) -> str:
        """papermill parameters of the sweep report: the grid, the plan's notes, the inputs."""
        embed = self.plan.sweep_embed
        return json.dumps(
            dict(
                dataset_name=self.plan.dataset_name,
                simulated=self.plan.simulated,
                statement=self.plan.statement,
                figures={
                    fig.id: (f"{self.root}/{fig.folder}/{fig.stem}.{embed}" if embed else "")
                    for fig in sweep_figures
                },
                grid=self.config["sweep"],
                folds=folds,
                skipped=skipped,
                selection=self.config["selection"],
                degree=self.config["decoupling"]["degree"],
                summary=input.summary,
                ranking=input.ranking,
                effects=input.effects,
                benchmarks=list(input.benchmarks),
            ),
            sort_keys=True,
        )


def page_files(inputs_of, keys) -> list[str]:
    """Every file the pages of ``keys`` read (a page's inputs are files or lists of them)."""
    return sorted(
        {
            path
            for key in keys
            for value in inputs_of(key).values()
            for path in (value if isinstance(value, list) else [value])
        }
    )
