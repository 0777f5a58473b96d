"""The sweep's figures from ranking.csv: the n_clusters x algorithm heat map, the factor effects."""

from thermaxis.config import DecouplingSettings, SelectionSettings
from thermaxis.figures import captions, style
from thermaxis.figures import sweep as sweep_figures
from thermaxis.pipeline.runner import run_script
from thermaxis.sweep import run as sweep_run


def _heatmap(snakemake, ranking):
    p = snakemake.params
    selection = SelectionSettings.from_section(p.selection)
    degree = DecouplingSettings.from_section(p.decoupling).degree
    tables = {
        approach: sweep_run.heatmap_table(ranking, approach, selection, degree)
        for approach in dict.fromkeys(ranking["approach"])
    }
    return sweep_figures.fig_sweep_heatmap(tables)


DRAW = {
    "sweep_heatmap": _heatmap,
    "sweep_factor_effects": lambda snakemake, ranking: sweep_figures.fig_factor_effects(ranking),
}


def main(snakemake):
    ranking = sweep_run.read_table(snakemake.input.ranking)
    fig = DRAW[snakemake.rule](snakemake, ranking)
    if snakemake.params.simulated:
        style.stamp_provenance(fig, captions.SIMULATED_NOTE)
    style.save_figure(fig, snakemake.output.figures, dpi=snakemake.params.dpi)


run_script(main, snakemake)
