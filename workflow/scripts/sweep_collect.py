"""The sweep's tables: every batch's rows (summary.csv), the ranking and the factor effects."""

import pandas as pd

from thermaxis.config import DecouplingSettings, SelectionSettings, StatisticsSettings
from thermaxis.pipeline.runner import run_script, write_csv
from thermaxis.statistics import with_uncertainty
from thermaxis.sweep import run as sweep_run


def main(snakemake):
    p = snakemake.params
    summary = sweep_run.collect_summary(pd.read_parquet(path) for path in snakemake.input.batches)
    degree = DecouplingSettings.from_section(p.decoupling).degree
    ranking = sweep_run.rank_configurations(
        summary, SelectionSettings.from_section(p.selection), degree
    )
    uncertain = with_uncertainty(summary, ranking, StatisticsSettings.from_section(p.statistics))
    write_csv(summary, snakemake.output.summary, float_format="%.6f")
    write_csv(uncertain, snakemake.output.ranking, float_format="%.6f")
    write_csv(sweep_run.factor_effects(ranking), snakemake.output.effects, float_format="%.6f")


run_script(main, snakemake)
