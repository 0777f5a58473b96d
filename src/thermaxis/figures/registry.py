"""The figure table: every figure of the project, one entry each (after showyourwork).

An entry's ``id`` is the figure's file stem, its caption key
(:func:`thermaxis.figures.captions.figure_caption`) and the name of the function that
draws it, ``<id>`` or ``fig_<id>`` in its module (:data:`FIGURES` lists the module and
function). A figure drawn once per fold or per model has a stem that starts with its id
and goes on with those values (``error_prediction_E4_decoupled_mlr``).

Each entry also says

* ``when``: the condition under which the dataset has the figure, a name of
  :class:`Facts` (``"always"``, ``"decoupled"``, ``"ambient"``, ``"other_runs"``);
* ``target``: who draws it: ``"all"`` (the workflow's default run), ``"sweep"`` (the
  workflow's ``sweep`` target) or ``"datasets"`` (``python -m thermaxis.reports.crossdataset``);
* ``family``: the workflow job that draws it with the rest of its family (starting Python
  and importing matplotlib costs more than drawing a figure): ``fig_data`` as soon as the
  data are assembled and decoupled, ``fig_predictions`` (every fold's) once the models
  are fitted, ``fig_results`` once the recommendation and the compensation are in;
* ``tables``: argument name -> table, relative to ``results/<dataset>/``, and
  ``arguments``: the function's other arguments; ``each``: the values it is drawn for;
* the report category, labels and caption details.

A :class:`Fact` in ``arguments``, ``caption``, ``labels`` or ``each`` stands for what the
workflow knows about the dataset when it is parsed (:class:`Facts`); ``{fold}`` in a
stem or table is the fold of a per-fold job. This module imports neither matplotlib
nor pandas: the workflow reads it while Snakemake parses.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import import_module
from itertools import groupby, product
from typing import Any

from thermaxis.figures.captions import figure_caption
from thermaxis.pipeline import paths

__all__ = [
    "Fact",
    "Facts",
    "FigureEntry",
    "Figure",
    "FIGURES",
    "entry",
    "stem_of",
    "expand",
    "function",
    "caption_of",
    "sweep_heatmap",
]


@dataclass(frozen=True)
class Fact:
    """A placeholder for the attribute ``name`` of :class:`Facts`."""

    name: str


@dataclass(frozen=True)
class Facts:
    """What the workflow knows about the dataset when it is parsed."""

    dataset_name: str
    simulated: bool
    decoupled: bool  # several target positions: the decoupled branch, Figs. 2, 7, 8 and 12
    ambient: bool  # an ambient sensor: Fig. 3
    run: str  # the run of the single-run figures (config figures.run, else the first)
    other_runs: Sequence[str]  # the other runs (Fig. 9 when there is one)
    folds: Sequence[str]  # held-out runs
    approaches: Sequence[str]  # decoupled and/or pointwise
    prediction_algorithms: Sequence[str]  # whose predictions are drawn (figures, model reports)
    units: Mapping = field(default_factory=dict)  # operating signals' units (Fig. 10)
    selection: Mapping = field(default_factory=dict)  # config selection (the sweep's heat map)
    degree: int = 1  # config decoupling.degree (the sweep's heat map)
    twin: bool = True  # a simulated dataset that reproduces the paper (its figures' note)
    always: bool = True


@dataclass(frozen=True)
class FigureEntry:
    """One row of the figure table (module docstring)."""

    id: str
    draw: str  # "<module>.<function>" under thermaxis, e.g. "figures.paper.fig5_unzeroed"
    family: str
    when: str  # an attribute of Facts
    target: str  # "all", "sweep" or "datasets"
    # argument -> path under results/<dataset>/ ({run}: Facts.run, {fold}: the fold)
    tables: Mapping[str, str]
    category: str | None = None  # a key of the workflow's report categories; None: no report
    subcategory: str | None = None
    label: str = ""  # the report's "figure" label
    labels: Mapping[str, Any] = field(default_factory=dict)  # its other labels
    arguments: Mapping[str, Any] = field(default_factory=dict)  # besides tables and a job's fold
    caption: Mapping[str, Any] | None = field(default_factory=dict)  # details; None: no caption
    each: Mapping[str, Any] = field(default_factory=dict)  # variable -> its values (or a Fact)
    stem: str = "{id}"
    folder: str = "figures"  # relative to results/<dataset>/ (target "datasets": to results/)
    reader: str | None = None  # "<module>.<function>" reading its tables; default by suffix


@dataclass(frozen=True)
class Figure:
    """An entry of the table for one dataset: condition decided, facts and values filled in."""

    id: str
    draw: str
    family: str
    stem: str  # may hold {fold}: the wildcard of a per-fold job
    folder: str
    tables: dict
    arguments: dict
    caption: dict | None
    category: str | None
    subcategory: str | None
    labels: dict
    reader: str | None

    @property
    def per_fold(self) -> bool:
        return "{fold}" in self.stem

    def report_fields(self, wildcards: Mapping[str, str]) -> dict:
        """Subcategory and labels of the Snakemake report with a per-fold job's fold filled in.

        A figure family's job has no wildcards (every fold's figure is one of its outputs),
        so Snakemake, which fills the report's fields from the job's wildcards, must get
        them filled already.
        """
        return {
            "subcategory": self.subcategory and _fill(self.subcategory, wildcards),
            "labels": {
                k: _fill(v, wildcards) if isinstance(v, str) else v for k, v in self.labels.items()
            },
        }


ERRORS = paths.ASSEMBLED_ERRORS
RUN = Fact("run")
FOLD = Fact("fold")  # a value of `each`, else the fold of a per-fold job
APPROACH = Fact("approach")
ALGORITHM = Fact("algorithm")


def _run_figure(id_: str, label: str, when: str) -> FigureEntry:
    """A paper figure of one run's errors (config figures.run)."""
    return FigureEntry(
        id_, f"figures.paper.{id_}", family="fig_data", when=when, target="all",
        tables={"errors": ERRORS}, category="data", label=label, labels={"run": RUN},
        arguments={"run": RUN}, caption={"run": RUN},
    )  # fmt: skip


