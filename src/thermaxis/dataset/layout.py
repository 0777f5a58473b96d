"""Where a run keeps its measurements and its logs (the raw-data layout of data/README.md).

Either one CSV per measurement in ``<run>/errors/``, or every measurement in one
``<run>/errors.csv`` told apart by its ``measurement`` column. The reader and the
checks that name a run's measurements in their messages both ask here, so a message
never names the layout the run does not use.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["ERRORS_FOLDER", "ERRORS_FILE", "error_source", "log_file"]

ERRORS_FOLDER = "errors"
ERRORS_FILE = "errors.csv"


def error_source(run_folder) -> Path:
    """``<run>/errors.csv`` when the run has one, else ``<run>/errors/`` (the reader refuses a run with both)."""
    run_folder = Path(run_folder)
    one_file = run_folder / ERRORS_FILE
    return one_file if one_file.exists() else run_folder / ERRORS_FOLDER


def log_file(run_folder, source: str, kind: str = "temperatures") -> Path:
    """One source's log in a run, as the checks name it: ``<run>/temperatures/<source>.csv``,
    or with ``kind="signals"`` ``<run>/signals/<source>.csv``."""
    return Path(run_folder) / kind / f"{source}.csv"
