"""The workflow's plan: what a dataset and its validated config make of one run of the
workflow (runs, folds, which branches run, the approach and algorithm lists), worked out
once when the Snakefile is parsed, after the parse-time gate (thermaxis.pipeline.preflight).

Nothing here needs Snakemake, so the plan is unit-tested on datasets of every shape.
"""

from __future__ import annotations

from dataclasses import dataclass

from thermaxis import vocabulary
from thermaxis.dataset.summary import data_statement
from thermaxis.pipeline.parallel import fold_workers
from thermaxis.pipeline.preflight import Checked

# The paper's report shows its two algorithms.
PAPER_ALGORITHMS = ("mlr", "svr")
# The formats a report can embed, in order of preference.
EMBED_FORMATS = ("png", "svg")
# The stages whose job deals its folds to processes (thermaxis.pipeline.parallel).
FOLD_STAGES = ("models", "recommend")


@dataclass(frozen=True)
class Plan:
    """One dataset's run of the workflow, frozen."""

    dataset_name: str
    simulated: bool
    paper: bool  # the dataset reproduces the paper: its audit and report
    decoupled: bool  # two target positions or more: the slope/intercept branch runs
    ambient: str | None  # the ambient sensor, if any: Fig. 3 and Table 1
    rises: bool  # temperature rises logged, not absolute temperatures
    runs: tuple[str, ...]
    folds: tuple[str, ...]  # held-out runs
    algorithms: tuple[str, ...]
    fig_algorithms: tuple[str, ...]  # whose predictions the figures draw
    report_algorithms: tuple[str, ...]  # whose models a model report shows
    fig_formats: tuple[str, ...]
    fig_run: str  # the run of the single-run figures
    report_fold: str  # the fold the paper's report predicts
    combined_conditions: bool  # one report of all conditions instead of one per run
    statement: str  # where the numbers come from (every report and caption)

    @property
    def approaches(self) -> tuple[str, ...]:
        # With one target there is no line to decouple: the point-by-point branch runs alone.
        return tuple(vocabulary.APPROACHES) if self.decoupled else ("pointwise",)

    @property
    def other_runs(self) -> tuple[str, ...]:
        return tuple(r for r in self.runs if r != self.fig_run)

    @property
    def prediction_algorithms(self) -> tuple[str, ...]:
        """Figures' algorithms, then the model reports' (they embed their predictions)."""
        return tuple(dict.fromkeys(self.fig_algorithms + self.report_algorithms))

    @property
    def paper_algorithms(self) -> tuple[str, ...]:
        return tuple(a for a in PAPER_ALGORITHMS if a in self.fig_algorithms)

    @property
    def report_models(self) -> tuple[tuple[str, str], ...]:
        """(approach, algorithm) a model report shows side by side, as the paper compares them."""
        return tuple((p, a) for p in self.approaches for a in self.report_algorithms)

    @property
    def embed_format(self) -> str:
        """The format a report embeds."""
        return next((f for f in EMBED_FORMATS if f in self.fig_formats), self.fig_formats[0])

    @property
    def sweep_embed(self) -> str | None:
        return next((f for f in EMBED_FORMATS if f in self.fig_formats), None)

    @property
    def fold_threads(self) -> dict[str, int]:
        """A stage job with many folds spreads them over this many processes (one per
        FOLDS_PER_WORKER[stage] folds), which Snakemake caps at --cores."""
        n = len(self.folds)
        return {stage: fold_workers(n, n, stage) for stage in FOLD_STAGES}

    @property
    def clean_threads(self) -> int:
        """The clean job's unit is a run (every run, whatever the folds)."""
        return fold_workers(len(self.runs), len(self.runs), "clean")

    def left_out(self) -> list[str]:
        """What the dataset leaves out, one clause each."""
        notes = []
        if not self.decoupled:
            notes.append(
                "a single target position: the decoupled (slope/intercept) branch does not "
                "apply (a slope needs two positions), only point-by-point models run"
            )
        if self.ambient is None:
            notes.append(
                "no ambient_sensor: the ambient figure (Fig. 3) and ambient table are left out"
            )
        if self.rises:
            notes.append(
                "temperature rises logged, not absolute temperatures: the slope model k uses "
                "the logged rises in their place"
            )
        return notes


def plan_of(checked: Checked) -> Plan:
    """The plan of a dataset that passed the gate, from its validated config."""
    dataset, settings, config = checked.dataset, checked.settings, checked.config
    runs, folds = tuple(checked.runs), tuple(checked.folds)
    algorithms = tuple(settings.models.algorithms)
    paper = dataset.reproduces == "xu2023"
    return Plan(
        dataset_name=dataset.name,
        simulated=dataset.simulated,
        paper=paper,
        decoupled=checked.n_positions >= 2,
        ambient=checked.ambient,
        rises=dataset.temperature_kind == "rise",
        runs=runs,
        folds=folds,
        algorithms=algorithms,
        fig_algorithms=tuple(a for a in settings.figures.algorithms if a in algorithms),
        report_algorithms=tuple(a for a in settings.reports.model_algorithms if a in algorithms),
        fig_formats=tuple(settings.figures.formats),
        fig_run=settings.figures.run or runs[0],
        # The paper predicts its last condition; a dataset without that run shows its last fold.
        report_fold=(
            config["paper_fold"] if paper and config["paper_fold"] in folds else folds[-1]
        ),
        # Many runs (config reports.combined_above_runs): one report of all conditions, a
        # section per run, instead of a notebook per run.
        combined_conditions=len(runs) > settings.reports.combined_above_runs,
        statement=data_statement(
            dataset.name,
            dataset.simulated,
            dataset.meta["provenance"]["citation"],
            reproduces_paper=paper,
        ),
    )


# The deployable compensation: the configured model fitted on all runs (model.json and a
# Structured Text block), and per held-out run the controller exports of that fold's
# model and the error left after compensating. Folds stay for evaluation only.
def compensation_params(checked: Checked, plan: Plan) -> dict:
    """The compensation rule's parameters (workflow/scripts/compensation.py)."""
    settings, config, dataset = checked.settings, checked.config, checked.dataset
    return dict(
        # A single target has no slope: the point-by-point model gives an offset (SD43900 alone).
        approach=settings.compensation.approach if plan.decoupled else "pointwise",
        model=settings.compensation.model,
        sections={
            name: config[name] for name in ("selection", "decoupling", "models", "compensation")
        },
        about=dict(dataset=dataset.name, simulated=plan.simulated, statement=plan.statement),
        signals=list(dataset.signals),
    )


# Which model the runs support: one job per outer fold scores every candidate (inner
# leave-one-condition-out on the other runs, and the held-out run), one job chooses
# (thermaxis.method.nested). The compensation deploys its choice (compensation.model).
def recommend_params(checked: Checked, plan: Plan) -> dict:
    """The recommend rule's parameters (workflow/scripts/recommend.py)."""
    config = checked.config
    return dict(
        recommend=config["recommend"],
        selection=config["selection"],
        models=config["models"],
        decoupling=config["decoupling"],
        decoupled=plan.decoupled,
        signals=list(checked.dataset.signals),
    )
