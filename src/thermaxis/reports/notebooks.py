"""Running a report notebook: papermill execution, volatile-field stripping and self-contained HTML.

``python -m thermaxis.reports.notebooks run NOTEBOOK OUT.ipynb OUT.html ...`` executes and converts in one process;
``run-pages NOTEBOOK --pages JSON`` executes one notebook once per page (a condition, a fold) in one
kernel, its namespace reset between pages, so the kernel and the imports start once per report kind.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import os
import re
import sys
import tempfile

__all__ = [
    "strip_volatile",
    "remote_loads",
    "notebook_to_html",
    "json_argument",
    "convert",
    "execute",
    "execute_pages",
    "clear_page_names",
]


# --------------------------------------------------------------------------- conversion

_VOLATILE_KEYS = ("start_time", "end_time", "duration")

# The JupyterLab template without the blocks that load require.js, MathJax, mermaid
# and widget managers from a CDN; its CSS is inlined by nbconvert. The empty icon
# keeps browsers from requesting /favicon.ico (a 404 in the console when served).
# Every HTML output (all a report shows) is focusable, as nbconvert's own pass over the
# finished page makes it (_exporter).
_TEMPLATE = """{%- extends 'index.html.j2' -%}
{%- block html_head_js -%}<link rel="icon" href="data:,">{%- endblock html_head_js -%}
{%- block html_head_js_mathjax -%}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
{%- block jupyter_widgets -%}{%- endblock jupyter_widgets -%}
{% block data_html scoped -%}
<div class="jp-RenderedHTMLCommon jp-RenderedHTML jp-OutputArea-output {{ extra_class }}" \
data-mime-type="text/html" tabindex="0">
{{ output.data['text/html'] }}
</div>
{%- endblock data_html %}
"""


def strip_volatile(nb: dict) -> dict:
    """Drop what differs between two executions of the same notebook on the same inputs.

    Removes papermill's and nbclient's time stamps (notebook and cell metadata), numbers
    the executed cells from 1 and gives papermill's injected parameters cell a fixed id.  ``nb`` is changed in place
    and returned.
    """
    meta = nb.get("metadata", {}).get("papermill")
    if isinstance(meta, dict):
        for key in _VOLATILE_KEYS:
            meta.pop(key, None)
    # Counted from 1 as a fresh kernel counts, whichever page of a shared kernel this was.
    executed = (c for c in nb.get("cells", []) if c.get("execution_count") is not None)
    for count, cell in enumerate(executed, start=1):
        cell["execution_count"] = count
        for output in cell.get("outputs", []):
            if "execution_count" in output:
                output["execution_count"] = count
    for cell in nb.get("cells", []):
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


@functools.cache
def _exporter():
    """One exporter per process: its templates load once for every page of a report.

    nbconvert's HTMLExporter parses every page it renders again with BeautifulSoup, to give
    images without alternative text a placeholder and to make outputs focusable: more
    than half of a page's conversion (0.1-0.3 s a page, 0.2 s more for a process's
    first). Here
    every image has its text (:func:`thermaxis.reports.html.figure_html`) and the template
    makes the outputs focusable (``_TEMPLATE``), so the page is the template's rendering,
    with HTMLExporter's two filters (the data type without widgets: reports have none).
    """
    import jinja2
    from nbconvert import HTMLExporter
    from nbconvert.exporters.templateexporter import TemplateExporter
    from nbconvert.filters import DataTypeFilter, Highlight2HTML

    class PageExporter(HTMLExporter):
        def from_notebook_node(self, nb, resources=None, **kw):
            language = nb.metadata.get("language_info", {})
            lexer = language.get("pygments_lexer", language.get("name"))
            self.register_filter(
                "highlight_code", Highlight2HTML(pygments_lexer=lexer, parent=self)
            )
            self.register_filter("filter_data_type", DataTypeFilter(parent=self))
            return TemplateExporter.from_notebook_node(self, nb, resources, **kw)

    return PageExporter(
        template_name="lab",
        extra_loaders=[jinja2.DictLoader({"thermaxis.html.j2": _TEMPLATE})],
        template_file="thermaxis.html.j2",
        exclude_input=True,
        exclude_input_prompt=True,
        exclude_output_prompt=True,
    )


def notebook_to_html(nb, title: str) -> str:
    """HTML of an executed notebook: outputs and Markdown only (code hidden), nothing remote.

    Raises
    ------
    ValueError
        If the page would still load something from the network.
    """
    exporter = _exporter()
    nb.metadata["title"] = title  # the template prefers it to the resource name
    body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": title}})
    remote = remote_loads(body)
    if remote:
        raise ValueError(
            f"report {title!r} would load {remote[0]!r} from the network; expected a self-contained page"
        )
    return body


def convert(notebook_path, html_path, title: str) -> None:
    """Normalise an executed notebook in place (:func:`strip_volatile`) and write its HTML."""
    import nbformat

    from thermaxis.pipeline.runner import write_text

    nb = nbformat.read(str(notebook_path), as_version=4)
    strip_volatile(nb)
    page = notebook_to_html(nb, title)
    write_text(nbformat.writes(nb) + "\n", notebook_path)
    write_text(page, html_path)


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
    page = {"executed": executed, "html": html_path, "title": title, "parameters": parameters}
    execute_pages(notebook, [page], kernel, start_timeout, execution_timeout)


def clear_page_names(shell) -> None:
    """Delete every name a page defined in the IPython ``shell`` of its kernel: imports and
    names with a leading underscore too, nothing IPython keeps (its hidden names, the
    dunders).

    This is what ``%reset`` clears of the namespace, without its two garbage collections,
    which cost 0.2 s a page in a kernel holding pandas and matplotlib; ``%reset_selective``
    would keep the underscored names.
    """
    hidden, absent = shell.user_ns_hidden, object()
    for name, value in list(shell.user_ns.items()):
        dunder = name.startswith("__") and name.endswith("__")
        if not dunder and hidden.get(name, absent) is not value:
            del shell.user_ns[name]


def execute_pages(
    notebook,
    pages: list[dict],
    kernel: str = "python3",
    start_timeout: float = 120,
    execution_timeout: float = 600,
) -> None:
    """Execute one report notebook once per page in one kernel, each with papermill.

    ``pages`` are dicts of ``executed``, ``html``, ``title`` and ``parameters``, as
    :func:`execute` takes them. Every name a page defined is deleted before the next
    (:func:`clear_page_names`): a page sees only its own parameters, and the modules the
    first page imported stay loaded. Each page is converted to HTML before the next one
    runs.
    """
    import nbformat
    import papermill
    from nbclient import NotebookClient

    reset = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_code_cell(
                "import thermaxis.reports.notebooks as _page\n_page.clear_page_names(get_ipython())"
            )
        ]
    )
    with _private_kernel(kernel) as km:
        for number, page in enumerate(pages):
            if number:
                # The kernel's own client runs the reset, as it runs a notebook's cells.
                NotebookClient(
                    reset, km=km, timeout=execution_timeout, startup_timeout=start_timeout
                ).execute()
            papermill.execute_notebook(
                str(notebook),
                str(page["executed"]),
                parameters=page["parameters"],
                kernel_name=kernel,
                km=km,
                start_timeout=start_timeout,
                execution_timeout=execution_timeout,
                progress_bar=False,
                # Written once, when the page is done (or has failed), not twice per
                # cell: a page with its figures is a megabyte of JSON.
                request_save_on_cell_execute=False,
            )
            convert(page["executed"], page["html"], page["title"])


@contextlib.contextmanager
def _private_kernel(kernel: str):
    """A started kernel that talks over IPC sockets in a folder of its own, shut down after.

    Over TCP, jupyter_client picks free ports and the kernel binds them later; a process
    that takes one in between kills the kernel at start (papermill#511, jupyter_client#154),
    and a test suite or a cluster node starts kernels beside many other processes. Socket
    files in a fresh temporary folder cannot be taken by anyone else.
    """
    from jupyter_client.manager import KernelManager

    with tempfile.TemporaryDirectory(prefix="thermaxis-kernel-", dir=_socket_parent()) as folder:
        km = KernelManager(
            kernel_name=kernel,
            transport="ipc",
            ip=os.path.join(folder, "socket"),
            connection_file=os.path.join(folder, "connection.json"),
        )
        km.start_kernel()
        try:
            yield km
        finally:
            km.shutdown_kernel(now=True)


# A Unix socket's path holds at most 107 bytes (Linux; 103 on macOS); the kernel's are
# "<folder>/socket-<n>". A cluster's per-job TMPDIR can be deep enough to pass that.
_SOCKET_PATH_MAX = 100


def _socket_parent() -> str | None:
    """The temporary folder's parent: the system's, unless its sockets' paths would be too long."""
    default = tempfile.gettempdir()
    room = _SOCKET_PATH_MAX - len("/thermaxis-kernel-xxxxxxxx/socket-99999")
    return None if len(os.fsencode(default)) <= room else "/tmp"


def json_argument(value: str, stdin=None):
    """A JSON command-line value, or with ``-`` the JSON on standard input.

    The workflow passes its report parameters on standard input: a record of many runs
    lists more files than one command line holds (Linux caps one argument at 128 KiB).
    """
    return json.loads((stdin or sys.stdin).read() if value == "-" else value)


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "run":
            execute(
                args.notebook,
                args.executed,
                args.html,
                args.title,
                json_argument(args.parameters),
                kernel=args.kernel,
                start_timeout=args.start_timeout,
                execution_timeout=args.execution_timeout,
            )
        elif args.command == "run-pages":
            execute_pages(
                args.notebook,
                json_argument(args.pages),
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
        print(
            f"thermaxis error: {args.notebook}: {type(exc).__name__} while executing the notebook",
            file=sys.stderr,
        )
        return 1
    return 0


def _parser() -> argparse.ArgumentParser:
    """The subcommands run, run-pages and html, as the workflow's rules call them."""
    parser = argparse.ArgumentParser(
        prog="python -m thermaxis.reports.notebooks", description=__doc__.splitlines()[0]
    )
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="execute a report notebook with papermill and write its HTML")
    run.add_argument("notebook")
    run.add_argument("executed")
    run.add_argument("html")
    run.add_argument("--title", required=True)
    run.add_argument(
        "--parameters", default="{}", help="JSON object of notebook parameters, or - for stdin"
    )
    run.add_argument("--kernel", default="python3")
    run.add_argument("--start-timeout", type=float, default=120)
    run.add_argument("--execution-timeout", type=float, default=600)
    many = sub.add_parser(
        "run-pages",
        help="execute a report notebook once per page in one kernel, and write each HTML",
    )
    many.add_argument("notebook")
    many.add_argument(
        "--pages",
        required=True,
        help="JSON list of {executed, html, title, parameters}, one per page, or - for stdin",
    )
    many.add_argument("--kernel", default="python3")
    many.add_argument("--start-timeout", type=float, default=120)
    many.add_argument("--execution-timeout", type=float, default=600)
    to_html = sub.add_parser(
        "html", help="normalise an executed notebook and write its self-contained HTML"
    )
    to_html.add_argument("notebook")
    to_html.add_argument("html")
    to_html.add_argument("--title", required=True)
    return parser


if __name__ == "__main__":
    sys.exit(main())
