"""The index pages: a dataset's ``results/<dataset>/index.html`` and ``results/index.html`` across datasets.

A dataset's page leads with the answer (the data statement, then
:func:`thermaxis.reports.answer.answer_sentence`: the model to deploy or none, its
held-out error against the paper's configuration and uncompensated, the verdict and the
run that decides it), then the reproduction (the paper's approach x algorithm grid,
lowest error first, and the paper's claims with their verdicts), then shows every figure as a thumbnail by stage, the main
tables in the page (sortable by a click, readable without JavaScript), the reports and
the provenance. Everything is computed from the workflow's tables, never recomputed.
"""

from __future__ import annotations

import html
import re
from dataclasses import dataclass, field

import pandas as pd

from thermaxis.compensation.verdict import verdict_sentence
from thermaxis.errors import DataError
from thermaxis.reports.html import (
    REPORT_CSS,
    SORT_SCRIPT,
    _code_spans,
    provenance_html,
    statement_html,
    table_html,
)
from thermaxis.reports.leads import model_name

__all__ = [
    "IndexRow",
    "IndexSection",
    "IndexFigure",
    "FigureGroup",
    "PageTable",
    "Headline",
    "PAPER_HEADLINE",
    "CLAIMS_COLUMNS",
    "claims_table",
    "deployment_comparison",
    "render_index",
    "render_results_index",
    "answers_table",
]


@dataclass(frozen=True)
class IndexRow:
    """One line of the index: a label and its links ``(text, relative href)``."""

    label: str
    links: tuple[tuple[str, str], ...]
    note: str = ""


@dataclass(frozen=True)
class IndexSection:
    """A heading of the index, an optional sentence under it, and its rows."""

    title: str
    rows: tuple[IndexRow, ...] = field(default=())
    intro: str = ""


@dataclass(frozen=True)
class IndexFigure:
    """A thumbnail: the PNG shown (and linked), the caption, every format's link."""

    stem: str
    caption: str
    thumbnail: str
    links: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class FigureGroup:
    """The figures of one stage of the method (errors and temperatures, decoupling, ...)."""

    title: str
    figures: tuple[IndexFigure, ...]


@dataclass(frozen=True)
class PageTable:
    """A table shown in the page, with its CSV beside it."""

    title: str
    frame: pd.DataFrame
    csv: str
    note: str = ""
    float_format: str = "%.3f"


@dataclass(frozen=True)
class Headline:
    """What a visitor came for, from the workflow's tables."""

    ranking: pd.DataFrame  # thermaxis.reports.crossdataset.model_ranking(the metrics table)
    recommendation: str  # the answer sentence of recommendation.md
    deployment: dict  # model.json's deployment record
    comparison: pd.DataFrame | None = None  # deployment_comparison(recommendation.csv)
    claims: pd.DataFrame | None = None  # the claims table, when the workflow made it
    answer: str = ""  # thermaxis.reports.answer.answer_sentence: what to deploy, and whether
    figure: str = ""  # the recommendation figure beside it, relative to the page
    figure_caption: str = ""


PAPER_HEADLINE = (
    "Reproduction of Xu et al., decoupling and step-by-step modelling of the thermal positioning error of a "
    "linear axis."
)
CLAIMS_COLUMNS = ("claim", "dataset", "effect", "lo", "hi", "p_value", "verdict")


# --------------------------------------------------------------------------- the numbers


def deployment_comparison(folds: pd.DataFrame) -> pd.DataFrame:
    """Per held-out run and on average: the recommended model's error against the paper's configuration."""
    columns = ["fold", "chosen", "rmse_um", "paper_rmse_um", "max_abs_um", "paper_max_abs_um"]
    shown = folds[[c for c in columns if c in folds.columns]].copy()
    mean = {c: shown[c].mean() for c in shown.columns if c not in ("fold", "chosen")}
    return pd.concat(
        [shown, pd.DataFrame([{"fold": "mean", "chosen": "", **mean}])], ignore_index=True
    )


def claims_table(frame: pd.DataFrame, where: str) -> pd.DataFrame:
    """The claims table's columns the headline shows; one line naming the file if any is missing."""
    missing = [c for c in CLAIMS_COLUMNS if c not in frame.columns]
    if missing:
        raise DataError(
            f"{where}: missing column(s) {', '.join(missing)}; expected {', '.join(CLAIMS_COLUMNS)}"
        )
    return frame[list(CLAIMS_COLUMNS)]


