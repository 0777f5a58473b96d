"""Draw one family of the figure table (:mod:`thermaxis.figures.registry`) in one job.

A family's figures are independent: above :data:`MIN_FIGURES_PER_WORKER` figures per
core they are dealt to worker processes (:func:`thermaxis.pipeline.parallel.map_folds`),
each starting Python and matplotlib once for its share. A figure's bytes depend only on
the figure (:func:`thermaxis.figures.style.save_figure`), not on the process drawing it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import partial

from thermaxis.figures.registry import function

__all__ = ["MIN_FIGURES_PER_WORKER", "draw_family", "family_workers"]

# A worker's start (Python, the library, matplotlib: about 2.5 CPU-s) against about
# 0.45 s per figure drawn and saved as PNG and PDF, and a job of two processes holds two
# cores: Snakemake starts it only when both are free, and its scheduler prefers two ready
# one-core jobs to it, while a one-process job runs beside any other. On a 12-run record
# the 72 prediction figures in two processes waited 30 s for both cores; a second process
# pays where the family is most of what is left to do, from 128 figures (the 43-run
# record's 258; docs/performance.md).
MIN_FIGURES_PER_WORKER = 64


def _read(path: str, reader: str | None):
    """A table by its entry's reader, else by its suffix."""
    import pandas as pd

    from thermaxis.tables import read_table

    if reader:
        return function(reader)(path)
    return pd.read_parquet(path) if str(path).endswith(".parquet") else read_table(path)


def _draw(figures: Sequence[Mapping], stamp: str | None, dpi: float | None) -> None:
    """Read the tables ``figures`` need, then draw and save each figure."""
    from thermaxis.figures import style

    readers = {path: f.get("reader") for f in figures for path in f["tables"].values()}
    tables = {path: _read(path, reader) for path, reader in readers.items()}
    for figure in figures:
        fig = function(figure["draw"])(
            **{arg: tables[path] for arg, path in figure["tables"].items()}, **figure["arguments"]
        )
        if stamp:
            style.stamp_provenance(fig, stamp)
        style.save_figure(fig, figure["paths"], dpi=dpi)


def family_workers(cores: int, n_figures: int) -> int:
    """How many processes draw a family of ``n_figures`` on ``cores`` cores."""
    return max(1, min(int(cores), n_figures // MIN_FIGURES_PER_WORKER))


def draw_family(
    figures: Sequence[Mapping], stamp: str | None, dpi: float | None, workers: int = 1
) -> None:
    """Draw every figure of ``figures`` (the workflow's figure specs), in ``workers`` processes.

    ``stamp``: the provenance note stamped on each figure (simulated data), or None.
    """
    from thermaxis.pipeline.parallel import map_folds

    shares = [list(figures[i::workers]) for i in range(workers)]
    map_folds(partial(_draw, stamp=stamp, dpi=dpi), [s for s in shares if s], workers)
