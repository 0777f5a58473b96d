"""Helpers of the report notebooks and the index page: HTML pieces, tables, figures, conversion.

The notebooks in ``notebooks/`` read the workflow's tables (nothing is recomputed) and
show them with the functions here, which return HTML strings; :func:`show` displays
them in a notebook.  Every page starts with :func:`banner_html`, whose first screen
carries the data statement (simulated or measured data).

A report rule runs ``python -m thermaxis.reporting run NOTEBOOK EXECUTED HTML ...``:
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

import argparse
import base64
import html
import json
import re
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .naming import sort_naturally
from .formatting import format_cell

__all__ = [
    "REPORT_CSS",
    "IndexRow",
    "IndexSection",
    "load_table",
    "statement_html",
    "banner_html",
    "provenance_html",
    "table_html",
    "figure_png",
    "figure_html",
    "figures_html",
    "plot_html",
    "show",
    "audit_summary",
    "audit_html",
    "cleaning_repairs",
    "temperature_overview",
    "error_overview",
    "strip_volatile",
    "remote_loads",
    "notebook_to_html",
    "convert",
    "execute",
    "render_index",
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
code.tx-hash{font-size:0.85em}
"""

_LINK_TO_INDEX = '<p class="tx-note"><a href="../index.html">All reports and figures of this dataset</a></p>'


# --------------------------------------------------------------------------- tables


def load_table(path) -> pd.DataFrame:
    """Read a table the workflow wrote: ``.csv`` or ``.parquet``."""
    path = Path(path)
    if path.suffix == ".parquet":
        return pd.read_parquet(path)
    if path.suffix == ".csv":
        return pd.read_csv(path)
    raise ValueError(f"{path}: cannot read a {path.suffix or 'suffix-less'} file as a table; expected .csv or .parquet")


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
        :func:`thermaxis.summary.data_statement` of the dataset.
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
    return "unknown" if not digest else f'<code class="tx-hash" title="{digest}">{digest[:n]}</code>'


def provenance_html(record: dict, full_record_href: str | None = "../provenance.json") -> str:
    """A compact table of a :func:`thermaxis.provenance.collect` record.

    The configuration line names the sections the record covers, with one short hash
    each, so it can be matched against ``config_sections_sha256`` of the dataset's
    ``provenance.json`` (which covers the whole configuration).
    """
    git = record.get("git", {})
    if git.get("commit") is None:
        commit = "unknown (not a git checkout)"
    else:
        state = {True: "dirty: uncommitted changes", False: "clean", None: "state unknown"}[git.get("dirty")]
        commit = f"{_short(git['commit'])} ({state})"
    sections = record.get("config_sections_sha256", {})
    config = f"{_short(record.get('config_sha256'))} over sections " + ", ".join(
        f"{html.escape(name)} {_short(digest, 8)}" for name, digest in sorted(sections.items())
    )
    data = record.get("data", {})
    packages = ", ".join(f"{html.escape(k)} {html.escape(str(v))}" for k, v in sorted(record.get("packages", {}).items()) if v)
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
        ("Python", html.escape(f"{python.get('version', '?')} ({python.get('implementation', '?')})")),
        ("Platform", html.escape(" ".join(str(plat.get(k, "")) for k in ("system", "release", "machine")).strip())),
        ("Packages", packages),
        ("Built (UTC)", html.escape(str(record.get("run_time", "")))),
    ]
    body = "".join(f"<tr><th>{name}</th><td>{value}</td></tr>" for name, value in rows)
    link = f' <a href="{html.escape(full_record_href)}">Full record</a>.' if full_record_href else ""
    return f'<table class="tx-table"><caption>Provenance.{link}</caption>{body}</table>'


def _cell_text(value, float_format: str) -> str:
    return html.escape(format_cell(value, float_format))


