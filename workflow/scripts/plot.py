"""One figure per rule: read the rule's tables, call the thermaxis.plotting function its entry names, save."""

import pandas as pd

from thermaxis import plotting
from thermaxis.runner import run_script


def _table(path):
    return pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)


def main(snakemake):
    tables = {name: _table(path) for name, path in snakemake.input.items() if name != "code"}
    draw = getattr(plotting, snakemake.params.draw)
    fig = draw(**tables, **snakemake.params.arguments, **dict(snakemake.wildcards.items()))
    if snakemake.params.simulated:
        plotting.stamp_provenance(fig, plotting.SIMULATED_NOTE)
    plotting.save_figure(fig, snakemake.output.figures, dpi=snakemake.params.dpi)


run_script(main, snakemake)
