"""Helpers of the report notebooks and the index page: HTML pieces, tables, figures, conversion.

The notebooks in ``notebooks/`` read the workflow's tables (nothing is recomputed) and
show them with the functions here, which return HTML strings; :func:`show` displays
them in a notebook.  Every page starts with :func:`banner_html`, whose first screen
carries the data statement (simulated or measured data).

A report rule runs ``python -m thermaxis.reports.notebooks run NOTEBOOK EXECUTED HTML ...``:
:func:`execute` has papermill execute the notebook with the given parameters in a
``python3`` kernel (explicit start and execution timeouts) and :func:`convert` turns it
into HTML.  One process instead of the ``papermill`` and ``jupyter nbconvert``
commands saves an interpreter start and the imports of nbformat and nbconvert per
report.  The HTML is written by :func:`convert` rather than by ``jupyter nbconvert``
for two more reasons:

* the HTML must load nothing from the network: the JupyterLab template of nbconvert
  pulls require.js, MathJax and mermaid from a CDN, so the template below drops those
  script blocks (the reports use neither widgets, LaTeX nor diagrams) and the result
  is checked with :func:`remote_loads`;
* the executed notebook must be the same bytes for the same inputs: papermill and
  nbclient record start/end times and give the injected parameters cell a random id,
  which :func:`strip_volatile` removes before both files are written.
"""

from __future__ import annotations

import base64
import html
import re
import tempfile
from pathlib import Path

import pandas as pd

from thermaxis.tables import format_cell, read_table

__all__ = [
    "REPORT_CSS",
    "load_table",
    "statement_html",
    "banner_html",
    "provenance_html",
    "table_html",
    "SORT_SCRIPT",
    "figure_png",
    "figure_html",
    "figures_html",
    "plot_html",
    "show",
]

REPORT_CSS = """
.tx-banner{border:3px solid #b45309;background:#fff7ed;padding:0.8em 1.2em;margin:0 0 1.2em 0;border-radius:6px}
.tx-banner.tx-measured{border-color:#1d4ed8;background:#eff6ff}
.tx-banner h1{margin:0 0 0.3em 0;font-size:1.7em}
.tx-banner .tx-subtitle{margin:0 0 0.5em 0;color:#374151}
.tx-statement{font-size:1.15em;margin:0.3em 0 0 0}
.tx-flag{display:inline-block;font-weight:bold;color:#fff;background:#b45309;padding:0.1em 0.5em;border-radius:4px;margin-right:0.5em}
.tx-measured .tx-flag{background:#1d4ed8}
table.tx-table{border-collapse:collapse;margin:0.5em 0 1em 0;font-size:0.9em}
/* !important: JupyterLab's CSS right-aligns every cell of rendered HTML with a more specific selector */
table.tx-table th,table.tx-table td{border:1px solid #d1d5db;padding:0.2em 0.6em;text-align:left!important}
table.tx-table td.tx-num{text-align:right!important;font-variant-numeric:tabular-nums}
table.tx-table th{background:#f3f4f6}
table.tx-table caption{caption-side:top;text-align:left;font-weight:bold;padding:0.2em 0}
figure.tx-figure{margin:0.8em 0 1.5em 0}
figure.tx-figure img{max-width:100%;height:auto;border:1px solid #e5e7eb}
figure.tx-figure figcaption{font-size:0.9em;color:#374151;max-width:60em}
.tx-note{color:#4b5563;font-style:italic}
.tx-lead{font-size:1.15em;max-width:60em}
code.tx-hash{font-size:0.85em}
"""

_LINK_TO_INDEX = (
    '<p class="tx-note"><a href="../index.html">All reports and figures of this dataset</a></p>'
)


# --------------------------------------------------------------------------- tables


def load_table(path) -> pd.DataFrame:
    """Read a table the workflow wrote: ``.csv`` or ``.parquet``."""
    path = Path(path)
    if path.suffix == ".parquet":
        return pd.read_parquet(path)
    if path.suffix == ".csv":
        return read_table(path)
    raise ValueError(
        f"{path}: cannot read a {path.suffix or 'suffix-less'} file as a table; expected .csv or .parquet"
    )


def _code_spans(text: str) -> str:
    """Escape ``text`` and turn Markdown `code` spans (the data statement uses them) into <code>."""
    return re.sub(r"`([^`]+)`", r"<code>\1</code>", html.escape(text))