def table_html(frame: pd.DataFrame, float_format: str = "%.3f", caption: str | None = None, max_rows: int | None = None) -> str:
    """A DataFrame as an HTML table: no index, a fixed float format, numbers right-aligned.

    Missing values are blank.  ``max_rows`` keeps the first rows and says how many were
    left out.
    """
    shown = frame if max_rows is None or len(frame) <= max_rows else frame.head(max_rows)
    numeric = [
        pd.api.types.is_numeric_dtype(dtype) and not pd.api.types.is_bool_dtype(dtype) for dtype in shown.dtypes
    ]
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in shown.columns)
    rows = []
    for values in shown.itertuples(index=False, name=None):
        cells = "".join(
            f'<td class="tx-num">{_cell_text(v, float_format)}</td>' if num else f"<td>{_cell_text(v, float_format)}</td>"
            for v, num in zip(values, numeric)
        )
        rows.append(f"<tr>{cells}</tr>")
    cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
    text = f'<table class="tx-table">{cap}<thead><tr>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table>'
    if len(shown) < len(frame):
        text += f'<p class="tx-note">First {len(shown)} of {len(frame)} rows; the full table is in the CSV.</p>'
    return text


# --------------------------------------------------------------------------- figures


def figure_png(fig, dpi: float = 150) -> bytes:
    """Render a :mod:`thermaxis.plotting` figure to PNG bytes (no time stamps: same figure, same bytes)."""
    from . import plotting

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "figure.png"
        plotting.save_figure(fig, path, dpi=dpi)
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
    return "".join(figure_html(entries[n]["path"], entries[n]["caption"]) for n in names if n in entries)


def plot_html(fig, caption: str, simulated: bool, dpi: float = 150) -> str:
    """A :mod:`thermaxis.plotting` figure drawn in the notebook, stamped like the workflow's when simulated."""
    from . import plotting

    if simulated:
        plotting.stamp_provenance(fig, plotting.SIMULATED_NOTE)
    return figure_html(figure_png(fig, dpi), caption)


def show(*parts: str) -> None:
    """Display HTML strings in the notebook (one output)."""
    from IPython.display import HTML, display

    display(HTML("".join(parts)))


# --------------------------------------------------------------------------- overviews

_REPAIR_COLUMNS = ("n_duplicates", "n_out_of_range", "n_spikes", "n_interpolated", "n_edge_held", "n_long_gap")


def cleaning_repairs(qc: pd.DataFrame) -> pd.DataFrame:
    """The rows of a cleaning QC table where something was repaired, with their total.

    Parameters
    ----------
    qc : pandas.DataFrame
        ``tables/cleaning_qc.csv`` (one row per run and sensor).

    Returns
    -------
    pandas.DataFrame
        run, sensor, source, the repair counts and ``repaired`` (their sum), only rows
        with ``repaired > 0``, sorted by run and sensor.
    """
    missing = [c for c in ("run", "sensor", "source", *_REPAIR_COLUMNS) if c not in qc.columns]
    if missing:
        raise ValueError(f"cleaning QC table lacks column(s) {', '.join(missing)}; expected the columns of tables/cleaning_qc.csv")
    table = qc[["run", "sensor", "source", *_REPAIR_COLUMNS]].copy()
    table["repaired"] = table[list(_REPAIR_COLUMNS)].sum(axis=1)
    return sort_naturally(table[table["repaired"] > 0], ["run", "sensor"])


def temperature_overview(temperatures: pd.DataFrame) -> pd.DataFrame:
    """Per run and sensor: absolute temperature at the first and last measurement, range, largest rise.

    ``temperatures`` is ``assembled/temperatures.parquet`` (or a run's
    ``measurement_temperatures.parquet``): run, measurement, sensor, absolute_c, relative_c.
    """
    t = sort_naturally(temperatures, ["run", "sensor", "measurement"])
    grouped = t.groupby(["run", "sensor"], sort=True)
    return pd.DataFrame(
        {
            "first_c": grouped["absolute_c"].first(),
            "last_c": grouped["absolute_c"].last(),
            "min_c": grouped["absolute_c"].min(),
            "max_c": grouped["absolute_c"].max(),
            "max_rise_c": grouped["relative_c"].max(),
        }
    ).reset_index().pipe(sort_naturally, ["run", "sensor"])


def error_overview(errors: pd.DataFrame) -> pd.DataFrame:
    """Per run: measurements, targets, range of the unzeroed error and of the re-zeroed error.

    ``errors`` is ``assembled/errors.parquet``: run, measurement, position_mm, error_um, rezeroed_um.
    """
    grouped = errors.groupby("run", sort=True)
    return pd.DataFrame(
        {
            "measurements": grouped["measurement"].nunique(),
            "positions": grouped["position_mm"].nunique(),
            "error_min_um": grouped["error_um"].min(),
            "error_max_um": grouped["error_um"].max(),
            "rezeroed_min_um": grouped["rezeroed_um"].min(),
            "rezeroed_max_um": grouped["rezeroed_um"].max(),
        }
    ).reset_index()


