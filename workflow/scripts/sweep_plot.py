"""The sweep's figures from ranking.csv: the n_clusters x algorithm heat map, the factor effects."""

from thermaxis import plotting, sweep
from thermaxis.config import DecouplingSettings, SelectionSettings
from thermaxis.runner import run_script


def _heatmap(snakemake, ranking):
    p = snakemake.params
    selection = SelectionSettings.from_section(p.selection)
    degree = DecouplingSettings.from_section(p.decoupling).degree
    tables = {
        approach: sweep.heatmap_table(ranking, approach, selection, degree)
        for approach in dict.fromkeys(ranking["approach"])
    }
    return plotting.fig_sweep_heatmap(tables)


DRAW = {
    "sweep_heatmap": _heatmap,
    "sweep_factor_effects": lambda snakemake, ranking: plotting.fig_factor_effects(ranking),
}


def main(snakemake):
    ranking = sweep.read_table(snakemake.input.ranking)
    fig = DRAW[snakemake.rule](snakemake, ranking)
    if snakemake.params.simulated:
        plotting.stamp_provenance(fig, plotting.SIMULATED_NOTE)
    plotting.save_figure(fig, snakemake.output.figures, dpi=snakemake.params.dpi)


run_script(main, snakemake)