def statement_html(statement: str, simulated: bool) -> str:
    """The data statement as one emphasised paragraph, flagged SIMULATED or MEASURED."""
    flag = "SIMULATED DATA" if simulated else "MEASURED DATA"
    return f'<p class="tx-statement"><span class="tx-flag">{flag}</span><strong>{_code_spans(statement)}</strong></p>'


def banner_html(title: str, statement: str, simulated: bool, subtitle: str = "") -> str:
    """First screen of every report: styles, title, optional subtitle and the data statement.

    Parameters
    ----------
    title : str
        The report's heading.
    statement : str
        :func:`thermaxis.dataset.summary.data_statement` of the dataset.
    simulated : bool
        Whether the data are simulated (the banner's colour and flag).
    subtitle : str, optional
        One line under the title.
    """
    kind = "tx-simulated" if simulated else "tx-measured"
    sub = f'<p class="tx-subtitle">{_code_spans(subtitle)}</p>' if subtitle else ""
    return (
        f"<style>{REPORT_CSS}</style>"
        f'<header class="tx-banner {kind}"><h1>{html.escape(title)}</h1>{sub}'
        f"{statement_html(statement, simulated)}</header>{_LINK_TO_INDEX}"
    )


def _short(digest: str | None, n: int = 12) -> str:
    return (
        "unknown" if not digest else f'<code class="tx-hash" title="{digest}">{digest[:n]}</code>'
    )


def provenance_html(record: dict, full_record_href: str | None = "../provenance.json") -> str:
    """A compact table of a :func:`thermaxis.reports.provenance.collect` record.

    The configuration line names the sections the record covers, with one short hash
    each, so it can be matched against ``config_sections_sha256`` of the dataset's
    ``provenance.json`` (which covers the whole configuration).
    """
    git = record.get("git", {})
    if git.get("commit") is None:
        commit = "unknown (not a git checkout)"
    else:
        state = {True: "dirty: uncommitted changes", False: "clean", None: "state unknown"}[
            git.get("dirty")
        ]
        commit = f"{_short(git['commit'])} ({state})"
    sections = record.get("config_sections_sha256", {})
    config = f"{_short(record.get('config_sha256'))} over sections " + ", ".join(
        f"{html.escape(name)} {_short(digest, 8)}" for name, digest in sorted(sections.items())
    )
    data = record.get("data", {})
    packages = ", ".join(
        f"{html.escape(k)} {html.escape(str(v))}"
        for k, v in sorted(record.get("packages", {}).items())
        if v
    )
    python = record.get("python", {})
    plat = record.get("platform", {})
    rows = [
        ("Code (git commit)", commit),
        ("Configuration (SHA-256)", config),
        (
            "Raw data",
            f"<code>{html.escape(str(data.get('root', '')))}</code>: {data.get('n_files', 0)} files, "
            f"manifest {_short(data.get('manifest_sha256'))}",
        ),
        (
            "Python",
            html.escape(f"{python.get('version', '?')} ({python.get('implementation', '?')})"),
        ),
        (
            "Platform",
            html.escape(
                " ".join(str(plat.get(k, "")) for k in ("system", "release", "machine")).strip()
            ),
        ),
        ("Packages", packages),
        ("Built (UTC)", html.escape(str(record.get("run_time", "")))),
    ]
    body = "".join(f"<tr><th>{name}</th><td>{value}</td></tr>" for name, value in rows)
    link = (
        f' <a href="{html.escape(full_record_href)}">Full record</a>.' if full_record_href else ""
    )
    return f'<table class="tx-table"><caption>Provenance.{link}</caption>{body}</table>'


def _cell_text(value, float_format: str) -> str:
    return html.escape(format_cell(value, float_format))


def _number_attr(value) -> str:
    """The full-precision value a sortable column sorts by (and a test can read back)."""
    if pd.isna(value):
        return ""
    return f' data-value="{float(value)!r}"'