_AUDIT_COLUMNS = ["item", "quantity", "unit", "published", "reproduced", "difference", "note"]


def audit_summary(comparison: pd.DataFrame) -> pd.DataFrame:
    """Per table of the paper: how many numbers, how many reproduced, mean and largest |difference|.

    ``comparison`` is ``tables/paper_comparison.csv``.
    """
    table = comparison.assign(abs_difference=comparison["difference"].abs())
    grouped = table.groupby("table", sort=True)
    return pd.DataFrame(
        {
            "items": grouped["item"].size(),
            "reproduced": grouped["reproduced"].count(),
            "mean_abs_difference": grouped["abs_difference"].mean(),
            "max_abs_difference": grouped["abs_difference"].max(),
        }
    ).reset_index()


def audit_html(comparison: pd.DataFrame, *tables: str, caption: str | None = None, max_rows: int | None = None) -> str:
    """The audit rows of some tables of the paper (``"table4"``, ``"eq9"``, ...): published beside reproduced."""
    rows = comparison[comparison["table"].isin(tables)][_AUDIT_COLUMNS]
    if rows.empty:
        return f'<p class="tx-note">The audit has no number of {", ".join(tables)}.</p>'
    return table_html(rows, "%.3f", caption=caption or f"Audit of {', '.join(tables)}: published and reproduced", max_rows=max_rows)


# --------------------------------------------------------------------------- conversion

_VOLATILE_KEYS = ("start_time", "end_time", "duration")

# The JupyterLab template without the blocks that load require.js, MathJax, mermaid
# and widget managers from a CDN; its CSS is inlined by nbconvert. The empty icon
# keeps browsers from requesting /favicon.ico (a 404 in the console when served).
_TEMPLATE = """{%- extends 'index.html.j2' -%}
{%- block html_head_js -%}<link rel="icon" href="data:,">{%- endblock html_head_js -%}
{%- block html_head_js_mathjax -%}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
{%- block jupyter_widgets -%}{%- endblock jupyter_widgets -%}
"""


def strip_volatile(nb: dict) -> dict:
    """Drop what differs between two executions of the same notebook on the same inputs.

    Removes papermill's and nbclient's time stamps (notebook and cell metadata) and
    gives papermill's injected parameters cell a fixed id.  ``nb`` is changed in place
    and returned.
    """
    meta = nb.get("metadata", {}).get("papermill")
    if isinstance(meta, dict):
        for key in _VOLATILE_KEYS:
            meta.pop(key, None)
    for i, cell in enumerate(nb.get("cells", [])):
        cell_meta = cell.get("metadata", {})
        cell_meta.pop("execution", None)
        if isinstance(cell_meta.get("papermill"), dict):
            for key in _VOLATILE_KEYS:
                cell_meta["papermill"].pop(key, None)
        if "injected-parameters" in cell_meta.get("tags", []):
            cell["id"] = "injected-parameters"
    return nb


_REMOTE = re.compile(
    r"""<(?:script|img|iframe|source|video|audio|embed)\b[^>]*\bsrc\s*=\s*["']?\s*(?:https?:)?//[^"'\s>]+"""
    r"""|<link\b[^>]*\bhref\s*=\s*["']?\s*(?:https?:)?//[^"'\s>]+"""
    r"""|@import\s+(?:url\()?\s*["']?\s*(?:https?:)?//[^"')\s;]+"""
    r"""|url\(\s*["']?\s*(?:https?:)?//[^"')\s]+""",
    re.IGNORECASE,
)


def remote_loads(text: str) -> list[str]:
    """Every place where an HTML page would load something from the network.

    Scripts, images, frames and media with a remote ``src``, stylesheets (``<link
    href>``), CSS ``@import`` and ``url()``.  Plain hyperlinks (``<a href>``) are not
    loads and are not reported.
    """
    return [m.group(0) for m in _REMOTE.finditer(text)]