def _grid_sentence(ranking: pd.DataFrame) -> str:
    """The reproduction's grid in one sentence: the lowest and highest mean error, not a choice."""
    low = ranking.iloc[0]
    text = (
        f"Of the paper's approach × algorithm grid, the {model_name(low['approach'], low['algorithm'])} "
        f"has the lowest mean RMSE, {low['mean_rmse_um']:.2f} µm over {int(low['n_folds'])} held-out runs "
        f"(largest |residual| {low['worst_max_abs_um']:.2f} µm at worst)."
    )
    if len(ranking) > 1:
        high = ranking.iloc[-1]
        text += f" The {model_name(high['approach'], high['algorithm'])} leaves {high['mean_rmse_um']:.2f} µm."
    return text + " The answer above combines more candidates, weighted without each held-out run."


# --------------------------------------------------------------------------- HTML pieces


_INDEX_CSS = (
    "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:76em;margin:1.5em auto;"
    "padding:0 1em;line-height:1.45}ul.tx-index{padding-left:1.2em}"
    ".tx-answer{border-left:4px solid #15803d;background:#f0fdf4;padding:0.6em 1.1em;margin:0 0 1.2em 0}"
    ".tx-answer h2{margin-top:0.3em}.tx-answer::after{content:'';display:block;clear:both}"
    ".tx-answer-figure{float:right;width:22em;max-width:40%;margin:0 0 0.6em 1.2em}"
    ".tx-answer-figure img{width:100%;height:auto;display:block}"
    ".tx-answer-figure figcaption{font-size:0.75em;color:#374151}"
    ".tx-verdict-yes{color:#15803d;font-weight:bold}.tx-verdict-no{color:#b91c1c;font-weight:bold}"
    ".tx-grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(15em,1fr));gap:1em}"
    ".tx-thumb{margin:0;border:1px solid #e5e7eb;padding:0.4em;background:#fff}"
    ".tx-thumb img{width:100%;height:auto;display:block}"
    ".tx-thumb figcaption{font-size:0.78em;color:#374151;overflow-wrap:anywhere}"
    "nav.tx-toc a{margin-right:1em}table.tx-sortable th{white-space:nowrap}"
    ".tx-scroll{overflow-x:auto;max-width:100%}"
)


def _inline_markdown(text: str) -> str:
    """Escaped text with the Markdown of recommendation.md's sentence: `code` and **bold**."""
    return re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", _code_spans(text))


def _scroll(table: str) -> str:
    """A wide table scrolls inside its box instead of widening the page."""
    return f'<div class="tx-scroll">{table}</div>'


def _links(links) -> str:
    return " · ".join(
        f'<a href="{html.escape(href, quote=True)}">{html.escape(text)}</a>' for text, href in links
    )


def _head(title: str, extra_css: str = "") -> list[str]:
    return [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1.0">',
        '<link rel="icon" href="data:,">',
        f"<title>{html.escape(title)}</title>",
        f"<style>{_INDEX_CSS}{extra_css}{REPORT_CSS}</style>",
        "</head><body>",
    ]


# The verdict's outcome as the answer box shows it (the class colours it).
OUTCOME_WORDS = {
    "recommended": ("tx-verdict-yes", "recommended for deployment"),
    "not_established": ("tx-verdict-no", "not established, too few held-out runs to tell"),
    "not_recommended": ("tx-verdict-no", "not recommended for deployment"),
}


def _verdict_html(deployment: dict) -> str:
    verdict = deployment["verdict"]
    css, words = OUTCOME_WORDS[verdict["outcome"]]
    return (
        f"<p>Deployed model: <strong>{html.escape(str(deployment.get('candidate', '')))}</strong> "
        f"(config <code>compensation.model: {html.escape(str(deployment.get('model', '')))}</code>); "
        f'<span class="{css}">{words}</span>. '
        f"{html.escape(verdict_sentence(verdict, unit='µm'))}</p>"
    )


