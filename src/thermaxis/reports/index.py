"""The index page of a dataset's results."""

from __future__ import annotations

import html
from dataclasses import dataclass, field

from thermaxis.reports.html import REPORT_CSS, _code_spans, provenance_html, statement_html

__all__ = [
    "IndexRow",
    "IndexSection",
    "render_index",
]


# --------------------------------------------------------------------------- index page


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


PAPER_HEADLINE = (
    "Reproduction of Xu et al., decoupling and step-by-step modelling of the thermal positioning error of a "
    "linear axis."
)


def render_index(
    dataset_name: str,
    statement: str,
    simulated: bool,
    sections,
    provenance: dict | None = None,
    headline: str = PAPER_HEADLINE,
) -> str:
    """The dataset's ``index.html``: the data statement, then every section's links.

    Parameters
    ----------
    dataset_name : str
    statement : str
        The data statement (:func:`thermaxis.dataset.summary.data_statement`).
    simulated : bool
    sections : iterable of IndexSection
        Links are written as given (relative to the index page); empty sections are left out.
    provenance : dict, optional
        The dataset's provenance record, shown in a table at the end.
    headline : str
        What the page is about, under its title: the paper for a dataset that
        reproduces it, else the dataset's own title or description.

    Returns
    -------
    str
        A complete HTML page with its style inline and nothing loaded from elsewhere.
    """
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1.0">',
        '<link rel="icon" href="data:,">',
        f"<title>thermaxis: {html.escape(dataset_name)}</title>",
        "<style>body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:70em;margin:1.5em auto;"
        f"padding:0 1em;line-height:1.45}}ul.tx-index{{padding-left:1.2em}}{REPORT_CSS}</style>",
        "</head><body>",
        f'<header class="tx-banner {"tx-simulated" if simulated else "tx-measured"}">'
        f"<h1>thermaxis results: {html.escape(dataset_name)}</h1>"
        f'<p class="tx-subtitle">{html.escape(headline)}</p>'
        f"{statement_html(statement, simulated)}</header>",
    ]
    for section in sections:
        if not section.rows:
            continue
        parts.append(f"<section><h2>{html.escape(section.title)}</h2>")
        if section.intro:
            parts.append(f'<p class="tx-note">{_code_spans(section.intro)}</p>')
        parts.append('<ul class="tx-index">')
        for row in section.rows:
            links = " · ".join(
                f'<a href="{html.escape(href, quote=True)}">{html.escape(text)}</a>'
                for text, href in row.links
            )
            note = f' <span class="tx-note">{_code_spans(row.note)}</span>' if row.note else ""
            parts.append(f"<li>{html.escape(row.label)}: {links}{note}</li>")
        parts.append("</ul></section>")
    if provenance is not None:
        parts.append(
            f"<section><h2>Provenance</h2>{provenance_html(provenance, 'provenance.json')}</section>"
        )
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
