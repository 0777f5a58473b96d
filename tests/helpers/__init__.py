"""Shared test helpers, imported as ``helpers`` (pyproject puts ``tests/`` on the path).

Modules by concern:

- ``helpers``: ``REPO`` (the checkout) and ``DEFAULTS`` (every stage's settings from an
  empty config);
- ``helpers.builders``: tiny datasets in the documented raw layout, written from known
  truth, and table edits;
- ``helpers.truth``: the independent truth the builders write and the tests compare with
  (the paper's Eq. 8 and Eq. 9, the exact lines of the ``lines`` dataset);
- ``helpers.workflow``: Snakemake in a scratch work folder (work folder, environment,
  run, planned rules, the end-to-end tests' config);
- ``helpers.runs``: the recipes of the session runs shared by the workflow tests
  (``lines_run``, ``built``); the fixtures themselves are in ``tests/conftest.py``.
"""

from __future__ import annotations

from pathlib import Path

from thermaxis.config import Settings

REPO = Path(__file__).resolve().parents[2]
# The documents whose result blocks `make docs` writes (thermaxis.reports.docblocks).
GUIDES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
# Every stage's settings from an empty config: the schema's defaults, through the config
# loader (the settings dataclasses have no defaults of their own).
DEFAULTS = Settings.from_config({})
