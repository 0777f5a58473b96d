"""Library modules of a script, from its imports (what the rules list as code inputs)."""

from pathlib import Path

from thermaxis.deps import library_modules

REPO = Path(__file__).resolve().parents[2]


def names(entry):
    return {Path(p).name for p in library_modules(REPO / entry)}


def test_selection_script_reaches_models_through_experiment():
    # select.py imports assemble, experiment and runner; experiment imports models,
    # selection, decouple and evaluate (read off the files' import lines by hand).
    found = names("workflow/scripts/select.py")
    assert {"assemble.py", "experiment.py", "runner.py", "models.py", "selection.py", "decouple.py", "evaluate.py"} <= found
    assert "plotting.py" not in found and "audit.py" not in found


def test_notebook_code_cells_count(tmp_path):
    notebook = tmp_path / "n.ipynb"
    notebook.write_text(
        '{"cells": [{"cell_type": "code", "source": ["from thermaxis import paper\\n"]},'
        ' {"cell_type": "markdown", "source": ["import thermaxis.plotting"]}]}'
    )
    found = {Path(p).name for p in library_modules(notebook)}
    assert "paper.py" in found and "plotting.py" not in found
