"""One family of figures per job: for each figure of the rule's table entries, read its tables, call the function it names, save."""

import pandas as pd

from thermaxis import compensation_figures, plotting
from thermaxis.runner import run_script

MODULES = {"plotting": plotting, "compensation_figures": compensation_figures}


def _table(path):
    return pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)


def main(snakemake):
    tables = {path: _table(path) for path in snakemake.input.tables}
    for figure in snakemake.params.figures:
        module, name = figure["draw"].split(".")
        draw = getattr(MODULES[module], name)
        fig = draw(**{arg: tables[path] for arg, path in figure["tables"].items()}, **figure["arguments"])
        if snakemake.params.simulated:
            plotting.stamp_provenance(fig, plotting.SIMULATED_NOTE)
        plotting.save_figure(fig, figure["paths"], dpi=snakemake.params.dpi)


run_script(main, snakemake)
