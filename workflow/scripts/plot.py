"""One figure per rule: read the rule's tables, call one thermaxis.plotting function, save."""

import pandas as pd

from thermaxis import plotting
from thermaxis.runner import run_script


def _ambient(snakemake):
    frames = []
    for run, path in zip(snakemake.params.runs, snakemake.input.series):
        series = pd.read_parquet(path, columns=["elapsed_min", snakemake.params.sensor])
        frames.append(
            pd.DataFrame(
                {"run": run, "elapsed_min": series["elapsed_min"], "temperature_c": series[snakemake.params.sensor]}
            )
        )
    return plotting.fig3_ambient(pd.concat(frames, ignore_index=True))


def _errors(snakemake):
    return pd.read_parquet(snakemake.input.errors)


DRAW = {
    "fig2_positioning_error": lambda s: plotting.fig2_positioning_error(_errors(s), s.params.run),
    "fig3_ambient": _ambient,
    "fig5_unzeroed": lambda s: plotting.fig5_unzeroed(_errors(s), s.params.run),
    "fig6_error_vs_time": lambda s: plotting.fig6_error_vs_time(_errors(s), s.params.run),
    "fig7_error_surface": lambda s: plotting.fig7_error_surface(_errors(s), s.params.run),
    "fig8_rezeroed": lambda s: plotting.fig8_rezeroed(_errors(s), s.params.run),
    "fig9_other_runs": lambda s: plotting.fig9_other_runs(_errors(s), s.params.runs),
    "fig10_temperature_rise": lambda s: plotting.fig10_temperature_rise(
        pd.read_parquet(s.input.series), signals=pd.read_parquet(s.input.signals), units=s.params.signal_units
    ),
    "fig12_slope_intercept": lambda s: plotting.fig12_slope_intercept(pd.read_csv(s.input.kb)),
    "fig_kb_prediction": lambda s: plotting.fig_kb_prediction(
        pd.read_csv(s.input.kb), s.wildcards.fold, s.wildcards.approach, s.wildcards.algorithm
    ),
    "fig_error_prediction": lambda s: plotting.fig_error_prediction(
        pd.read_csv(s.input.errors), s.wildcards.fold, s.wildcards.approach, s.wildcards.algorithm
    ),
    "fig_fold_comparison": lambda s: plotting.fig_fold_comparison(pd.read_csv(s.input.metrics)),
}


def main(snakemake):
    fig = DRAW[snakemake.rule](snakemake)
    if snakemake.params.simulated:
        plotting.stamp_provenance(fig, plotting.SIMULATED_NOTE)
    plotting.save_figure(fig, snakemake.output.figures, dpi=snakemake.params.dpi)


run_script(main, snakemake)
