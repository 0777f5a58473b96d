"""The thermal-drift figure of one held-out run, before and after compensation."""

import pandas as pd

from thermaxis import plotting
from thermaxis.compensation_figures import fig_compensation_drift
from thermaxis.runner import run_script


def main(snakemake):
    fig = fig_compensation_drift(pd.read_csv(snakemake.input.summary), snakemake.wildcards.fold)
    if snakemake.params.simulated:
        plotting.stamp_provenance(fig, plotting.SIMULATED_NOTE)
    plotting.save_figure(fig, snakemake.output.figures, dpi=snakemake.params.dpi)


run_script(main, snakemake)
