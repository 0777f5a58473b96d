"""Every output of a dataset's run of the workflow, as lists of result files below
``root`` (results/<dataset>): what `rule all` asks for and what the reports and the
index link. Figures are entries of the figure table (thermaxis.figures.registry): a
figure's files are its folder, its stem and each configured format.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from thermaxis.pipeline import paths
from thermaxis.pipeline.paths import under
from thermaxis.pipeline.plan import Plan

# The tables each fold of the models rule writes (thermaxis.method.folds.SORT_KEYS).
MODEL_TABLES = ("metrics", "coefficients", "kb_predictions", "error_predictions", "fitting")
# The compensation's tables, per held-out run and collected: the controller exports, the
# residuals, ISO 230-2 and the before/after summary.
COMPENSATION_TABLES = ("siemens_840d", "twincat", "residuals", "iso230_2", "summary")


@dataclass(frozen=True)
class Filed:
    """A result file the Snakemake report files: its category (reports.pages.CATEGORY), the
    caption's file under workflow/report/ and its labels."""

    path: str
    category: str
    caption: str
    labels: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- dataset
def dataset_sheets(dataset_root) -> list[str]:
    return [str(Path(dataset_root) / "dataset.yaml"), str(Path(dataset_root) / "runs.tsv")]


def dataset_files(dataset_root) -> list[str]:
    """Every file of the dataset but its two sheets: what provenance.json hashes."""
    sheets = set(dataset_sheets(dataset_root))
    files = (str(p) for p in Path(dataset_root).rglob("*") if p.is_file())
    return sorted(f for f in files if f not in sheets)


def dataset_tables(plan: Plan, root) -> dict:
    """What assemble writes beside the assembled runs when the dataset has it: Table 1's
    ambient ranges (an ambient sensor) and the decoupling of Table 5 (two positions or more).
    """
    tables = {}
    if plan.ambient:
        tables["ambient"] = Filed(
            under(root, paths.AMBIENT_RANGES),
            "dataset",
            "ambient_ranges",
            {"table": "ambient ranges (Table 1)"},
        )
        tables["ambient_series"] = under(root, paths.AMBIENT_SERIES)
    if plan.decoupled:
        tables["kb"] = Filed(
            under(root, paths.TABLE5), "decoupling", "table5", {"table": "Table 5"}
        )
        tables["kb_markdown"] = under(root, paths.TABLE5_MARKDOWN)
        tables["polynomials"] = under(root, paths.POLYNOMIALS)
    return tables


def audit_tables(plan: Plan, root) -> dict:
    """What the statistics job writes for a dataset that reproduces the paper: the paper's
    published values beside the reproduced ones, and the faithfulness of the twin."""
    if not plan.paper:
        return {}
    return dict(
        paper_csv=Filed(
            under(root, paths.PAPER_COMPARISON),
            "audit",
            "paper_comparison",
            {"table": "paper comparison"},
        ),
        paper_markdown=under(root, paths.PAPER_COMPARISON_MARKDOWN),
        faithfulness=Filed(
            under(root, paths.FAITHFULNESS), "audit", "faithfulness", {"table": "faithfulness"}
        ),
        faithfulness_markdown=under(root, paths.FAITHFULNESS_MARKDOWN),
    )


# --------------------------------------------------------------------------- figures
def families(figures) -> dict[str, list]:
    """The figures by family (one rule each), in table order."""
    grouped = {}
    for figure in figures:
        grouped.setdefault(figure.family, []).append(figure)
    return grouped


def figure_instances(plan: Plan, figures) -> list:
    """Each figure with its wildcards: once per fold when its stem holds the fold, else once."""
    return [
        (fig, {"fold": fold} if fold else {})
        for fig in figures
        for fold in (plan.folds if fig.per_fold else [None])
    ]


def figure_paths(plan: Plan, root, figure, **wildcards) -> list[str]:
    """Every format's file of a figure (with a per-fold figure's ``{fold}`` unless given)."""
    stem = figure.stem.format(**wildcards) if wildcards else figure.stem
    return [f"{root}/{figure.folder}/{stem}.{ext}" for ext in plan.fig_formats]


def figure_files(plan: Plan, root, figures) -> list[str]:
    """Every file of ``figures``, a per-fold figure's for every fold, in table order."""
    return [
        path
        for fig, wildcards in figure_instances(plan, figures)
        for path in figure_paths(plan, root, fig, **wildcards)
    ]