def _headline_html(headline: Headline) -> str:
    lead = headline.answer or headline.recommendation
    figure = (
        f'<figure class="tx-answer-figure"><a href="{html.escape(headline.figure, quote=True)}">'
        f'<img src="{html.escape(headline.figure, quote=True)}" '
        f'alt="{html.escape(headline.figure_caption, quote=True)}"></a>'
        f"<figcaption>{html.escape(headline.figure_caption)}</figcaption></figure>"
        if headline.figure
        else ""
    )
    parts = [
        '<section class="tx-answer" id="answer"><h2>The answer</h2>',
        figure,
        f'<p class="tx-lead">{_inline_markdown(lead)}</p>',
        _verdict_html(headline.deployment),
    ]
    if headline.comparison is not None:
        parts.append(
            table_html(
                headline.comparison,
                "%.2f",
                caption="Recommended model (chosen without each held-out run) against the paper's configuration, µm",
                sortable=True,
            )
        )
    parts += [
        "</section>",
        '<section id="grid"><h2>The reproduction: the paper\'s approach × algorithm grid</h2>',
        f"<p>{html.escape(_grid_sentence(headline.ranking))}</p>",
        f"<p>{_inline_markdown(headline.recommendation)}</p>" if headline.answer else "",
        # Eleven columns: the table scrolls inside its box, not the page.
        '<div id="headline-models" class="tx-scroll">',
        table_html(
            headline.ranking,
            "%.2f",
            caption="Held-out error of each approach × algorithm, lowest first (µm; leave-one-condition-out, "
            "error curves)",
            sortable=True,
        ),
        "</div>",
    ]
    if headline.claims is not None:
        parts += [
            "<h3>The paper's claims</h3>",
            _scroll(
                table_html(
                    headline.claims,
                    "%.3g",
                    caption="Each claim's effect, interval and verdict",
                    sortable=True,
                )
            ),
        ]
    parts.append("</section>")
    return "".join(parts)


def _figures_html(groups) -> str:
    parts = ['<section id="figures"><h2>Figures</h2>']
    for group in groups:
        if not group.figures:
            continue
        parts.append(f'<h3>{html.escape(group.title)}</h3><div class="tx-grid">')
        for fig in group.figures:
            alt = html.escape(fig.caption or fig.stem, quote=True)
            parts.append(
                f'<figure class="tx-thumb"><a href="{html.escape(fig.thumbnail, quote=True)}">'
                f'<img src="{html.escape(fig.thumbnail, quote=True)}" alt="{alt}"></a>'
                f"<figcaption><strong>{html.escape(fig.stem)}</strong> ({_links(fig.links)}). "
                f"{_code_spans(fig.caption)}</figcaption></figure>"
            )
        parts.append("</div>")
    parts.append("</section>")
    return "".join(parts)


def _tables_html(tables) -> str:
    parts = ['<section id="tables"><h2>Tables</h2>']
    for table in tables:
        note = f' <span class="tx-note">{_code_spans(table.note)}</span>' if table.note else ""
        parts.append(
            f"<h3>{html.escape(table.title)}</h3>"
            f'<p><a href="{html.escape(table.csv, quote=True)}">CSV</a>{note}</p>'
            + _scroll(table_html(table.frame, table.float_format, sortable=True))
        )
    parts.append("</section>")
    return "".join(parts)


def _sections_html(sections) -> str:
    parts = []
    for section in sections:
        if not section.rows:
            continue
        parts.append(f"<section><h2>{html.escape(section.title)}</h2>")
        if section.intro:
            parts.append(f'<p class="tx-note">{_code_spans(section.intro)}</p>')
        parts.append('<ul class="tx-index">')
        for row in section.rows:
            note = f' <span class="tx-note">{_code_spans(row.note)}</span>' if row.note else ""
            parts.append(f"<li>{html.escape(row.label)}: {_links(row.links)}{note}</li>")
        parts.append("</ul></section>")
    return "".join(parts)


# --------------------------------------------------------------------------- pages


def render_index(
    dataset_name: str,
    statement: str,
    simulated: bool,
    headline: Headline,
    figures=(),
    tables=(),
    sections=(),
    provenance: dict | None = None,
    subtitle: str = PAPER_HEADLINE,
) -> str:
    """The dataset's ``index.html``: the answer, figures, tables, reports and files, provenance.

    Links are written as given (relative to the page); empty sections are left out.
    Returns a complete HTML page with its style and script inline, nothing loaded from
    elsewhere.
    """
    kind = "tx-simulated" if simulated else "tx-measured"
    parts = _head(f"thermaxis: {dataset_name}")
    parts += [
        f'<header class="tx-banner {kind}"><h1>thermaxis results: {html.escape(dataset_name)}</h1>'
        f'<p class="tx-subtitle">{html.escape(subtitle)}</p>{statement_html(statement, simulated)}</header>',
        '<nav class="tx-toc"><a href="#answer">Answer</a><a href="#figures">Figures</a>'
        '<a href="#tables">Tables</a><a href="#reports">Reports and files</a>'
        '<a href="#provenance">Provenance</a> · <a href="../index.html">All datasets</a></nav>',
        _headline_html(headline),
        _figures_html(figures),
        _tables_html(tables),
        f'<div id="reports">{_sections_html(sections)}</div>',
    ]
    if provenance is not None:
        parts.append(
            f'<section id="provenance"><h2>Provenance</h2>{provenance_html(provenance, "provenance.json")}</section>'
        )
    parts += [f"<script>{SORT_SCRIPT}</script>", "</body></html>"]
    return "\n".join(parts) + "\n"