def _prediction(id_: str, when: str, tables: dict, label: str, approaches) -> FigureEntry:
    """A held-out prediction: one job per fold, one figure per approach and algorithm."""
    return FigureEntry(
        id_, f"figures.predictions.fig_{id_}", family="fig_predictions", when=when, target="all",
        tables=tables, category="prediction", subcategory="{fold}", label=label,
        labels={"fold": "{fold}", "approach": APPROACH, "algorithm": ALGORITHM},
        arguments={"approach": APPROACH, "algorithm": ALGORITHM},
        caption={"fold": FOLD, "approach": APPROACH, "algorithm": ALGORITHM},
        each={"algorithm": Fact("prediction_algorithms"), "approach": approaches},
        stem="{id}_{fold}_{approach}_{algorithm}",
    )  # fmt: skip


FIGURES: tuple[FigureEntry, ...] = (
    # The paper's data figures. Figures along the stroke (2, 7, 8) need several positions;
    # the others are drawn against time when there is one.
    _run_figure("fig2_positioning_error", "Fig. 2", when="decoupled"),
    _run_figure("fig5_unzeroed", "Fig. 5", when="always"),
    _run_figure("fig6_error_vs_time", "Fig. 6", when="always"),
    _run_figure("fig7_error_surface", "Fig. 7", when="decoupled"),
    _run_figure("fig8_rezeroed", "Fig. 8", when="decoupled"),
    FigureEntry(
        "fig3_ambient", "figures.paper.fig3_ambient", family="fig_data", when="ambient",
        target="all", tables={"ambient": paths.AMBIENT_SERIES},
        category="data", label="Fig. 3", labels={"run": "all"},
    ),
    FigureEntry(
        "fig9_other_runs", "figures.paper.fig9_other_runs", family="fig_data", when="other_runs",
        target="all", tables={"errors": ERRORS}, category="data", label="Fig. 9",
        labels={"run": "others"}, arguments={"runs": Fact("other_runs")},
        caption={"runs": Fact("other_runs")},
    ),
    FigureEntry(
        "fig10_temperature_rise", "figures.paper.fig10_temperature_rise", family="fig_data",
        when="always", target="all",
        tables={
            "series": paths.CLEAN_SERIES,
            "signals": paths.CLEAN_SIGNAL_SERIES,
        },
        category="data", label="Fig. 10", labels={"run": RUN}, arguments={"units": Fact("units")},
        caption={"run": RUN},
    ),
    FigureEntry(
        "fig12_slope_intercept", "figures.paper.fig12_slope_intercept",
        family="fig_data", when="decoupled", target="all",
        tables={"kb": paths.TABLE5}, category="decoupling", label="Fig. 12",
        labels={"run": "all"},
    ),
    FigureEntry(
        "fold_comparison", "figures.predictions.fig_fold_comparison", family="fig_results",
        when="always", target="all", tables={"metrics": paths.METRICS},
        category="prediction", label="fold comparison", labels={"fold": "all"},
        caption={"target": "error"},
    ),
    FigureEntry(
        "recommendation", "figures.predictions.fig_recommendation", family="fig_results",
        when="always", target="all", tables={"recommendation": paths.RECOMMENDATION},
        category="prediction", label="recommendation", labels={"fold": "all"},
    ),
    # Beside Table 6: how often each sensor is chosen when a training run is left out.
    FigureEntry(
        "selection_stability", "figures.statistics.fig_selection_stability",
        family="fig_results", when="always", target="all",
        tables={"stability": paths.SELECTION_STABILITY}, category="sensitive_points",
        label="stability", labels={"fold": "all"},
    ),
    # Figs. 11/15/17 (point by point: 11) and 14/16.
    _prediction("error_prediction", "always", {"err_pred": paths.ERROR_PREDICTIONS},
                "Figs. 11/15/17", approaches=Fact("approaches")),
    _prediction("kb_prediction", "decoupled", {"kb_pred": paths.KB_PREDICTIONS},
                "Figs. 14/16", approaches=("decoupled",)),
    # The drift of each compensated held-out run, all in one job.
    FigureEntry(
        "compensation_drift", "figures.compensation.fig_compensation_drift",
        family="fig_results", when="always", target="all",
        tables={"summary": paths.FOLD_COMPENSATION.format(fold="{fold}", table="summary")}, category="compensation",
        label="thermal drift", labels={"fold": FOLD}, arguments={"fold": FOLD},
        caption={"fold": FOLD}, each={"fold": Fact("folds")}, stem="{id}_{fold}",
    ),
    # The sweep's figures, from its ranking (`make sweep`).
    FigureEntry(
        "sweep_heatmap", "figures.registry.sweep_heatmap", family="fig_sweep", when="always",
        target="sweep", tables={"ranking": paths.SWEEP_RANKING}, reader="sweep.run.read_sweep_table",
        arguments={"selection": Fact("selection"), "degree": Fact("degree")}, caption=None,
        folder="sweep/figures",
    ),
    FigureEntry(
        "sweep_factor_effects", "figures.sweep.fig_factor_effects", family="fig_sweep",
        when="always", target="sweep", tables={"ranking": paths.SWEEP_RANKING},
        reader="sweep.run.read_sweep_table", caption=None, folder="sweep/figures",
    ),
    FigureEntry(
        "sweep_critical_difference", "figures.statistics.fig_sweep_critical_difference",
        family="fig_sweep", when="always", target="sweep", tables={"ranking": paths.SWEEP_RANKING},
        reader="sweep.run.read_sweep_table", caption=None, folder="sweep/figures",
    ),
    # Held-out error across datasets, after every dataset's run (results/_datasets/).
    FigureEntry(
        "heldout_error", "figures.crossdataset.fig_heldout_error", family="", when="always",
        target="datasets", tables={"summary": "_datasets/summary.csv"}, caption=None,
        folder="_datasets",
    ),
)  # fmt: skip
_BY_ID = {e.id: e for e in FIGURES}