def table_html(
    frame: pd.DataFrame,
    float_format: str = "%.3f",
    caption: str | None = None,
    max_rows: int | None = None,
    sortable: bool = False,
) -> str:
    """A DataFrame as an HTML table: no index, a fixed float format, numbers right-aligned.

    Missing values are blank.  ``max_rows`` keeps the first rows and says how many were
    left out.  A ``sortable`` table carries each number's full value for
    :data:`SORT_SCRIPT`, which sorts it by a click on a header.
    """
    shown = frame if max_rows is None or len(frame) <= max_rows else frame.head(max_rows)
    numeric = [
        pd.api.types.is_numeric_dtype(dtype) and not pd.api.types.is_bool_dtype(dtype)
        for dtype in shown.dtypes
    ]
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in shown.columns)
    rows = []
    for values in shown.itertuples(index=False, name=None):
        cells = "".join(
            f'<td class="tx-num"{_number_attr(v) if sortable else ""}>{_cell_text(v, float_format)}</td>'
            if num
            else f"<td>{_cell_text(v, float_format)}</td>"
            for v, num in zip(values, numeric, strict=False)
        )
        rows.append(f"<tr>{cells}</tr>")
    cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
    kind = "tx-table tx-sortable" if sortable else "tx-table"
    text = f'<table class="{kind}">{cap}<thead><tr>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table>'
    if len(shown) < len(frame):
        text += f'<p class="tx-note">First {len(shown)} of {len(frame)} rows; the full table is in the CSV.</p>'
    return text


# Inline, so a page loads nothing from elsewhere; without JavaScript the tables read as written.
SORT_SCRIPT = """
document.querySelectorAll("table.tx-sortable").forEach(function (table) {
  table.querySelectorAll("thead th").forEach(function (th, column) {
    th.title = "click to sort";
    th.style.cursor = "pointer";
    th.addEventListener("click", function () {
      var body = table.tBodies[0];
      var rows = Array.prototype.slice.call(body.rows);
      var up = th.getAttribute("aria-sort") !== "ascending";
      table.querySelectorAll("thead th").forEach(function (h) { h.removeAttribute("aria-sort"); });
      th.setAttribute("aria-sort", up ? "ascending" : "descending");
      function key(row) {
        var cell = row.cells[column];
        var v = cell.getAttribute("data-value");
        return v === null ? cell.textContent : parseFloat(v);
      }
      rows.sort(function (a, b) {
        var x = key(a), y = key(b);
        var order = (typeof x === "number" && typeof y === "number") ? x - y : String(x).localeCompare(String(y));
        return up ? order : -order;
      });
      rows.forEach(function (row) { body.appendChild(row); });
    });
  });
});
"""


# --------------------------------------------------------------------------- figures


def figure_png(fig, dpi: float = 150) -> bytes:
    """Render a :mod:`thermaxis.figures` figure to PNG bytes (no time stamps: same figure, same bytes)."""
    from thermaxis.figures import style

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "figure.png"
        style.save_figure(fig, path, dpi=dpi)
        return path.read_bytes()


_MIME = {".png": "image/png", ".svg": "image/svg+xml"}


def figure_html(source, caption: str = "", alt: str = "") -> str:
    """A figure embedded as a ``data:`` URI, with its caption.

    Parameters
    ----------
    source : bytes or str or os.PathLike
        PNG bytes, or a ``.png`` / ``.svg`` file to embed.  Any other file (a PDF) is
        linked, relative to the report, instead of embedded.
    caption, alt : str
        Caption under the figure; alternative text (default: the caption).
    """
    alt = html.escape(alt or caption or "figure", quote=True)
    cap = f"<figcaption>{_code_spans(caption)}</figcaption>" if caption else ""
    if isinstance(source, (bytes, bytearray)):
        mime, data = "image/png", bytes(source)
    else:
        path = Path(source)
        if path.suffix not in _MIME:
            return f'<figure class="tx-figure"><p><a href="../figures/{html.escape(path.name)}">{html.escape(path.name)}</a></p>{cap}</figure>'
        mime, data = _MIME[path.suffix], path.read_bytes()
    uri = f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"
    return f'<figure class="tx-figure"><img src="{uri}" alt="{alt}">{cap}</figure>'


def figures_html(entries: dict, *names: str) -> str:
    """The figures ``names`` of a ``{name: {"path": ..., "caption": ...}}`` mapping, in order.

    Names missing from ``entries`` are skipped: a dataset with one run has no Fig. 9.
    """
    return "".join(
        figure_html(entries[n]["path"], entries[n]["caption"]) for n in names if n in entries
    )


def plot_html(fig, caption: str, stamp: str | None, dpi: float = 150) -> str:
    """A :mod:`thermaxis.figures` figure drawn in the notebook, stamped as the workflow
    stamps its figures: ``stamp`` is the dataset's
    :func:`~thermaxis.figures.captions.provenance_note` (None for measured data)."""
    from thermaxis.figures import style

    if stamp:
        style.stamp_provenance(fig, stamp)
    return figure_html(figure_png(fig, dpi), caption)


def show(*parts: str) -> None:
    """Display HTML strings in the notebook (one output)."""
    from IPython.display import HTML, display

    display(HTML("".join(parts)))