def notebook_to_html(nb, title: str) -> str:
    """HTML of an executed notebook: outputs and Markdown only (code hidden), nothing remote.

    Raises
    ------
    ValueError
        If the page would still load something from the network.
    """
    import jinja2
    from nbconvert import HTMLExporter

    exporter = HTMLExporter(
        template_name="lab",
        extra_loaders=[jinja2.DictLoader({"thermaxis.html.j2": _TEMPLATE})],
        template_file="thermaxis.html.j2",
        exclude_input=True,
        exclude_input_prompt=True,
        exclude_output_prompt=True,
    )
    nb.metadata["title"] = title  # the template prefers it to the resource name
    body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": title}})
    remote = remote_loads(body)
    if remote:
        raise ValueError(f"report {title!r} would load {remote[0]!r} from the network; expected a self-contained page")
    return body


def convert(notebook_path, html_path, title: str) -> None:
    """Normalise an executed notebook in place (:func:`strip_volatile`) and write its HTML."""
    import nbformat

    from .runner import write_text

    nb = nbformat.read(str(notebook_path), as_version=4)
    strip_volatile(nb)
    page = notebook_to_html(nb, title)
    write_text(nbformat.writes(nb) + "\n", notebook_path)
    write_text(page, html_path)


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
        The data statement (:func:`thermaxis.summary.data_statement`).
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
            links = " · ".join(f'<a href="{html.escape(href, quote=True)}">{html.escape(text)}</a>' for text, href in row.links)
            note = f' <span class="tx-note">{_code_spans(row.note)}</span>' if row.note else ""
            parts.append(f"<li>{html.escape(row.label)}: {links}{note}</li>")
        parts.append("</ul></section>")
    if provenance is not None:
        parts.append(f"<section><h2>Provenance</h2>{provenance_html(provenance, 'provenance.json')}</section>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


# --------------------------------------------------------------------------- command line


def execute(
    notebook,
    executed,
    html_path,
    title: str,
    parameters: dict,
    kernel: str = "python3",
    start_timeout: float = 120,
    execution_timeout: float = 600,
) -> None:
    """Execute a report notebook with papermill, then :func:`convert` it to HTML.

    Parameters
    ----------
    notebook, executed, html_path : str or os.PathLike
        The clean notebook, the executed notebook to write, the HTML to write.
    title : str
        Title of the HTML page.
    parameters : dict
        Values for the notebook's ``parameters`` cell.
    kernel : str
        Jupyter kernel name.
    start_timeout, execution_timeout : float
        Seconds the kernel may take to start, and any one cell to run.
    """
    import papermill

    papermill.execute_notebook(
        str(notebook),
        str(executed),
        parameters=parameters,
        kernel_name=kernel,
        start_timeout=start_timeout,
        execution_timeout=execution_timeout,
        progress_bar=False,
    )
    convert(executed, html_path, title)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m thermaxis.reporting", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="execute a report notebook with papermill and write its HTML")
    run.add_argument("notebook")
    run.add_argument("executed")
    run.add_argument("html")
    run.add_argument("--title", required=True)
    run.add_argument("--parameters", default="{}", help="JSON object of notebook parameters")
    run.add_argument("--kernel", default="python3")
    run.add_argument("--start-timeout", type=float, default=120)
    run.add_argument("--execution-timeout", type=float, default=600)
    to_html = sub.add_parser("html", help="normalise an executed notebook and write its self-contained HTML")
    to_html.add_argument("notebook")
    to_html.add_argument("html")
    to_html.add_argument("--title", required=True)
    args = parser.parse_args(argv)
    try:
        if args.command == "run":
            execute(
                args.notebook,
                args.executed,
                args.html,
                args.title,
                json.loads(args.parameters),
                kernel=args.kernel,
                start_timeout=args.start_timeout,
                execution_timeout=args.execution_timeout,
            )
        else:
            convert(args.notebook, args.html, args.title)
    except (OSError, ValueError) as exc:
        print(f"thermaxis error: {str(exc).splitlines()[0]}", file=sys.stderr)
        return 1
    except Exception as exc:  # papermill's execution error: the traceback of the failing cell
        print(exc, file=sys.stderr)
        print(f"thermaxis error: {args.notebook}: {type(exc).__name__} while executing the notebook", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
