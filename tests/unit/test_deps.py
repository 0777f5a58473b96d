"""Library modules of a script, from its imports (what the rules list as code inputs)."""

from pathlib import Path

from thermaxis.pipeline.deps import PACKAGE, library_modules

REPO = Path(__file__).resolve().parents[2]


def names(entry):
    return {Path(p).relative_to(PACKAGE).as_posix() for p in library_modules(entry)}


def test_models_script_reaches_the_method_through_the_folds():
    # models.py imports cleaning.run, method.folds and pipeline.runner; the folds import
    # the estimators (and through them regressors and search), selection, decouple and
    # metrics (read off the files' import lines by hand).
    found = names(REPO / "workflow/scripts/models.py")
    assert {
        "cleaning/run.py",
        "method/folds.py",
        "pipeline/runner.py",
        "method/estimators.py",
        "method/regressors.py",
        "method/search.py",
        "method/selection.py",
        "method/decouple.py",
        "method/metrics.py",
    } <= found
    assert not {p for p in found if p.startswith(("figures/", "paper/"))}


def test_notebook_code_cells_count(tmp_path):
    notebook = tmp_path / "n.ipynb"
    notebook.write_text(
        '{"cells": [{"cell_type": "code", "source": ["from thermaxis.paper import published\\n"]},'
        ' {"cell_type": "markdown", "source": ["import thermaxis.figures.paper"]}]}'
    )
    found = names(notebook)
    assert "paper/published.py" in found and "figures/paper.py" not in found


def test_the_import_scan_reads_lists_aliases_relative_and_lazy_imports():
    from thermaxis.pipeline.deps import _imported

    source = (
        "import numpy as np, thermaxis.config\n"
        "from . import fit\n"
        "from ..method.folds import (\n"
        "    FoldResult,  # a comment\n"
        "    select_for_fold as select,\n"
        ")\n"
        "def f():\n"
        "    from thermaxis.paper import published\n"
    )
    # By hand: relative to package thermaxis.twin, "." is thermaxis.twin, ".." thermaxis.
    assert _imported(source, "thermaxis.twin") == {
        "numpy",
        "thermaxis.config",
        "thermaxis.twin",
        "thermaxis.twin.fit",
        "thermaxis.method.folds",
        "thermaxis.method.folds.FoldResult",
        "thermaxis.method.folds.select_for_fold",
        "thermaxis.paper",
        "thermaxis.paper.published",
    }


def test_the_import_scan_finds_every_import_the_python_parser_finds():
    import ast

    from thermaxis.pipeline import deps

    sources = [
        *PACKAGE.rglob("*.py"),
        *(REPO / "workflow" / "scripts").glob("*.py"),
        *(REPO / "notebooks").glob("*.ipynb"),
    ]
    for path in sources:
        text = deps._source(path)
        package = deps._package_of(path) if PACKAGE in path.parents else None
        scanned = deps._imported(text, package)
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Import):
                assert {a.name for a in node.names} <= scanned, (path, node.lineno)
            elif isinstance(node, ast.ImportFrom) and not node.level:
                names = {f"{node.module}.{a.name}" for a in node.names} | {node.module}
                assert names <= scanned, (path, node.lineno)
