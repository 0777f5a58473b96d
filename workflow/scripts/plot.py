"""One family of figures per job: for each figure of the rule's table entries, read its tables, call the function it names, save."""

import pandas as pd

from thermaxis.figures import compensation, captions, paper, predictions, style
from thermaxis.pipeline.runner import run_script

# The figure table names functions as "figures.<module>.<function>".
MODULES = {f"figures.{m.__name__.rsplit('.', 1)[1]}": m for m in (paper, predictions, compensation)}


def _table(path):
    return pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)


def main(snakemake):
    tables = {path: _table(path) for path in snakemake.input.tables}
    for figure in snakemake.params.figures:
        module, name = figure["draw"].rsplit(".", 1)
        draw = getattr(MODULES[module], name)
        fig = draw(**{arg: tables[path] for arg, path in figure["tables"].items()}, **figure["arguments"])
        if snakemake.params.simulated:
            style.stamp_provenance(fig, captions.SIMULATED_NOTE)
        style.save_figure(fig, figure["paths"], dpi=snakemake.params.dpi)


run_script(main, snakemake)