def figure_tables(plan: Plan, root, figures) -> list[str]:
    """The tables a family reads, a per-fold figure's for every fold."""
    return sorted(
        {
            under(root, path, **wildcards)
            for fig, wildcards in figure_instances(plan, figures)
            for path in fig.tables.values()
        }
    )


def embedded_path(plan: Plan, root, stem: str) -> str:
    """The file of a workflow figure a report embeds."""
    return f"{root}/figures/{stem}.{plan.embed_format}"


# --------------------------------------------------------------------------- reports
def condition_reports(plan: Plan, root) -> list[str]:
    if plan.combined_conditions:
        return [under(root, paths.CONDITIONS_REPORT, ext="html")]
    return [under(root, paths.CONDITION_REPORT, run=run, ext="html") for run in plan.runs]


def model_reports(plan: Plan, root) -> list[str]:
    if not plan.report_models:
        return []
    return [under(root, paths.MODEL_REPORT, fold=fold, ext="html") for fold in plan.folds]


def report_html(plan: Plan, root) -> list[str]:
    return [
        *([under(root, paths.PAPER_REPORT, ext="html")] if plan.paper else []),
        under(root, paths.DATASET_REPORT, ext="html"),
        *condition_reports(plan, root),
        *model_reports(plan, root),
    ]


def report_outputs(plan: Plan, root) -> list[str]:
    return [under(root, paths.PROVENANCE), under(root, paths.INDEX), *report_html(plan, root)]


# --------------------------------------------------------------------------- tables
def statistics_outputs(root) -> list[str]:
    return [
        under(root, p)
        for p in (paths.COMPARISONS, paths.CLAIMS, paths.CLAIMS_MARKDOWN, paths.SELECTION_STABILITY)
    ]


def recommendation_outputs(root) -> list[str]:
    return [
        under(root, p)
        for p in (
            paths.RECOMMENDATION,
            paths.RECOMMENDATION_MARKDOWN,
            paths.CANDIDATES,
            paths.CHOICE,
        )
    ]


def compensation_outputs(root) -> list[str]:
    """model.json, the ST block and the tables; the drift figures are figures."""
    return [
        under(root, paths.DEPLOYED_MODEL),
        under(root, paths.STRUCTURED_TEXT),
        *(under(root, paths.COMPENSATION_TABLE, table=name) for name in COMPENSATION_TABLES),
    ]


def linked_tables(plan: Plan, root) -> list[str]:
    """The tables the index links."""
    tables = [
        paths.DATASET_SUMMARY,
        paths.CLEANING_QC,
        *([paths.AMBIENT_RANGES] if plan.ambient else []),
        *([paths.TABLE5, paths.TABLE5_MARKDOWN] if plan.decoupled else []),
        paths.SENSITIVE_POINTS,
        paths.METRICS,
        paths.COEFFICIENTS,
        paths.FITTING,
        paths.KB_PREDICTIONS,
        paths.ERROR_PREDICTIONS,
        *(
            [
                paths.PAPER_COMPARISON,
                paths.PAPER_COMPARISON_MARKDOWN,
                paths.FAITHFULNESS,
                paths.FAITHFULNESS_MARKDOWN,
            ]
            if plan.paper
            else []
        ),
    ]
    return [under(root, name) for name in tables] + statistics_outputs(root)


def all_outputs(plan: Plan, root, figures) -> list[str]:
    """What `rule all` asks for: ``figures`` (the figure table's, expanded), the tables,
    the recommendation, the compensation and the reports."""
    return [
        *figure_files(plan, root, figures),
        under(root, paths.DATASET_SUMMARY),
        under(root, paths.ASSEMBLED_ERRORS),
        under(root, paths.CLEANING_QC),
        under(root, paths.METRICS),
        *([under(root, paths.PAPER_COMPARISON)] if plan.paper else []),
        *([under(root, paths.TABLE5)] if plan.decoupled else []),
        *recommendation_outputs(root),
        *statistics_outputs(root),
        *compensation_outputs(root),
        *report_outputs(plan, root),
    ]


def one_of(names) -> str:
    """A wildcard's constraint: one of ``names``, literally."""
    return "|".join(name.replace(".", r"\.") for name in names)


def suffix(path: str) -> str:
    """A link's text: the file's extension."""
    return Path(path).suffix[1:]
