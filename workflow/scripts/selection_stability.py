"""How often each sensor is chosen when one of a fold's training runs is left out."""

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import DecouplingSettings, SelectionSettings
from thermaxis.pipeline.runner import run_script, write_csv
from thermaxis.statistics import selection_stability


def main(snakemake):
    p = snakemake.params
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors), pd.read_parquet(snakemake.input.temperatures)
    )
    degree = DecouplingSettings.from_section(p.decoupling).degree if p.decoupled else None
    table = selection_stability(
        X, Y, p.folds, SelectionSettings.from_section(p.selection), degree, p.decoupled
    )
    write_csv(table, snakemake.output.table, float_format="%.6f")


run_script(main, snakemake)