def entry(figure_id: str) -> FigureEntry:
    """The table's row of ``figure_id``."""
    if figure_id not in _BY_ID:
        raise ValueError(f"unknown figure id {figure_id!r}; expected one of {', '.join(_BY_ID)}")
    return _BY_ID[figure_id]


def stem_of(figure_id: str, **values) -> str:
    """The file stem of one figure of ``figure_id``; ``values`` fill its fields (others ignored)."""
    return _fill(entry(figure_id).stem, {"id": figure_id, **values})


def _resolve(value, facts: Facts | None, values: Mapping[str, Any]):
    """``value`` with its Facts filled in: an ``each`` variable, a job's fold or a fact."""
    if isinstance(value, Fact):
        if value.name in values:
            return values[value.name]
        if value.name == "fold":
            return "{fold}"
        return getattr(facts, value.name)
    if isinstance(value, Mapping):
        return {k: _resolve(v, facts, values) for k, v in value.items()}
    return value


def _fill(template: str, values: Mapping[str, Any]) -> str:
    for name, value in values.items():
        template = template.replace(f"{{{name}}}", str(value))
    return template


def _figure(e: FigureEntry, facts: Facts | None, values: dict) -> Figure:
    run = {"run": facts.run} if facts is not None else {}
    return Figure(
        id=e.id,
        draw=e.draw,
        family=e.family,
        stem=_fill(e.stem, {"id": e.id, **values}),
        folder=e.folder,
        tables={k: _fill(v, {**run, **values}) for k, v in e.tables.items()},
        arguments=_resolve(dict(e.arguments), facts, values),
        caption=None if e.caption is None else _resolve(dict(e.caption), facts, values),
        category=e.category,
        subcategory=e.subcategory,
        labels={"figure": e.label, **_resolve(dict(e.labels), facts, values)},
        reader=e.reader,
    )


