"""One family of figures per job: for each figure of the rule's table entries, read its
tables, call the function it names, save."""

from importlib import import_module

import pandas as pd

from thermaxis.figures import captions, style
from thermaxis.pipeline.runner import run_script


def function(path):
    """The figure table's "<module>.<function>" under thermaxis (as registry.function).

    Resolved here rather than imported with the table, so that a family's code inputs are
    plot.py's imports and its own figures' modules (common.smk, figure_code).
    """
    module, name = path.rsplit(".", 1)
    return getattr(import_module(f"thermaxis.{module}"), name)


def _read(path, reader):
    """A table by its entry's reader, else by its suffix."""
    if reader:
        return function(reader)(path)
    return pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)


def main(snakemake):
    figures = snakemake.params.figures
    readers = {path: f.get("reader") for f in figures for path in f["tables"].values()}
    tables = {path: _read(path, readers.get(path)) for path in snakemake.input.tables}
    for figure in figures:
        draw = function(figure["draw"])
        fig = draw(
            **{arg: tables[path] for arg, path in figure["tables"].items()}, **figure["arguments"]
        )
        if snakemake.params.simulated:
            style.stamp_provenance(fig, captions.SIMULATED_NOTE)
        style.save_figure(fig, figure["paths"], dpi=snakemake.params.dpi)


run_script(main, snakemake)
