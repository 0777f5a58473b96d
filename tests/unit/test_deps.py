"""Library modules of a script, from its imports (what the rules list as code inputs)."""

from pathlib import Path

from thermaxis.pipeline.deps import PACKAGE, library_modules

REPO = Path(__file__).resolve().parents[2]


def names(entry):
    return {Path(p).relative_to(PACKAGE).as_posix() for p in library_modules(entry)}


def test_models_script_reaches_the_method_through_the_folds():
    # models.py imports cleaning.run, method.folds and pipeline.runner; the folds import
    # models, selection, decouple and metrics (read off the files' import lines by hand).
    found = names(REPO / "workflow/scripts/models.py")
    assert {
        "cleaning/run.py",
        "method/folds.py",
        "pipeline/runner.py",
        "method/models.py",
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


def test_the_statement_walk_finds_every_import_ast_walk_finds():
    import ast
    import json

    from thermaxis.pipeline import deps

    sources = [
        *PACKAGE.rglob("*.py"),
        *(REPO / "workflow" / "scripts").glob("*.py"),
        *(REPO / "notebooks").glob("*.ipynb"),
    ]
    for path in sources:
        if path.suffix == ".ipynb":
            cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
            text = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
        else:
            text = path.read_text(encoding="utf-8")
        tree = ast.parse(text)
        every = [n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))]
        found = [
            n for n in deps._statements(tree.body) if isinstance(n, (ast.Import, ast.ImportFrom))
        ]
        assert len(found) == len(every), path