def expand(facts: Facts | None, target: str = "all") -> list[Figure]:
    """The figures of ``target`` that the dataset has, in table order.

    An entry is drawn for every combination of its ``each`` values. Consecutive entries
    that vary first by the same variable are expanded together, by that variable first
    (each algorithm's error and k, b predictions side by side). ``facts`` is None for
    target ``"datasets"``, which belongs to no dataset.
    """
    chosen = [
        e for e in FIGURES if e.target == target and (facts is None or getattr(facts, e.when))
    ]
    out: list[Figure] = []
    for outer, group in groupby(chosen, key=lambda e: next(iter(e.each), None)):
        group = list(group)
        if outer is None:
            out += [_figure(e, facts, {}) for e in group]
            continue
        for value in _resolve(group[0].each[outer], facts, {}):
            for e in group:
                inner = [n for n in e.each if n != outer]
                lists = [_resolve(e.each[n], facts, {}) for n in inner]
                for combination in product(*lists):
                    values = {outer: value, **dict(zip(inner, combination, strict=True))}
                    out.append(_figure(e, facts, values))
    return out


def function(path: str):
    """The function ``"<module>.<function>"`` under :mod:`thermaxis` (a drawing one: matplotlib)."""
    module, name = path.rsplit(".", 1)
    return getattr(import_module(f"thermaxis.{module}"), name)


def caption_of(figure: Figure, facts: Facts, wildcards: Mapping[str, str] | None = None):
    """The figure's caption; a per-fold figure's fold comes from the job's ``wildcards``."""
    if figure.caption is None:
        return None
    details = {
        k: _fill(v, wildcards) if isinstance(v, str) and wildcards else v
        for k, v in figure.caption.items()
    }
    return figure_caption(
        figure.id, facts.dataset_name, facts.simulated, twin=facts.twin, **details
    )


# --------------------------------------------------------------------------- drawn by their id


def sweep_heatmap(ranking, selection: Mapping, degree: int):
    """The sweep's n_clusters x algorithm heat map, one panel per approach, from ranking.csv."""
    from thermaxis.config import SelectionSettings
    from thermaxis.figures.sweep import fig_sweep_heatmap
    from thermaxis.sweep.run import heatmap_table

    settings = SelectionSettings.from_section(selection)
    approaches = dict.fromkeys(ranking["approach"])
    tables = {a: heatmap_table(ranking, a, settings, int(degree)) for a in approaches}
    return fig_sweep_heatmap(tables)
