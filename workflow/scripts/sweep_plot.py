"""The sweep's figures from ranking.csv: the n_clusters x algorithm heat map, the factor effects."""

from thermaxis import plotting, sweep
from thermaxis.runner import run_script


def _heatmap(snakemake, ranking):
    p = snakemake.params
    tables = {
        approach: sweep.heatmap_table(ranking, approach, p.selection, p.degree)
        for approach in dict.fromkeys(ranking["approach"])
    }
    return sweep.fig_sweep_heatmap(tables)


DRAW = {
    "sweep_heatmap": _heatmap,
    "sweep_factor_effects": lambda snakemake, ranking: sweep.fig_factor_effects(ranking),
}


def main(snakemake):
    ranking = sweep.read_table(snakemake.input.ranking)
    fig = DRAW[snakemake.rule](snakemake, ranking)
    if snakemake.params.simulated:
        plotting.stamp_provenance(fig, plotting.SIMULATED_NOTE)
    plotting.save_figure(fig, snakemake.output.figures, dpi=snakemake.params.dpi)


run_script(main, snakemake)