def _deployed_cell(answer: dict) -> str:
    """The answers table's model: the one config ``compensation.model`` set, or the
    recommendation when its verdict says deploy, else none with the closest (the verdict
    column says how it went)."""
    if answer["by_config"]:
        return f"{answer['candidate']} (set by config)"
    if answer["recommended"]:
        return answer["candidate"]
    return f"none (closest: {answer['candidate']})"


def answers_table(summary: pd.DataFrame, answers: dict[str, dict]) -> pd.DataFrame:
    """One row per dataset: its data, the model deployed, its held-out error against the paper's, the verdict."""
    data = summary.groupby("dataset", sort=True)["data"].first()
    rows = [
        {
            "dataset": name,
            "data": data.get(name, ""),
            "deployed model": _deployed_cell(a),
            "held-out RMSE, µm": a["rmse_um"],
            "paper's configuration, µm": a["paper_rmse_um"],
            "verdict": OUTCOME_WORDS[a["outcome"]][1],
        }
        for name, a in sorted(answers.items())
    ]
    return pd.DataFrame(rows)


def render_results_index(
    summary: pd.DataFrame, pages: dict[str, str], figure: str | None, answers: dict | None = None
) -> str:
    """``results/index.html``: each dataset's answer, its held-out errors and its page.

    ``pages`` maps a dataset name to its page, relative to ``results/``; ``figure`` is the
    summary figure's PNG, relative too; ``answers`` each dataset's
    :func:`thermaxis.reports.answer.read_answer`.
    """
    parts = _head("thermaxis: all datasets")
    simulated = sorted(summary.loc[summary["data"] == "simulated", "dataset"].unique())
    parts += [
        '<header class="tx-banner tx-measured"><h1>thermaxis results: all datasets</h1>'
        '<p class="tx-subtitle">Held-out error of each approach × algorithm on every dataset '
        "(leave-one-condition-out, error curves, µm).</p>",
        (
            f'<p class="tx-statement"><span class="tx-flag">SIMULATED DATA</span><strong>'
            f"{html.escape(', '.join(simulated))}: simulated, not measurements.</strong></p>"
            if simulated
            else ""
        ),
        "</header>",
    ]
    if answers:
        parts += [
            '<section id="answers" class="tx-answer"><h2>The answer per dataset</h2>',
            table_html(answers_table(summary, answers), "%.2f"),
            "</section>",
        ]
    parts += [
        '<section id="answer"><h2>Lowest error of the paper\'s grid per dataset</h2><ul>',
    ]
    parts += _lowest_per_dataset(summary, pages)
    parts.append("</ul></section>")
    if figure:
        parts.append(
            f'<figure class="tx-figure"><a href="{html.escape(figure, quote=True)}"><img src="{html.escape(figure, quote=True)}" '
            'alt="Held-out error per dataset, approach and algorithm"></a>'
            "<figcaption>Held-out error per dataset, approach and algorithm.</figcaption></figure>"
        )
    parts += [
        '<section id="tables"><h2>Every dataset, approach and algorithm</h2>'
        '<p><a href="_datasets/summary.csv">CSV</a> · <a href="_datasets/summary.md">Markdown</a></p>',
        _scroll(table_html(summary, "%.3f", sortable=True)),
        "</section>",
        f"<script>{SORT_SCRIPT}</script>",
        "</body></html>",
    ]
    return "\n".join(parts) + "\n"


def _lowest_per_dataset(summary: pd.DataFrame, pages: dict[str, str]) -> list[str]:
    """Per dataset, linked to its page, the model of the paper's grid with the lowest mean RMSE."""
    parts = []
    for name, rows in summary.groupby("dataset", sort=True):
        best = rows.sort_values(["mean_rmse_um", "mean_max_abs_um"], kind="stable").iloc[0]
        link = pages.get(name)
        title = (
            f'<a href="{html.escape(link, quote=True)}">{html.escape(name)}</a>'
            if link
            else html.escape(name)
        )
        parts.append(
            f"<li>{title} ({html.escape(str(best['data']).upper())}): the paper's grid's lowest, the "
            f"{html.escape(model_name(best['approach'], best['algorithm']))}, leaves a mean RMSE of {best['mean_rmse_um']:.2f} µm "
            f"over {int(best['n_folds'])} held-out runs.</li>"
        )
    return parts
